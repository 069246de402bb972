#pragma once
// A window of the scan read as fit pixels (star light positive), and the detections' light in it, for the
// fits at a known place (trail_forced.cpp, dash_in_pixels.cpp).
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/detect/scan_pixels.h"
#include "platemeter/detect/star_detector.h"
#include "star_internal.h"

namespace platemeter::detect_internal {

// The square window of half-size half_px about centre (whole pixels covering it); false when it is not
// inside the scan.
bool WindowAbout(const ScanPixels& scan, const PixelPoint& centre, double half_px, PixelRect* rect);

// The window's pixels, their values as contrast (negated on a negative). A clipped pixel (saturated, or at
// the film's floor) holds light not measured, which a fit would take for less: without `clipped`, false at
// the first; with it, each is left out and listed there. Masked pixels (core/image.h) are left out silently.
bool ReadContrast(const ScanPixels& scan, const PixelRect& rect, std::vector<star_internal::FitPixel>* pixels,
                  std::vector<PixelPoint>* clipped = nullptr);

// Distance from p to a sweep: the segment of length_px along angle_rad about centre.
double ToSweep_px(const PixelPoint& p, const PixelPoint& centre, double angle_rad, double length_px);

// Whether every clipped pixel lies farther than clear_px from the sweep: a saturated neighbour's core that
// near would take the sweep's own light with it.
bool ClearOfClipped(const std::vector<PixelPoint>& clipped, const PixelPoint& centre, double angle_rad,
                    double length_px, double clear_px);

// A detected image as the detector fitted it (a point image is a segment of length 0).
star_internal::FittedSegment ModelOf(const DetectedStar& d);

}  // namespace platemeter::detect_internal
