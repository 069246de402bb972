// The shared least-squares engine of the fiducial mark fits (mark_fit_engine.h).
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "centre_information.h"
#include "mark_fit_engine.h"
#include "median.h"

namespace platemeter::internal {
namespace {

using detect_internal::Median;

// Full parameter vector: x0, y0, shape..., gain, b0, bx, by.
class MarkCost : public ceres::CostFunction {
 public:
  MarkCost(const MarkShapeModel& model, const std::vector<MarkSample>* samples, double xc, double yc, int background_terms)
      : model_(model), samples_(samples), xc_(xc), yc_(yc), nb_(background_terms),
        n_(model.num_shape() + 3 + background_terms) {
    set_num_residuals(static_cast<int>(samples->size()));
    mutable_parameter_block_sizes()->push_back(n_);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* p = parameters[0];
    const size_t count = samples_->size();
    const int ns = n_ - 1 - nb_;  // x0, y0, shape
    const bool want = jacobians && jacobians[0];
    values_.resize(count);
    if (want) derivatives_.resize(count * ns);
    model_.Evaluate(p, *samples_, values_.data(), want ? derivatives_.data() : nullptr);
    const double gain = p[ns];
    const double* b = p + ns + 1;
    for (size_t i = 0; i < count; ++i) {
      const MarkSample& s = (*samples_)[i];
      // Background terms in units of 100 px keep the normal matrix well scaled.
      const double dx = 0.01 * (s.x_px - xc_), dy = 0.01 * (s.y_px - yc_);
      const double terms[6] = {1.0, dx, dy, dx * dx, dx * dy, dy * dy};
      double background = 0.0;
      for (int k = 0; k < nb_; ++k) background += b[k] * terms[k];
      residuals[i] = background + gain * values_[i] - s.value_dn;
      if (!std::isfinite(residuals[i])) return false;
      if (want) {
        double* row = jacobians[0] + i * n_;
        for (int k = 0; k < ns; ++k) row[k] = gain * derivatives_[i * ns + k];
        row[ns] = values_[i];
        for (int k = 0; k < nb_; ++k) row[ns + 1 + k] = terms[k];
      }
    }
    return true;
  }

  // Residuals and full Jacobian at p (for outliers and the covariance).
  void Full(const double* p, std::vector<double>* residuals, Eigen::MatrixXd* jacobian) const {
    residuals->resize(samples_->size());
    double* rows = nullptr;
    if (jacobian) {
      jacobian->resize(static_cast<Eigen::Index>(samples_->size()), n_);
      row_major_.resize(samples_->size() * n_);
      rows = row_major_.data();
    }
    double* jac[1] = {rows};
    const double* params[1] = {p};
    Evaluate(params, residuals->data(), jacobian ? jac : nullptr);
    if (jacobian) {
      for (size_t i = 0; i < samples_->size(); ++i)
        for (int k = 0; k < n_; ++k) (*jacobian)(static_cast<Eigen::Index>(i), k) = row_major_[i * n_ + k];
    }
  }

 private:
  const MarkShapeModel& model_;
  const std::vector<MarkSample>* samples_;
  double xc_, yc_;
  int nb_;
  int n_;
  mutable std::vector<double> values_, derivatives_, row_major_;
};

bool Solve(const MarkShapeModel& model, const std::vector<MarkSample>& samples, double xc, double yc,
           const MarkEngineSettings& settings, bool shape_fixed, std::vector<double>* p, std::string* message) {
  const int ns = model.num_shape() + 2;
  ceres::Problem problem;
  problem.AddResidualBlock(new MarkCost(model, &samples, xc, yc, settings.background_terms), nullptr, p->data());
  auto is_held = [&](int k) { return std::find(settings.held.begin(), settings.held.end(), k) != settings.held.end(); };
  for (int k = 0; k < ns; ++k) {
    if (k >= 2 && (shape_fixed || is_held(k))) continue;
    problem.SetParameterLowerBound(p->data(), k, settings.lower[k]);
    problem.SetParameterUpperBound(p->data(), k, settings.upper[k]);
  }
  std::vector<int> held;
  for (int k = 2; k < ns; ++k)
    if (shape_fixed || is_held(k)) held.push_back(k);
  if (!held.empty()) {
    problem.SetManifold(p->data(), new ceres::SubsetManifold(static_cast<int>(p->size()), held));
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  // The shape-held pass only brings the position near; the full pass converges.
  solver.max_num_iterations = shape_fixed ? std::min(settings.max_iterations, 8) : settings.max_iterations;
  solver.function_tolerance = 1e-11;
  solver.parameter_tolerance = 1e-11;
  solver.gradient_tolerance = 1e-14;
  solver.num_threads = 1;  // marks are fitted in parallel one level up
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  *message = summary.message;
  return summary.IsSolutionUsable();
}

}  // namespace

MarkEngineResult RunMarkFit(const MarkShapeModel& model, std::vector<MarkSample> samples,
                            const MarkEngineSettings& settings) {
  MarkEngineResult result;
  const int ns = model.num_shape() + 2;
  const int n = ns + 1 + settings.background_terms;
  if (static_cast<int>(samples.size()) < 4 * n) {
    result.message = "too few pixels around the mark to fit it";
    return result;
  }
  const double xc = settings.start[0], yc = settings.start[1];
  // Start of gain and background: the background is the median of the pixels
  // the start shape leaves empty, the gain a regression on the shape.
  std::vector<double> p(settings.start);
  p.resize(n, 0.0);
  {
    std::vector<double> shape(samples.size());
    model.Evaluate(p.data(), samples, shape.data(), nullptr);
    std::vector<double> outside;
    for (size_t i = 0; i < samples.size(); ++i)
      if (shape[i] < 0.02) outside.push_back(samples[i].value_dn);
    if (outside.size() < 8) {
      result.message = "no background pixels around the mark";
      return result;
    }
    const double background = Median(outside);
    double num = 0, den = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
      num += shape[i] * (samples[i].value_dn - background);
      den += shape[i] * shape[i];
    }
    if (!(den > 0.0) || num == 0.0) {
      result.message = "no contrast between the mark and the background";
      return result;
    }
    p[ns] = num / den;
    p[ns + 1] = background;
  }

  std::string message;
  bool usable = Solve(model, samples, xc, yc, settings, /*shape_fixed=*/true, &p, &message) &&
                Solve(model, samples, xc, yc, settings, /*shape_fixed=*/false, &p, &message);
  const size_t all_pixels = samples.size();
  std::vector<double> residuals;
  for (int round = 0; usable && round < 2; ++round) {
    MarkCost cost(model, &samples, xc, yc, settings.background_terms);
    cost.Full(p.data(), &residuals, nullptr);
    std::vector<double> abs_residuals(residuals.size());
    for (size_t i = 0; i < residuals.size(); ++i) abs_residuals[i] = std::abs(residuals[i]);
    const double robust_sigma = 1.4826 * Median(abs_residuals);
    const double limit =
        std::max(settings.outlier_threshold * robust_sigma, settings.min_outlier_contrast * std::abs(p[ns]));
    std::vector<MarkSample> kept;
    kept.reserve(samples.size());
    for (size_t i = 0; i < samples.size(); ++i)
      if (abs_residuals[i] <= limit) kept.push_back(samples[i]);
    if (kept.size() == samples.size()) break;
    if (static_cast<int>(kept.size()) < 4 * n) {
      usable = false;
      message = "too many pixels dropped as outliers";
      break;
    }
    samples.swap(kept);
    usable = Solve(model, samples, xc, yc, settings, /*shape_fixed=*/false, &p, &message);
  }
  result.outlier_fraction = 1.0 - static_cast<double>(samples.size()) / static_cast<double>(all_pixels);
  result.params = p;
  result.message = message;
  if (!usable) return result;

  // Formal covariance of the position: the Schur complement on every other free
  // parameter (centre_information.h).
  MarkCost cost(model, &samples, xc, yc, settings.background_terms);
  Eigen::MatrixXd jacobian;
  cost.Full(p.data(), &residuals, &jacobian);
  double rss = 0.0;
  for (double r : residuals) rss += r * r;
  std::vector<int> free_columns;
  for (int k = 0; k < n; ++k)
    if (std::find(settings.held.begin(), settings.held.end(), k) == settings.held.end()) free_columns.push_back(k);
  const Eigen::MatrixXd jacobian_free = jacobian(Eigen::all, free_columns);
  const Eigen::MatrixXd normal = jacobian_free.transpose() * jacobian_free;
  const int n_free = static_cast<int>(free_columns.size());
  const int dof = static_cast<int>(samples.size()) - n_free;
  const double sigma0_sq = rss / std::max(dof, 1);
  const Eigen::Matrix2d schur = CentreInformation(normal, settings.pinv_tolerance);
  const Eigen::Matrix2d covariance = sigma0_sq * schur.inverse();
  result.converged = std::isfinite(covariance(0, 0)) && std::isfinite(covariance(1, 1));
  result.cov_xx = covariance(0, 0);
  result.cov_xy = covariance(0, 1);
  result.cov_yy = covariance(1, 1);
  result.sigma0_dn = std::sqrt(sigma0_sq);
  result.pixels_used = static_cast<int>(samples.size());
  return result;
}

}  // namespace platemeter::internal
