#pragma once
// A decoded trail's dots the detector missed, measured where the trail's track
// puts them (docs/trails.md, "Dots measured at their track's prediction").
// The detector's threshold (4 sigma of the background mesh, whose clipped sigma
// a crowded cell overstates) drops faint 0.6-1.2 s dots; once a trail is
// decoded, each of its dots' place and time is known to a few hundredths of a
// pixel, so the question is no longer "is there a star" but "is this dot
// there": a PSF swept along the track (its length the exposure's duration x
// the track's speed) is fitted at the prediction, its centre and flux free,
// and taken only when it is significant, where the track puts it and as
// bright as the trail's other images say it must be. What is near another
// image (detected or predicted) is not measured: its light is not the dot's
// alone.
#include <string>
#include <vector>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/pixel.h"
#include "platemeter/detect/scan_pixels.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/detect/trail_linker.h"

namespace platemeter {

struct ForcedDotOptions {
  bool enabled = true;
  double min_snr = 5.0;            // fitted flux / its sigma at least this
  double max_offset_px = 0.5;      // px; the fitted centre within this of the track's prediction, and
  double max_offset_sigma = 4.0;   // within this many sigmas (the fit's and the prediction's, radial)
  double flux_tolerance = 0.3;     // fraction; the flux within this (plus 3 sigma) of the trail's flux per
                                   // second x the exposure's duration
  double isolation_fwhm = 2.0;     // no other image (detected, or another trail's predicted dot) within this
                                   // many FWHM of the dot's sweep
  double window_fwhm = 2.5;        // px of the fit window beyond the sweep, in FWHM
  double max_extrapolation_s = 250.0;   // s; dots beyond the trail's first or last measured image up to this
  double max_prediction_sigma_px = 0.15;  // px; where the track's prediction there is this sure (radial sigma)
  int min_trail_images = 8;
  bool remeasure = true;           // a detection the linker left unassigned (not contested) alone at the place,
  double remeasure_radius_px = 1.0;  // px; within this of the prediction, is fitted there as the dot (replaces)        // a trail's track is used with at least this many measured images
  bool Check(std::string* why) const;
};

// One dot measured at its track's prediction: the image (kind star, measured, length_px the sweep's
// fixed length) and its tag (assigned, forced, refined_px its measured position).
struct ForcedDot {
  DetectedStar image;
  TrailImage tag;
  int replaces = -1;  // the detection (index into the images) re-measured as this dot (remeasure), -1: none
};

// What became of the dots tried (each counted once, at the first test it failed).
struct ForcedDotStats {
  long tried = 0;      // dot exposures without an image within a trail's reach (MeasureMissingDots)
  long outside = 0;    // off the scan or the exposed format (with the fit window)
  long crowded = 0;    // another image, or another trail's predicted dot, within isolation_fwhm
  long clipped = 0;    // a clipped (saturated) pixel within window_fwhm FWHM of the dot's sweep
  long failed = 0;     // the fit did not converge
  long faint = 0;      // below min_snr
  long off_place = 0;  // the fitted centre off the prediction
  long off_flux = 0;   // the flux off the trail's
  long measured = 0;
};

// Every decoded trail's (a track of its own, at least min_trail_images measured images) dot exposures
// without an image, between its first and last measured image (or beyond, within max_extrapolation_s
// and max_prediction_sigma_px), fitted at the track's prediction.
// `images` and `linked` are LinkTrails' input and output with this `program` and `trail_options`
// (the scan's area and exposed format: dots outside are not measured). Throws Error for invalid options.
std::vector<ForcedDot> MeasureMissingDots(const ScanPixels& scan, const std::vector<DetectedStar>& images,
                                          const TrailLinkResult& linked, const DutyCycleScheduleOptions& program,
                                          const TrailOptions& trail_options, const ForcedDotOptions& options = {},
                                          ForcedDotStats* stats = nullptr);

}  // namespace platemeter
