#pragma once
// The fiducial interior orientation (docs/measure.md): the measured fiducials
// (comparator mm after the earlier steps) fitted to their calibrated camera
// coordinates with FitReseau's models (similarity or affine), weighted by
// their covariances, robust by leave-one-out; then every point mapped into
// camera coordinates with the point's covariance and the transform's
// parameter covariance propagated.
#include <string>
#include <vector>

#include "platemeter/grids/definitions.h"
#include "platemeter/measure/corrections.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/reseau_fit.h"

namespace platemeter {

// A fiducial's calibrated camera position.
struct CalibratedFiducial {
  std::string id;
  double x_mm = 0.0, y_mm = 0.0;  // mm; camera frame
};

// The camera's fiducial set's table, plus the format corners UL, UR, LL, LR at
// (+-w/2, +-h/2) when the camera uses them. `set` may be null (no table).
std::vector<CalibratedFiducial> CalibratedFiducials(const CameraDefinition& camera, const FiducialSet* set);

struct FiducialOrientationOptions {
  ReseauFitModel model = ReseauFitModel::kAffine;  // similarity or affine
  double rejection_threshold = 4.0;  // a fiducial whose leave-one-out discrepancy / its sigma exceeds this is rejected
  int max_rejected = 1;              // at most this many fiducials rejected
  double min_sigma_mm = 1e-5;        // mm; floor of a fiducial's sigma
  bool Check(std::string* why) const;
};

struct FiducialOrientation {
  ReseauFit fit;  // camera mm -> measured mm, over the used fiducials (fit.is_rejected per observation)
  std::vector<ReseauObservation> observations;  // grid_x/y_mm = calibrated camera position
  // Per observation: the leave-one-out discrepancy (measured - predicted by
  // the others) over its sigma (Mahalanobis, 2 dof); 0 without redundancy.
  std::vector<double> leave_one_out;

  // F^-1(m) with cov = J_m C J_m^T + J_p C_p J_p^T (point + parameters).
  PlanePoint ToCamera(const PlanePoint& measured) const;
  // Observation i's camera position: F^-1 of its measurement; for a used
  // fiducial the covariance is that of its residual (it shares its error with
  // the parameters), J_m (C_i - A_i C_p A_i^T) J_m^T.
  PlanePoint FiducialToCamera(size_t i) const;
  // The header line "fiducial_orientation" with the model, parameters, sigmas, counts.
  AppliedCorrection Record(const std::string& source) const;  // source (no spaces): e.g. "sn004-terrain-fiducials", "format_corners"
};

// Throws Error("fiducial orientation", reason) for a model other than
// similarity/affine or with fewer fiducials than the model needs.
FiducialOrientation FitFiducialOrientation(const std::vector<ReseauObservation>& observations,
                                           const FiducialOrientationOptions& options);

// Fits the fiducial rows of `file` (kind fiducial, matched by id to
// `calibrated`) at `positions` (one per row of file->points, in the frame the
// earlier steps left them; rows with has_position false are skipped) and
// replaces every position by its camera coordinates; rejected fiducials get
// the flag "fiducial_orientation:rejected". The caller writes the mm columns
// and the header line (Record).
FiducialOrientation ApplyFiducialOrientation(MeasurementFile* file, std::vector<PlanePoint>* positions,
                                             const std::vector<bool>& has_position,
                                             const std::vector<CalibratedFiducial>& calibrated,
                                             const FiducialOrientationOptions& options);

}  // namespace platemeter
