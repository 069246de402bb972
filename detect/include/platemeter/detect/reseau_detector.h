#pragma once
// Finds every reseau cross of a master grid in a scan, with its master-table id:
//   1. coarse: cross candidates on a reduced overview (both polarities);
//   2. assignment: robust fit of the whole grid to the candidates over the 8
//      orientations (grid_assignment.h);
//   3. refinement: least-squares cross model on the scan's own pixels for every
//      grid point, at its candidate or, for a miss, at its predicted position
//      (a second search), giving position and formal sigma (cross_fit.h);
//      crosses whose pixels cannot pin their shape (faint ones) fitted again
//      with the plate's own cross shape held;
//   4. checks: matched-filter SNR, fit quality, defects, and each cross against the
//      residual field of its neighbours; a status and reason per cross.
// Orientations that the grid's layout cannot tell apart (a regular square grid)
// are separated by the grid's calibrated deviations from regularity, measured
// against a smooth polynomial; if that is not decisive, the result says so.
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/detect/cross_candidates.h"
#include "platemeter/detect/cross_fit.h"
#include "platemeter/detect/grid_assignment.h"
#include "platemeter/detect/point.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

struct ReseauDetectorOptions {
  double pixel_size_um = 0.0;                  // um; the scan's pixel size (required)
  std::optional<ScanOrientation> orientation;  // known orientation (skips the search over 8)
  double min_matched_filter_snr = 8.0;  // |cross contrast| / its sigma (cross_fit.h: gain_sigma_dn) below this: missing, low_contrast
  double max_shift_fraction = 0.25;     // a fit that moves further than this share of the grid spacing from its start: rejected, poor_fit
  double neighbour_outlier_sigma = 5.0; // deviation from the neighbours' residual field, in combined sigmas: rejected, outlier
  double orientation_min_excess_chi2 = 25.0;  // the runner-up orientation's chi2 must exceed the best's by this (scaled) to decide
  GridAssignmentOptions assignment;     // pixel_size_um and orientation are filled from the fields above
  CrossCandidateOptions candidates;     // line width and arm length are filled from the grid's mark
  CrossFitOptions fit;
  bool Check(std::string* why) const;
};

struct ReseauDetection {
  std::vector<DetectedPoint> points;  // one per grid point, in the grid's order
  std::vector<CrossFitResult> fits;   // the same order (diagnostics; unfitted points have converged = false)
  bool found = false;                 // false: the grid could not be placed at all (see summary)
  ScanOrientation orientation;
  bool orientation_ambiguous = false; // several orientations fit equally well: ids are not trustworthy
  std::string orientation_evidence;   // what decided it, in words
  int polarity = -1;                  // -1 dark crosses, +1 bright
  PlateToPixel plate_to_pixel;        // similarity from the assignment
  int candidates = 0;                 // coarse candidates found
  int overview_factor = 1;
  int measured = 0, rejected = 0, missing = 0;
  long masked_px = 0;                 // masked pixels in the whole scan (image.h: no value, not used)
  double seconds_overview = 0, seconds_candidates = 0, seconds_assignment = 0, seconds_refinement = 0;
  std::string summary;
};

ReseauDetection DetectReseau(const Image& image, const MasterGrid& grid, const ReseauDetectorOptions& options);

}  // namespace platemeter
