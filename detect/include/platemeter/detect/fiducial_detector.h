#pragma once
// Finds a camera's fiducial marks in a scan, with their table ids:
// - with a prior plate-to-pixel map (from the reseau detection), each mark is
//   predicted, searched for by normalized correlation with its template in a
//   window around the prediction (either polarity), and fitted there on the
//   scan's own pixels (fiducial_fit.h; crosses by FitCross);
// - without one (a camera with no reseau), the marks are found on their own:
//   template correlation on an overview (overview.h) for each mark type (format
//   corners: one template per L direction), then a robust fit of the layout
//   (similarity over the 8 scan orientations and the plausible scale range,
//   from pairs of candidates), then the same search and fit at every predicted
//   mark. Layouts that look the same in several orientations (format corners
//   of a square or rectangular format, point-symmetric fiducial sets) are
//   separated by the chi-square of the fitted marks against each orientation's
//   similarity; if that is not decisive the result says so (ids not trustworthy)
//   and takes the first of the tied orientations in ScanOrientation::All()
//   order ("0" first), or the given options.orientation.
// Format-corner cameras (CameraDefinition::format_corners_as_fiducials) get the
// marks UL, UR, LL, LR at the format's corners, drawn as an L whose arms run
// inward along the format edges; the position is the corner point where the
// arms' centre lines meet.
// Statuses as the reseau detector: measured; rejected (low_contrast, defect,
// poor_fit); missing (outside_scan, not_found). A rejected mark carries its
// fitted position and sigmas (or, if the fit failed, the search's position with
// zero sigmas); a missing mark carries its predicted position with zero
// sigmas: never a measurement.
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/detect/fiducial_fit.h"
#include "platemeter/detect/grid_assignment.h"
#include "platemeter/detect/point.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

struct FiducialDetectorOptions {
  double pixel_size_um = 0.0;  // um; nominal scan pixel size (required without a prior; with one, taken from it)
  std::optional<ScanOrientation> orientation;  // known orientation (no prior): only this one is tried
  double scale_tolerance = 0.05;     // relative; scan scale against nominal (no prior)
  double max_rotation_deg = 5.0;     // deg; scanner rotation beyond the 90-degree steps (no prior)
  double search_radius_mm = 1.0;     // mm; around each predicted mark
  double match_radius_mm = 0.5;      // mm; a coarse candidate matches a predicted mark within this (no prior)
  double min_search_score = 0.5;     // |normalized correlation| below this: the mark is not there (missing, not_found)
  double min_contrast_snr = 8.0;     // |contrast| / residual sigma below this: rejected, low_contrast
  double blur_sigma_px = 0.7;        // px; expected scanner blur (templates, fit start)
  double corner_line_width_um = 100.0;   // um; format-corner L line width (the simulator's default)
  double corner_arm_length_um = 3000.0;  // um; format-corner L arm length from the corner point
  double layout_sigma_floor_px = 0.3;    // px; added in quadrature to the formal sigmas when orientations are compared
  double orientation_min_excess_chi2 = 25.0;  // the runner-up orientation's chi2 must exceed the best's by this
  int candidates_per_template = 200; // strongest coarse candidates kept per template (no prior; reseau crosses may look alike)
  MarkFitOptions fit;
  bool Check(std::string* why) const;
};

struct FiducialDetection {
  std::vector<DetectedPoint> points;  // the set's marks in table order, then UL, UR, LL, LR for format corners
  std::vector<MarkFitResult> fits;    // the same order (unfitted: converged = false)
  bool found = false;                 // false: no prior and the layout could not be placed
  bool used_prior = false;
  ScanOrientation orientation;        // no prior: the layout's; with a prior: read from it
  bool orientation_ambiguous = false; // several orientations fit equally well: ids are not trustworthy
  std::string orientation_evidence;
  PlateToPixel plate_to_pixel;        // the prior, or the layout's similarity
  int candidates = 0;                 // coarse candidates (no prior)
  int measured = 0, rejected = 0, missing = 0;
  long masked_px = 0;                 // no prior: masked pixels in the whole scan (image.h); with one, 0 (not counted)
  std::string summary;
};

// The marks the camera has: `set` (may be nullptr) plus the format corners if
// the camera uses them. `prior` maps plate mm (the definitions' frame) to scan
// pixels; nullptr: search the whole scan. Throws Error for invalid options or
// a camera without any fiducial.
FiducialDetection DetectFiducialMarks(const Image& image, const CameraDefinition& camera, const FiducialSet* set,
                                      const PlateToPixel* prior, const FiducialDetectorOptions& options);

// The points only (kind fiducial, ids from the table or UL/UR/LL/LR).
std::vector<DetectedPoint> DetectFiducials(const Image& image, const CameraDefinition& camera, const FiducialSet* set,
                                           const PlateToPixel* prior, const FiducialDetectorOptions& options);

}  // namespace platemeter
