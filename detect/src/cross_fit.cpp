#include "platemeter/detect/cross_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "bar_profile.h"
#include "median.h"

namespace platemeter {
namespace {

using detect_internal::Median;

using internal::BarProfile;
using internal::EvaluateBarProfile;

// Parameter order of the cross model (see cross_fit.h).
enum Param { kX0, kY0, kTheta, kWidthH, kWidthV, kLength, kSigma, kGain, kB0, kBx, kBy, kNumParams };

struct Sample {
  double x_px;
  double y_px;
  double value_dn;
};

// Model value at one pixel and, if gradient != nullptr, its derivatives.
double CrossModel(const double* p, double xc, double yc, const Sample& s, double* gradient) {
  const double c = std::cos(p[kTheta]), sn = std::sin(p[kTheta]);
  const double dx = s.x_px - p[kX0], dy = s.y_px - p[kY0];
  const double u = c * dx + sn * dy;
  const double v = -sn * dx + c * dy;
  const BarProfile a = EvaluateBarProfile(v, p[kWidthH], p[kSigma]);   // across the bar along u
  const BarProfile b = EvaluateBarProfile(u, p[kWidthV], p[kSigma]);   // across the bar along v
  const BarProfile eu = EvaluateBarProfile(u, p[kLength], p[kSigma]);  // along the bar along u
  const BarProfile ev = EvaluateBarProfile(v, p[kLength], p[kSigma]);  // along the bar along v
  const double cross = a.value * eu.value + b.value * ev.value - a.value * b.value;
  const double bx = s.x_px - xc, by = s.y_px - yc;
  const double model = p[kB0] + p[kBx] * bx + p[kBy] * by + p[kGain] * cross;
  if (gradient) {
    const double g = p[kGain];
    const double dc_du = a.value * eu.d_t + b.d_t * ev.value - a.value * b.d_t;
    const double dc_dv = a.d_t * eu.value + b.value * ev.d_t - a.d_t * b.value;
    // du/dx0 = -c, dv/dx0 = sn; du/dy0 = -sn, dv/dy0 = -c; du/dtheta = v, dv/dtheta = -u.
    gradient[kX0] = g * (-c * dc_du + sn * dc_dv);
    gradient[kY0] = g * (-sn * dc_du - c * dc_dv);
    gradient[kTheta] = g * (v * dc_du - u * dc_dv);
    gradient[kWidthH] = g * (a.d_width * eu.value - a.d_width * b.value);
    gradient[kWidthV] = g * (b.d_width * ev.value - a.value * b.d_width);
    gradient[kLength] = g * (a.value * eu.d_width + b.value * ev.d_width);
    gradient[kSigma] = g * (a.d_sigma * eu.value + a.value * eu.d_sigma + b.d_sigma * ev.value +
                            b.value * ev.d_sigma - a.d_sigma * b.value - a.value * b.d_sigma);
    gradient[kGain] = cross;
    gradient[kB0] = 1.0;
    gradient[kBx] = bx;
    gradient[kBy] = by;
  }
  return model;
}

class CrossCost : public ceres::CostFunction {
 public:
  CrossCost(const std::vector<Sample>* samples, double xc, double yc) : samples_(samples), xc_(xc), yc_(yc) {
    set_num_residuals(static_cast<int>(samples->size()));
    mutable_parameter_block_sizes()->push_back(kNumParams);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* p = parameters[0];
    double gradient[kNumParams];
    const bool want_jacobian = jacobians && jacobians[0];
    for (size_t i = 0; i < samples_->size(); ++i) {
      const Sample& s = (*samples_)[i];
      residuals[i] = CrossModel(p, xc_, yc_, s, want_jacobian ? gradient : nullptr) - s.value_dn;
      if (want_jacobian) std::copy(gradient, gradient + kNumParams, jacobians[0] + i * kNumParams);
    }
    return true;
  }

 private:
  const std::vector<Sample>* samples_;
  double xc_, yc_;
};

// Pixels near the arms (within the start's uncertainty), plus a margin of background;
// the region's masked pixels are left out and counted in *masked.
std::vector<Sample> SelectSamples(const ImageWindow& window, const CrossFitStart& start, const CrossFitOptions& options,
                                  int* masked) {
  const double c = std::cos(start.rotation_rad), sn = std::sin(start.rotation_rad);
  const double band = 0.5 * start.line_width_px + 4.0 * start.blur_sigma_px + options.margin_px + start.line_width_px;
  const double reach = 0.5 * start.arm_length_px + 4.0 * start.blur_sigma_px + options.margin_px;
  std::vector<Sample> samples;
  for (long row = window.rect.y0_px; row < window.rect.y_end_px(); ++row) {
    for (long col = window.rect.x0_px; col < window.rect.x_end_px(); ++col) {
      const double dx = col - start.centre_px.x_px, dy = row - start.centre_px.y_px;
      const double u = c * dx + sn * dy, v = -sn * dx + c * dy;
      const bool on_u_arm = std::abs(v) <= band && std::abs(u) <= reach;
      const bool on_v_arm = std::abs(u) <= band && std::abs(v) <= reach;
      if (!on_u_arm && !on_v_arm) continue;
      const float value = window.at(col, row);
      if (std::isfinite(value)) {
        samples.push_back({static_cast<double>(col), static_cast<double>(row), static_cast<double>(value)});
      } else {
        ++*masked;
      }
    }
  }
  return samples;
}

// What a solve holds at its current values.
enum class Held {
  kShape,         // rotation, widths, length, blur: a first pass that cannot wander off into a
                  // thin-line degeneracy while the position is still rough
  kNothing,       // every parameter free
  kWidthsAndBlur  // widths, length, blur (CrossFitStart::shape_known): the rotation free
};

bool Solve(const std::vector<Sample>& samples, double xc, double yc, const CrossFitOptions& options,
           const CrossFitStart& start, Held held, double* p, std::string* message) {
  ceres::Problem problem;
  problem.AddResidualBlock(new CrossCost(&samples, xc, yc), nullptr, p);
  // The start is within about a line width; a fit that wants to leave this box has found something else.
  const double reach_px = 2.0 * start.line_width_px + 2.0;
  problem.SetParameterLowerBound(p, kX0, start.centre_px.x_px - reach_px);
  problem.SetParameterUpperBound(p, kX0, start.centre_px.x_px + reach_px);
  problem.SetParameterLowerBound(p, kY0, start.centre_px.y_px - reach_px);
  problem.SetParameterUpperBound(p, kY0, start.centre_px.y_px + reach_px);
  if (held == Held::kShape) {
    problem.SetManifold(p, new ceres::SubsetManifold(kNumParams, {kTheta, kWidthH, kWidthV, kLength, kSigma}));
  } else {
    problem.SetParameterLowerBound(p, kTheta, start.rotation_rad - 0.1);
    problem.SetParameterUpperBound(p, kTheta, start.rotation_rad + 0.1);
  }
  if (held == Held::kWidthsAndBlur) {
    problem.SetManifold(p, new ceres::SubsetManifold(kNumParams, {kWidthH, kWidthV, kLength, kSigma}));
  } else if (held == Held::kNothing) {
    // Plausible ranges around the definition, so a bad pixel patch cannot turn the cross into something else.
    const double w = start.line_width_px;
    for (int k : {kWidthH, kWidthV}) {
      problem.SetParameterLowerBound(p, k, 0.2 * w);
      problem.SetParameterUpperBound(p, k, 3.0 * w + 1.0);
    }
    problem.SetParameterLowerBound(p, kLength, 0.7 * start.arm_length_px);
    problem.SetParameterUpperBound(p, kLength, 1.3 * start.arm_length_px + 2.0);
    problem.SetParameterLowerBound(p, kSigma, options.min_blur_sigma_px);
    problem.SetParameterUpperBound(p, kSigma, 2.0 * w + 3.0);
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 11 parameters, thousands of residuals
  solver.max_num_iterations = options.max_iterations;
  // Converged when a step moves the centre by far less than its sigma.
  solver.function_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-9;
  solver.gradient_tolerance = 1e-12;
  solver.num_threads = 1;  // crosses are fitted in parallel one level up
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  *message = summary.message;
  return summary.IsSolutionUsable();
}

// Formal errors of a converged fit, scaled by its own residual variance.
struct FormalErrors {
  Eigen::Matrix2d centre_covariance;
  double gain_variance = 0.0;         // place and shape held, plane background free
  double sigma0_sq = 0.0;
};

// Pseudo-inverse of a symmetric positive semi-definite matrix, scaled to unit
// diagonal first so the tolerance is meaningful (width and blur of a thin line
// are nearly interchangeable, which must not break the position's sigma);
// zero rows (held parameters) stay zero.
template <int N>
Eigen::Matrix<double, N, N> ScaledPseudoInverse(const Eigen::Matrix<double, N, N>& m) {
  const Eigen::Matrix<double, N, 1> scale = m.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::Matrix<double, N, N> scaled = scale.asDiagonal() * m * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(scaled);
  Eigen::Matrix<double, N, 1> inverse_values;
  const double tolerance = 1e-10 * eigen.eigenvalues().maxCoeff();
  for (int i = 0; i < N; ++i) inverse_values[i] = eigen.eigenvalues()[i] > tolerance ? 1.0 / eigen.eigenvalues()[i] : 0.0;
  return scale.asDiagonal() * eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose() *
         scale.asDiagonal();
}

using Normal = Eigen::Matrix<double, kNumParams, kNumParams>;

// The normal matrix of the fit at p over the samples (and, when rss != nullptr,
// the residual sum of squares); a held shape's rows and columns are zero.
Normal NormalMatrix(const std::vector<Sample>& samples, const double* p, double xc, double yc, bool shape_held,
                    double* rss) {
  Normal normal = Normal::Zero();
  for (const Sample& s : samples) {
    Eigen::Matrix<double, kNumParams, 1> gradient;
    const double residual = CrossModel(p, xc, yc, s, gradient.data()) - s.value_dn;
    normal.selfadjointView<Eigen::Lower>().rankUpdate(gradient);
    if (rss) *rss += residual * residual;
  }
  normal = normal.selfadjointView<Eigen::Lower>();
  if (shape_held) {
    for (int k : {kWidthH, kWidthV, kLength, kSigma}) {
      normal.row(k).setZero();
      normal.col(k).setZero();
    }
  }
  return normal;
}

// The information on the centre: the Schur complement of the normal matrix on
// the nuisance parameters.
Eigen::Matrix2d CentreInformation(const Normal& normal) {
  constexpr int kNuisance = kNumParams - 2;
  const Eigen::Matrix<double, 2, kNuisance> npn = normal.topRightCorner<2, kNuisance>();
  const Eigen::Matrix<double, kNuisance, kNuisance> nnn_pinv =
      ScaledPseudoInverse<kNuisance>(normal.bottomRightCorner<kNuisance, kNuisance>());
  return normal.topLeftCorner<2, 2>() - npn * nnn_pinv * npn.transpose();
}

// The centre's covariance from its information, and the gain's variance.
FormalErrors ComputeFormalErrors(const std::vector<Sample>& samples, const double* p, double xc, double yc,
                                 bool shape_held) {
  double rss = 0.0;
  const Normal normal = NormalMatrix(samples, p, xc, yc, shape_held, &rss);
  const int free_params = shape_held ? kNumParams - 4 : kNumParams;
  FormalErrors errors;
  errors.sigma0_sq = rss / std::max(static_cast<int>(samples.size()) - free_params, 1);
  errors.centre_covariance = errors.sigma0_sq * CentreInformation(normal).inverse();
  // |gain| / sqrt(gain_variance) is the matched-filter SNR of the fitted cross.
  const Eigen::Matrix4d gain_block = normal.block<4, 4>(kGain, kGain);
  errors.gain_variance = errors.sigma0_sq * gain_block.inverse()(0, 0);
  return errors;
}

// The share of the centre's information (1 / variance, the worse axis) that the
// kept pixels hold of what the whole region would with a clean cross.
double InformationKept(const std::vector<Sample>& all, const std::vector<Sample>& kept, const double* p, double xc,
                       double yc, bool shape_held) {
  if (kept.size() == all.size()) return 1.0;
  const Eigen::Matrix2d all_covariance = CentreInformation(NormalMatrix(all, p, xc, yc, shape_held, nullptr)).inverse();
  const Eigen::Matrix2d kept_covariance = CentreInformation(NormalMatrix(kept, p, xc, yc, shape_held, nullptr)).inverse();
  return std::min(all_covariance(0, 0) / kept_covariance(0, 0), all_covariance(1, 1) / kept_covariance(1, 1));
}

// The samples whose residual from the model lies beyond the outlier limit, the
// limit from the robust scatter of the samples not yet dropped.
std::vector<char> FlagOutliers(const std::vector<Sample>& samples, const std::vector<char>& dropped, const double* p,
                               double xc, double yc, const CrossFitOptions& options) {
  std::vector<double> abs_residuals(samples.size()), kept_residuals;
  for (size_t i = 0; i < samples.size(); ++i) {
    abs_residuals[i] = std::abs(CrossModel(p, xc, yc, samples[i], nullptr) - samples[i].value_dn);
    if (!dropped[i]) kept_residuals.push_back(abs_residuals[i]);
  }
  const double robust_sigma = 1.4826 * Median(kept_residuals);
  // The floor keeps a nearly noise-free scan from losing pixels to tiny model
  // differences; real defects deviate by a large part of the contrast.
  const double limit = std::max(options.outlier_threshold * robust_sigma, options.min_outlier_contrast * std::abs(p[kGain]));
  std::vector<char> flags(samples.size(), 0);
  for (size_t i = 0; i < samples.size(); ++i) flags[i] = abs_residuals[i] > limit;
  return flags;
}

// Grows the flagged samples by margin_px (a square) on the window's pixel grid.
std::vector<char> GrowFlags(const std::vector<Sample>& samples, const std::vector<char>& flags, const PixelRect& rect,
                            long margin_px) {
  if (margin_px <= 0) return flags;
  std::vector<char> grid(static_cast<size_t>(rect.width_px * rect.height_px), 0);
  auto cell = [&](long col, long row) -> char& {
    return grid[static_cast<size_t>((row - rect.y0_px) * rect.width_px + (col - rect.x0_px))];
  };
  for (size_t i = 0; i < samples.size(); ++i) {
    if (!flags[i]) continue;
    const long col = static_cast<long>(samples[i].x_px), row = static_cast<long>(samples[i].y_px);
    for (long r = std::max(rect.y0_px, row - margin_px); r <= std::min(rect.y_end_px() - 1, row + margin_px); ++r)
      for (long c = std::max(rect.x0_px, col - margin_px); c <= std::min(rect.x_end_px() - 1, col + margin_px); ++c)
        cell(c, r) = 1;
  }
  std::vector<char> grown(samples.size(), 0);
  for (size_t i = 0; i < samples.size(); ++i)
    grown[i] = cell(static_cast<long>(samples[i].x_px), static_cast<long>(samples[i].y_px));
  return grown;
}

std::vector<Sample> Kept(const std::vector<Sample>& samples, const std::vector<char>& dropped) {
  std::vector<Sample> kept;
  kept.reserve(samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    if (!dropped[i]) kept.push_back(samples[i]);
  return kept;
}

}  // namespace

bool CrossFitOptions::Check(std::string* why) const {
  if (!(margin_px >= 0.0)) return *why = "margin_px must be >= 0", false;
  if (!(min_blur_sigma_px > 0.0)) return *why = "min_blur_sigma_px must be > 0", false;
  if (!(outlier_threshold > 1.0)) return *why = "outlier_threshold must be > 1", false;
  if (!(min_information_kept > 0.0 && min_information_kept <= 1.0)) {
    return *why = "min_information_kept must be in (0, 1]", false;
  }
  if (!(foreign_margin_blurs >= 0.0)) return *why = "foreign_margin_blurs must be >= 0", false;
  if (!(max_masked_fraction >= 0.0 && max_masked_fraction < 1.0)) {
    return *why = "max_masked_fraction must be in [0, 1)", false;
  }
  if (max_iterations < 1) return *why = "max_iterations must be >= 1", false;
  return true;
}

PixelRect CrossFitWindow(const CrossFitStart& start, const CrossFitOptions& options) {
  const double half = 0.5 * start.arm_length_px + 4.0 * start.blur_sigma_px + options.margin_px + start.line_width_px;
  const long x0 = static_cast<long>(std::floor(start.centre_px.x_px - half));
  const long y0 = static_cast<long>(std::floor(start.centre_px.y_px - half));
  const long x1 = static_cast<long>(std::ceil(start.centre_px.x_px + half));
  const long y1 = static_cast<long>(std::ceil(start.centre_px.y_px + half));
  return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

CrossFitResult FitCross(const ImageWindow& window, const CrossFitStart& start, const CrossFitOptions& options) {
  CrossFitResult result;
  std::vector<Sample> samples = SelectSamples(window, start, options, &result.pixels_masked);
  const size_t region_px = samples.size() + static_cast<size_t>(result.pixels_masked);
  result.masked_fraction = region_px > 0 ? static_cast<double>(result.pixels_masked) / static_cast<double>(region_px) : 0.0;
  if (result.masked_fraction > options.max_masked_fraction) {
    result.too_many_masked = true;
    result.summary = std::to_string(result.pixels_masked) + " of the cross's " + std::to_string(region_px) +
                     " px are masked (no value in the scan): too few left to fit it";
    return result;
  }
  if (samples.size() < 4 * kNumParams) {
    result.summary = "too few pixels around the cross to fit it";
    return result;
  }
  // Start: background from the median; contrast from the tail of the pixel
  // values on the side away from the background (dark or bright crosses).
  std::vector<double> values;
  values.reserve(samples.size());
  for (const Sample& s : samples) values.push_back(s.value_dn);
  std::sort(values.begin(), values.end());
  const double background = values[values.size() / 2];
  const size_t tail = std::max<size_t>(3, values.size() / 40);
  double low = 0, high = 0;
  for (size_t i = 0; i < tail; ++i) {
    low += values[i] / tail;
    high += values[values.size() - 1 - i] / tail;
  }
  const double gain = (background - low > high - background) ? low - background : high - background;
  const double xc = start.centre_px.x_px, yc = start.centre_px.y_px;
  double p[kNumParams] = {};
  p[kX0] = start.centre_px.x_px;
  p[kY0] = start.centre_px.y_px;
  p[kTheta] = start.rotation_rad;
  p[kWidthH] = p[kWidthV] = start.line_width_px;
  p[kLength] = start.arm_length_px;
  // A generous blur widens the basin of the first pass (thin lines, rough start).
  p[kSigma] = start.shape_known ? start.blur_sigma_px
                                : std::max({start.blur_sigma_px, options.min_blur_sigma_px, 0.5 * start.line_width_px + 0.5});
  p[kGain] = gain / std::min(1.0, start.line_width_px);  // a sub-pixel line covers only part of a pixel
  p[kB0] = background;
  if (gain == 0.0) {
    result.summary = "no contrast between the arms and the background";
    return result;
  }

  std::string message;
  const Held final_pass = start.shape_known ? Held::kWidthsAndBlur : Held::kNothing;
  bool usable = Solve(samples, xc, yc, options, start, Held::kShape, p, &message) &&
                Solve(samples, xc, yc, options, start, final_pass, p, &message);
  // Drop pixels that do not belong to a clean cross (dust, scratches, damage,
  // star images) and solve again without them, so the final fit is plain least
  // squares: first the outliers of the first fit; then, afresh, those of the fit
  // without them (the first fit, bent toward the foreign pixels, also misfits
  // some of the cross's own), with a margin around each (their blurred edges
  // still pull) of the clean fit's blur.
  const std::vector<Sample> all_samples = samples;
  std::vector<char> dropped(all_samples.size(), 0);
  for (int round = 0; usable && round < 2; ++round) {
    const std::vector<char> flags = FlagOutliers(all_samples, dropped, p, xc, yc, options);
    const long margin_px = std::lround(options.foreign_margin_blurs * p[kSigma]);
    std::vector<char> next = round == 0 ? flags : GrowFlags(all_samples, flags, window.rect, margin_px);
    if (next == dropped) break;
    dropped.swap(next);
    std::vector<Sample> kept = Kept(all_samples, dropped);
    if (kept.size() < 4 * kNumParams) {
      usable = false;
      message = "too few clean pixels left";
      break;
    }
    samples.swap(kept);
    usable = Solve(samples, xc, yc, options, start, final_pass, p, &message);
  }
  result.outlier_fraction = 1.0 - static_cast<double>(samples.size()) / static_cast<double>(all_samples.size());
  if (usable) result.information_kept = InformationKept(all_samples, samples, p, xc, yc, start.shape_known);
  if (!usable) {
    result.summary = "the cross fit did not converge (" + message + ")";
    return result;
  }

  const FormalErrors errors = ComputeFormalErrors(samples, p, xc, yc, start.shape_known);
  const Eigen::Matrix2d& covariance = errors.centre_covariance;
  result.converged = true;
  result.centre_px = {p[kX0], p[kY0]};
  result.sigma_x_px = std::sqrt(std::max(covariance(0, 0), 0.0));
  result.sigma_y_px = std::sqrt(std::max(covariance(1, 1), 0.0));
  result.correlation_xy = covariance(0, 1) / std::max(result.sigma_x_px * result.sigma_y_px, 1e-300);
  result.rotation_rad = p[kTheta];
  result.width_h_px = p[kWidthH];
  result.width_v_px = p[kWidthV];
  result.arm_length_px = p[kLength];
  result.blur_sigma_px = p[kSigma];
  result.gain_dn = p[kGain];
  result.background_dn = p[kB0];
  result.residual_sigma_dn = std::sqrt(errors.sigma0_sq);
  result.gain_sigma_dn = std::sqrt(std::max(errors.gain_variance, 0.0));
  result.pixels_used = static_cast<int>(samples.size());
  std::ostringstream summary;
  summary << "fitted on " << samples.size() << " px (" << static_cast<int>(100.0 * result.outlier_fraction + 0.5)
          << "% dropped as outliers";
  if (result.pixels_masked > 0) summary << ", " << result.pixels_masked << " masked left out";
  summary << "), residual sigma " << result.residual_sigma_dn << " DN";
  result.summary = summary.str();
  return result;
}

}  // namespace platemeter
