#pragma once
// Marked passpoints (dots or rings drawn or pricked on the plate) found and
// measured on a scan (docs/passpoints.md):
// - with an approximate list (ids and positions as an operator clicks them),
//   each entry is searched in a window of options.search_radius around its
//   position by normalized correlation with the mark's template, and the
//   strongest candidates are fitted with the dot/ring model of fiducial_fit.h
//   on the scan's own pixels; the entry keeps the user's id;
// - without a list, the whole scan is searched tile by tile (bounded memory:
//   one tile, block-averaged so the mark is about 12 px across, at a time per
//   thread), every correlation peak is fitted at full resolution, and only
//   fits of the right shape, size and polarity are passpoints. They are
//   numbered P1, P2, ... in row-major order of their fitted positions
//   (increasing y_px, ties by increasing x_px).
// A peak that correlates better with the other shape of the same diameter
// (a filled disk for rings, a ring for dots) is not the mark and not fitted.
// Positions near crosses and fiducials (options.mask) are never passpoints.
// Statuses: measured; rejected (low_contrast, poor_fit, defect, ambiguous),
// carrying the fitted position and sigmas (or the search's position with zero
// sigmas if the fit failed); missing (outside_scan, not_found) carrying the
// listed position with zero sigmas: never a measurement.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/detect/fiducial_fit.h"
#include "platemeter/detect/point.h"

namespace platemeter {

// One entry of an approximate list: the user's id and where the mark roughly is.
struct ApproximatePasspoint {
  std::string id;
  PixelPoint position_px;
};

// Reads the approximate-list CSV (docs/passpoints.md): a header `id,x_px,y_px`,
// then one row per passpoint; blank lines and lines starting with '#' are
// skipped. Throws Error(path, "line N: ...") for an unreadable file, a wrong
// header, a malformed or duplicate row, or a list without entries.
std::vector<ApproximatePasspoint> ReadPasspointList(const std::string& path);
// The same on text already read; `origin` names it in errors.
std::vector<ApproximatePasspoint> ParsePasspointList(const std::string& text, const std::string& origin);

// A region where no passpoint can be: every position within radius_px of the
// segment a-b (a == b: a disk). Crosses and corner marks are two segments.
struct PasspointMask {
  PixelPoint a_px, b_px;
  double radius_px = 0.0;
};

struct PasspointDetectorOptions {
  MarkType shape = MarkType::kRing;    // kDot or kRing
  double diameter_px = 0.0;            // px; outer diameter of the mark on the scan (required)
  double line_width_px = 0.0;          // px; ring line width (rings only, required for them)
  bool dark = true;                    // the mark is darker than its surroundings
  double blur_sigma_px = 0.7;          // px; expected scanner blur (template, fit start)
  // List mode: the search window around each listed position, in scan pixels.
  double search_radius_px = 0.0;       // px; a listed position within this of the mark's centre finds it
                                       // (0: twice diameter_px, e.g. 500 um for a 250 um ring)
  double min_search_score = 0.5;       // automatic mode: normalized correlation (0..1) below this: no mark there
  double min_list_score = 0.3;         // list mode: the same near a listed position (the user says a mark is
                                       // there; weaker peaks are fitted and judged, e.g. low_contrast)
  double min_contrast_snr = 8.0;       // |fitted contrast| / residual sigma below this: rejected, low_contrast
  double size_tolerance = 0.2;         // relative; |fitted diameter / diameter_px - 1| above this: not this mark
  double line_width_tolerance = 0.4;   // relative; ring width off by more than this (and 0.75 px): not this mark
  double max_blur_sigma_px = 0.0;      // px; fitted blur above this: not a sharp mark (0: a third of the line
                                       // width for rings, a sixth of the diameter for dots, at least 1.5 px)
  std::vector<PasspointMask> mask;     // candidates whose centre falls here are ignored (crosses, fiducials)
  // Automatic mode: tiling.
  long tile_px = 2048;                 // px; side of a full-resolution tile (plus an overlap of one template)
  int max_candidates_per_tile = 2000;  // strongest correlation peaks fitted per tile
  MarkFitOptions fit;
  bool Check(std::string* why) const;
};

struct PasspointPoint {
  DetectedPoint point;               // kind passpoint; id from the list or P1, P2, ...
  MarkFitResult fit;                 // converged = false: not fitted
  std::optional<PixelPoint> listed_px;  // list mode: the user's position
  double search_score = 0.0;         // normalized correlation of the search peak (0 if none)
  std::vector<std::string> flags;    // clipped (fit window cut by the scan edge), outliers (pixels dropped)
};

struct PasspointDetection {
  bool from_list = false;
  std::vector<PasspointPoint> points;  // list order, or P1, P2, ... in row-major order
  int candidates = 0;                  // correlation peaks examined (automatic mode) or per-entry peaks (list)
  int masked = 0;                      // peaks dropped by the mask
  int not_passpoints = 0;              // automatic mode: peaks that are not this mark, by reason in
  std::map<std::string, int> not_passpoint_reasons;  // look_alike (correlates better with the other shape),
                                       // not_converged, polarity, off_start, size, line_width, blur
  int measured = 0, rejected = 0, missing = 0;
  int tiles = 0;                       // automatic mode
  int overview_factor = 1;             // block averaging of the search (1: full resolution)
  std::string summary;
};

// Throws Error for invalid options. `list`: nullptr for automatic mode.
PasspointDetection DetectPasspoints(const Image& image, const PasspointDetectorOptions& options,
                                    const std::vector<ApproximatePasspoint>* list = nullptr);

}  // namespace platemeter
