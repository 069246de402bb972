#pragma once
// Gives every cross candidate its master-table id: a robust fit of the whole
// master grid to the candidates over the 8 scan orientations (0/90/180/270,
// mirrored or not) and the plausible scale range. One-point hypotheses (this
// candidate is that grid point) with the lattice's rotation and scale measured
// from the candidates themselves are scored by how many grid points they put on
// a candidate, then refined by least squares; no chaining from cross to cross.
//
// A regular square grid looks the same in several orientations; those
// hypotheses tie here and are all returned, so that a later stage can separate
// them with finer evidence (the grid's calibrated deviations, fiducials, or the
// user's word).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/scan_orientation.h"
#include "platemeter/detect/cross_candidates.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

// pixel = A * plate_mm + t, A = scale * R(rotation) * O(orientation) with the y flip of pixel rows.
struct PlateToPixel {
  double a[4] = {1, 0, 0, -1};  // row-major 2x2, px per mm
  double t[2] = {0, 0};         // px
  PixelPoint Apply(double x_mm, double y_mm) const {
    return {a[0] * x_mm + a[1] * y_mm + t[0], a[2] * x_mm + a[3] * y_mm + t[1]};
  }
};

struct GridAssignmentOptions {
  double pixel_size_um = 0.0;      // um; nominal scan pixel size (required)
  double scale_tolerance = 0.05;   // relative; the scan scale may differ from nominal by this much
  double max_rotation_deg = 10.0;  // deg; scanner rotation beyond the 90-degree steps
  double match_fraction = 0.15;    // a candidate matches a prediction within this share of the grid spacing
  double tie_fraction = 0.9;       // hypotheses with at least this share of the best match count are kept as ties
  std::optional<ScanOrientation> orientation;  // known orientation: only this one is tried
  int hypothesis_candidates = 40;  // the strongest candidates that seed one-point hypotheses
  bool Check(std::string* why) const;
};

struct GridHypothesis {
  ScanOrientation orientation;
  int polarity = -1;               // -1 dark crosses, +1 bright crosses
  PlateToPixel plate_to_pixel;     // least-squares similarity on the matched pairs
  std::vector<int> candidate_of_point;  // per grid point: index into the candidates, or -1
  int matched = 0;
  double rms_px = 0.0;             // of the matched pairs about the similarity
};

struct GridAssignment {
  bool found = false;
  std::vector<GridHypothesis> hypotheses;  // best first; ties (symmetric grids) follow it
  double lattice_rotation_deg = 0.0;       // measured from the candidates (mod 90)
  double lattice_scale_px_per_mm = 0.0;
  std::string summary;
};

GridAssignment AssignGrid(const std::vector<CrossCandidate>& candidates, const MasterGrid& grid,
                          const GridAssignmentOptions& options);

}  // namespace platemeter
