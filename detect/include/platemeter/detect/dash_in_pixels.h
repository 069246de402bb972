#pragma once
// Whether the pixels show a trail's dash where the plate's flow puts it (docs/trails.md, "The plate's
// flow" 5). A lone trail is numbered by counting its leading run's dashes back from the last one; in a
// crowd a dash often merges with a neighbour into one detection whose centre, length and flux are no
// dash's, and the detections alone cannot say whether the dash is there. The pixels can: the dash's place,
// direction, length and flux are known, so its light is fitted in three pieces (the sweep's thirds, each a
// PSF swept along a third of it), with a constant background and the light of every other detection in
// the window (each its fitted shape, its flux free). A dash shows in all three thirds with about a third
// of its flux each; another star's point image at the place fills one or two of them, another star's
// dash (its direction is the same) fills all three only where it lies on the same track within a third of
// a dash -- not where it is merely near. A place where the thirds hold next to nothing is empty.
#include <array>
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/detect/scan_pixels.h"
#include "platemeter/detect/star_detector.h"

namespace platemeter {

// A dash where the flow puts it.
struct DashPlace {
  PixelPoint centre_px;        // the sweep's centre (mid-exposure)
  double angle_rad = 0.0;      // the sweep's direction
  double length_px = 0.0;      // the sweep's length (exposure x speed)
  double fwhm_px = 0.0;        // the PSF's
  double flux_dn = 0.0;        // the star's dash flux (its flux per second x the dash's duration)
  double tolerance_px = 0.0;   // how far the true sweep may lie from this one (the flow's prediction error)
};

struct DashInPixelsOptions {
  double window_fwhm = 2.5;          // the fit's window: the sweep plus this many FWHM about it
  double on_sweep_fwhm = 1.0;        // a detection centred within this many FWHM of the sweep is not modelled:
                                     // its light is what is asked about (a dash merged with a neighbour), if
                                     // it may be such a merge (MayHoldDash in dash_in_pixels.cpp)
  double min_third = 0.5;            // each third's flux at least this x a third of the dash's flux,
  double max_third = 3.0;            // and at most this x (a merged neighbour adds light; a bright star's
                                     // image is no dash)
  double max_third_sigma = 0.35;     // each third's flux sigma at most this x a third of the dash's flux (the
                                     // thirds told apart: a dash a few FWHM long is not)
  double clear_of_clipped_fwhm = 2.0;  // no clipped pixel within this many FWHM of the sweep (others are
                                       // left out of the fit)
  double max_absent = 0.25;          // absent: every third's flux within +-this x a third of the dash's flux
                                     // (a dash half off its predicted place fills some of them),
  double max_overlap_absent = 0.3;   // and no detection modelled whose light overlaps the dash's this much
                                     // (cosine of their models): its fitted flux could hold the dash's
};

struct DashInPixels {
  bool measured = false;                 // inside the scan, no clipped pixel near the sweep, the thirds told
                                         // apart (each third's sigma within max_third_sigma)
  std::array<double, 3> third_flux_dn{};   // along the sweep's direction
  std::array<double, 3> third_sigma_dn{};  // from the residuals' noise (their median absolute value)
  int modelled = 0;                      // other detections whose light was fitted
  double max_overlap = 0.0;              // the largest cosine between one's model and the dash's
  bool shown = false;                    // measured, every third within its bounds
  bool absent = false;                   // measured, every third within max_absent of none
};

// The thirds of `dash` fitted jointly with the light of `images` whose centre lies off its sweep (the
// caller passes those whose light may reach the window: every one is checked).
DashInPixels MeasureDashInPixels(const ScanPixels& scan, const DashPlace& dash, const std::vector<DetectedStar>& images,
                                 const DashInPixelsOptions& options = {});

// Whether a clipped pixel (a saturated core) lies on the dash's sweep -- within a FWHM of it, in the sweep's
// half away from `own` (the star's neighbouring dash, whose own saturated core may reach across the 10 s gap
// into the near half; nullptr: the whole sweep): a saturated image there may hold the dash, and neither the
// detector nor the thirds see into it. Outside the scan: false.
bool ClippedOnSweep(const ScanPixels& scan, const DashPlace& dash, const DetectedStar* own);

}  // namespace platemeter
