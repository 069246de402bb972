#pragma once
// The least-squares machinery shared by the fiducial mark fits (dot, ring,
// corner): a unit-gain shape S(pixel; x0, y0, shape...) on a planar background,
//   I = b0 + bx (x - xc) + by (y - yc) [+ quadratic terms] + g * S,
// solved with Ceres (first with the shape held, then free), pixels that do not
// belong to a clean mark dropped, and the formal covariance of (x0, y0) as the
// Schur complement of the normal matrix on every other parameter, scaled by the
// fit's own residual variance.
#include <string>
#include <vector>

namespace platemeter::internal {

struct MarkSample {
  double x_px;
  double y_px;
  double value_dn;
};

// A mark shape: parameters x0, y0 then num_shape() shape parameters.
class MarkShapeModel {
 public:
  virtual ~MarkShapeModel() = default;
  virtual int num_shape() const = 0;
  // Unit-gain shape values at every sample and, if derivatives != nullptr, the
  // row-major derivatives with respect to (x0, y0, shape...) (2 + num_shape() per sample).
  virtual void Evaluate(const double* params, const std::vector<MarkSample>& samples, double* values,
                        double* derivatives) const = 0;
};

struct MarkEngineSettings {
  std::vector<double> start;         // x0, y0, shape...
  std::vector<double> lower, upper;  // bounds of the same parameters
  int background_terms = 3;          // 3: plane; 6: quadratic (long windows over a varying background)
  std::vector<int> held;             // shape parameters held at their start (known), not in the covariance
  double outlier_threshold = 4.0;
  double min_outlier_contrast = 0.05;
  int max_iterations = 50;
  double pinv_tolerance = 1e-10;
};

struct MarkEngineResult {
  bool converged = false;
  std::vector<double> params;  // x0, y0, shape..., then gain, background terms (b0 first)
  double cov_xx = 0, cov_xy = 0, cov_yy = 0;  // formal, scaled by sigma0^2
  double sigma0_dn = 0.0;
  double outlier_fraction = 0.0;
  int pixels_used = 0;
  std::string message;
};

MarkEngineResult RunMarkFit(const MarkShapeModel& model, std::vector<MarkSample> samples,
                            const MarkEngineSettings& settings);

}  // namespace platemeter::internal
