#pragma once
// The fit of the measured reseau to the master grid (docs/measure.md). The
// model maps master-grid mm g to measured (comparator, corrected) mm m:
//   similarity:  m = t + s R(theta) g
//   affine:      m = t + [a b; c d] g
//   scales:      m = t + diag(sx, sy) K(eps) R(theta) g,  K = [1 tan eps; 0 1/cos eps]
//                (seed 001's separate x/y scales C_x, C_y and non-orthogonality eps)
//   projective:  m = ([a b; c d] g + t) / (1 + h1 gx + h2 gy)
// fitted by weighted least squares (Ceres) with each cross whitened by its
// measured covariance; robust rejection drops the worst cross while its
// normalized residual exceeds the threshold. Corrected positions are
// g = F^-1(m) with cov_g = J cov_m J^T, J = (dF/dg)^-1.
#include <string>
#include <vector>

#include "platemeter/measure/corrections.h"

namespace platemeter {

enum class ReseauFitModel { kSimilarity, kAffine, kScales, kProjective };
const char* ReseauFitModelName(ReseauFitModel model);  // similarity, affine, scales, projective
bool ParseReseauFitModel(const std::string& name, ReseauFitModel* model);

struct ReseauFitOptions {
  ReseauFitModel model = ReseauFitModel::kScales;
  double rejection_threshold = 4.0;    // a cross whose |residual| / (sigma0 * its sigma) exceeds this is rejected
  int max_rejected = 1000;             // at most this many crosses rejected
  double min_sigma_mm = 1e-5;          // mm; floor of a cross's sigma (zero sigmas would weigh infinitely)
  bool scale_by_variance_factor = true;  // multiply the covariance by max(1, sigma0^2)
  bool Check(std::string* why) const;
};

struct ReseauObservation {
  std::string id;
  double grid_x_mm = 0.0, grid_y_mm = 0.0;  // mm; master grid
  PlanePoint measured;                       // mm; comparator frame after the earlier corrections
};

// A derived quantity with its standard deviation.
struct ValueSigma {
  double value = 0.0;
  double sigma = 0.0;
};

struct ReseauFit {
  ReseauFitModel model = ReseauFitModel::kScales;
  double parameters[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // tx, ty (mm), then the model's (see ParameterNames)
  double covariance[64] = {};                        // 8x8 row-major (zeros for unused parameters)
  int parameter_count = 0;
  double sigma0 = 1.0;        // sqrt(chi2 / (2 n - parameter_count)) of the used crosses
  double rms_mm = 0.0;        // RMS of the used crosses' residuals (grid frame, per axis combined)
  int used = 0, rejected = 0;
  // Per observation (same order as given): rejected by the robust loop, and
  // the residual in the grid frame: grid - F^-1(measured) (mm).
  std::vector<bool> is_rejected;
  std::vector<double> residual_x_mm, residual_y_mm;
  // Linear part decomposed as diag(sx, sy) K(eps) R(theta) (for every model;
  // the projective's at the grid origin), with sigmas from the covariance.
  ValueSigma scale_x, scale_y, non_orthogonality_rad, rotation_rad;
  ValueSigma mean_scale;  // (scale_x + scale_y) / 2: the scale against the calibrated grid

  std::vector<std::string> ParameterNames() const;
  // F(g) in measured mm.
  void Forward(double gx, double gy, double* mx, double* my) const;
  // F^-1 with the covariance propagated.
  PlanePoint ToGrid(const PlanePoint& measured) const;
};

// Throws Error("reseau fit", reason) with fewer crosses than the model needs.
ReseauFit FitReseau(const std::vector<ReseauObservation>& observations, const ReseauFitOptions& options);

// Decomposes a row-major 2x2 matrix as diag(sx, sy) K(eps) R(theta):
// out = {sx, sy, eps_rad, theta_rad}.
void DecomposeScalesNonOrthogonality(const double a[4], double out[4]);

}  // namespace platemeter
