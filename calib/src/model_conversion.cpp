// Lens estimates, the common form and the conversions between lens models
// (model_conversion.h has the formulas).
#include "platemeter/calib/model_conversion.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>

#include "platemeter/calib/camera_model.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// c plus the largest parameter block of the common form (brown-affine: 7).
constexpr int kMaxModelDim = 9;
using Jet = ceres::Jet<double, kMaxModelDim>;

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Gaussian models hold no a0: their focal length absorbs it.
bool IsGaussian(DistortionModelId id) {
  return id == DistortionModelId::kBrownConrady || id == DistortionModelId::kBrownAffine ||
         id == DistortionModelId::kSmacRadialDecentering || id == DistortionModelId::kNone;
}

GeneralLens<double> ValuePart(const GeneralLens<Jet>& g) {
  GeneralLens<double> v;
  v.c_mm = g.c_mm.a;
  for (int i = 0; i < 4; ++i) v.a[i] = g.a[i].a;
  for (int i = 0; i < 4; ++i) v.p[i] = g.p[i].a;
  for (int i = 0; i < 2; ++i) v.b[i] = g.b[i].a;
  return v;
}

// The comparison grid: row-major, x fastest.
std::vector<Eigen::Vector2d> FormatGrid(const ConversionOptions& options) {
  std::vector<Eigen::Vector2d> points;
  const int n = options.grid_points_per_side;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      points.emplace_back(options.format_width_mm * (double(i) / (n - 1) - 0.5),
                          options.format_height_mm * (double(j) / (n - 1) - 0.5));
    }
  }
  return points;
}

struct ResidualStats {
  double rms_mm = 0.0;
  double max_mm = 0.0;
};

ResidualStats Stats(const std::vector<double>& lengths_mm) {
  ResidualStats stats;
  double sum2 = 0.0;
  for (double d : lengths_mm) {
    sum2 += d * d;
    stats.max_mm = std::max(stats.max_mm, d);
  }
  stats.rms_mm = lengths_mm.empty() ? 0.0 : std::sqrt(sum2 / lengths_mm.size());
  return stats;
}

// Target field (model M's correction) minus a fixed field, at one point.
template <typename M>
struct CorrectionResidual {
  double x_mm, y_mm, target_dx_mm, target_dy_mm;
  template <typename T>
  bool operator()(const T* params, T* residual) const {
    T dx, dy;
    M::Apply(params, T(x_mm), T(y_mm), &dx, &dy);
    residual[0] = dx - T(target_dx_mm);
    residual[1] = dy - T(target_dy_mm);
    return true;
  }
};

// Model M's ideal point minus a fixed ideal point (either direction).
template <typename M>
struct IdealResidual {
  double x_mm, y_mm, ideal_x_mm, ideal_y_mm;
  template <typename T>
  bool operator()(const T* params, T* residual) const {
    T ix, iy;
    if (!IdealFromMeasured<M>(params, T(x_mm), T(y_mm), &ix, &iy)) return false;
    residual[0] = ix - T(ideal_x_mm);
    residual[1] = iy - T(ideal_y_mm);
    return true;
  }
};

ceres::Solver::Options FitSolverOptions() {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-16;
  options.parameter_tolerance = 1e-16;
  options.gradient_tolerance = 1e-24;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.num_threads = 1;
  return options;
}

// Least squares with the columns scaled to unit length (the parameters span
// 1e0 .. 1e-13): returns X minimizing |A X - B| (minimum norm if A is rank deficient).
Eigen::MatrixXd ScaledLeastSquares(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  Eigen::VectorXd scale(a.cols());
  for (int j = 0; j < a.cols(); ++j) {
    const double norm = a.col(j).norm();
    scale(j) = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  const Eigen::MatrixXd scaled = a * scale.asDiagonal();
  const Eigen::MatrixXd x = scaled.completeOrthogonalDecomposition().solve(b);
  return scale.asDiagonal() * x;
}

}  // namespace

// ---------------------------------------------------------------------------
std::vector<std::string> LensEstimate::ParameterNames() const {
  std::vector<std::string> names = {"principal_distance_mm"};
  for (const std::string& name : DistortionModelParamNames(model)) names.push_back(name);
  return names;
}

int LensEstimate::IndexOf(const std::string& name) const {
  const std::vector<std::string> names = ParameterNames();
  const auto found = std::find(names.begin(), names.end(), name);
  return found == names.end() ? -1 : int(found - names.begin());
}

bool LensEstimate::Check(std::string* why) const {
  const int n = DistortionModelNumParams(model);
  if (int(params.size()) != n) {
    *why = fmt::format("model {} has {} parameters, not {}", DistortionModelName(model), n, params.size());
    return false;
  }
  if (!(principal_distance_mm > 0.0) || !std::isfinite(principal_distance_mm)) {
    *why = fmt::format("the principal distance must be finite and > 0 (is {})", principal_distance_mm);
    return false;
  }
  for (size_t i = 0; i < params.size(); ++i) {
    if (!std::isfinite(params[i])) {
      *why = fmt::format("parameter {} is not finite", DistortionModelParamNames(model)[i]);
      return false;
    }
  }
  if (covariance.rows() != n + 1 || covariance.cols() != n + 1) {
    *why = fmt::format("the covariance must be {0} x {0} (c and {1} parameters), is {2} x {3}", n + 1, n,
                       covariance.rows(), covariance.cols());
    return false;
  }
  const std::vector<std::string> names = ParameterNames();
  for (int i = 0; i <= n; ++i) {
    if (!std::isfinite(covariance(i, i)) || covariance(i, i) < 0.0) {
      *why = fmt::format("the variance of {} must be finite and >= 0", names[i]);
      return false;
    }
    for (int j = 0; j < i; ++j) {
      const double tolerance = 1e-12 * std::sqrt(covariance(i, i) * covariance(j, j));
      if (!std::isfinite(covariance(i, j)) || std::abs(covariance(i, j) - covariance(j, i)) > tolerance) {
        *why = fmt::format("the covariance of {} and {} is not symmetric", names[i], names[j]);
        return false;
      }
    }
  }
  return true;
}

LensEstimate LensEstimateFromCalibration(const LensCalibration& lens, const std::string& subject,
                                         std::vector<std::string>* without_sigma) {
  const CameraModel camera = CameraModelFromLensCalibration(lens, subject);
  LensEstimate estimate;
  estimate.model = camera.model();
  estimate.principal_distance_mm = camera.interior().principal_distance_mm;
  estimate.params = camera.params();
  const std::vector<std::string> names = estimate.ParameterNames();
  estimate.covariance = Eigen::MatrixXd::Zero(names.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    // The sigma under the parameter's own name, or under the published unit.
    std::vector<std::pair<std::string, double>> keys = {{name, 1.0}};
    if (EndsWith(name, "_mm")) keys.push_back({name.substr(0, name.size() - 3) + "_um", 1e-3});
    if (EndsWith(name, "_rad")) keys.push_back({name.substr(0, name.size() - 4) + "_deg", M_PI / 180.0});
    bool found = false;
    for (const auto& [key, scale] : keys) {
      const auto it = lens.sigmas.find(key);
      if (it == lens.sigmas.end()) continue;
      const double sigma = it->second * scale;
      if (!std::isfinite(sigma) || sigma < 0.0) {
        throw Error(subject, fmt::format("the sigma of {} must be finite and >= 0", key));
      }
      estimate.covariance(i, i) = sigma * sigma;
      found = true;
      break;
    }
    if (!found && without_sigma != nullptr) without_sigma->push_back(name);
  }
  return estimate;
}

void SetCorrelation(LensEstimate* lens, const std::string& a, const std::string& b, double rho) {
  const int i = lens->IndexOf(a);
  const int j = lens->IndexOf(b);
  std::string known;
  for (const std::string& name : lens->ParameterNames()) known += (known.empty() ? "" : ", ") + name;
  if (i < 0) throw Error("correlation", fmt::format("no parameter {} (known: {})", a, known));
  if (j < 0) throw Error("correlation", fmt::format("no parameter {} (known: {})", b, known));
  if (i == j) throw Error("correlation", fmt::format("a parameter's correlation with itself ({}) is 1", a));
  if (!(std::abs(rho) <= 1.0)) throw Error("correlation", fmt::format("{} is not in [-1, 1]", rho));
  const int n = int(lens->ParameterNames().size());
  if (lens->covariance.rows() != n || lens->covariance.cols() != n) {
    throw Error("correlation", fmt::format("the covariance must be {0} x {0}", n));
  }
  const double value = rho * std::sqrt(lens->covariance(i, i) * lens->covariance(j, j));
  lens->covariance(i, j) = value;
  lens->covariance(j, i) = value;
}

double PropagatedSigma(const Eigen::MatrixXd& covariance, const Eigen::VectorXd& gradient) {
  const double variance = gradient.dot(covariance * gradient);
  return std::sqrt(std::max(variance, 0.0));
}

bool HasGeneralLensForm(DistortionModelId id) { return id != DistortionModelId::kSlama; }

void BrownDecenteringFromSmac(double j1_per_mm, double theta0_rad, double* p1_per_mm, double* p2_per_mm) {
  *p1_per_mm = -j1_per_mm * std::sin(theta0_rad);
  *p2_per_mm = j1_per_mm * std::cos(theta0_rad);
}

void SmacDecenteringFromBrown(double p1_per_mm, double p2_per_mm, double* j1_per_mm, double* theta0_rad) {
  *j1_per_mm = std::hypot(p1_per_mm, p2_per_mm);
  *theta0_rad = std::atan2(-p1_per_mm, p2_per_mm);
}

bool ConversionOptions::Check(std::string* why) const {
  if (!(format_width_mm > 0.0) || !(format_height_mm > 0.0) || !std::isfinite(format_width_mm) ||
      !std::isfinite(format_height_mm)) {
    *why = fmt::format("the format must be > 0 mm wide and high (is {} x {})", format_width_mm, format_height_mm);
    return false;
  }
  if (grid_points_per_side < 3 || grid_points_per_side > 1001) {
    *why = fmt::format("grid_points_per_side must be 3..1001 (is {})", grid_points_per_side);
    return false;
  }
  if (!(exact_tolerance_mm >= 0.0)) {
    *why = "exact_tolerance_mm must be >= 0";
    return false;
  }
  if (!std::isnan(balance_radius_mm) && !(balance_radius_mm > 0.0 && std::isfinite(balance_radius_mm))) {
    *why = fmt::format("the balance radius must be > 0 mm (is {})", balance_radius_mm);
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------
LensConversion ConvertLens(const LensEstimate& from, DistortionModelId to, const ConversionOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("lens conversion", why);
  if (!from.Check(&why)) throw Error("lens conversion", why);
  for (DistortionModelId id : {from.model, to}) {
    if (!HasGeneralLensForm(id)) {
      throw Error("lens conversion", fmt::format("model {} is not of the common form (use FitDistortionField)",
                                                 DistortionModelName(id)));
    }
  }
  const int n = 1 + int(from.params.size());
  const int m = DistortionModelNumParams(to);

  // The exact part, as Jets over [c, params...] of the source.
  std::vector<Jet> x(n);
  for (int i = 0; i < n; ++i) x[i] = Jet(i == 0 ? from.principal_distance_mm : from.params[i - 1], i);
  GeneralLens<Jet> g;
  GeneralLensFromModel(from.model, x[0], x.data() + 1, &g);
  if (IsGaussian(to)) {
    g = RescaledGeneralLens(g, Jet(1.0) / (Jet(1.0) + g.a[0]));
  } else if (to == DistortionModelId::kBrownBalanced && !std::isnan(options.balance_radius_mm)) {
    const double r2 = options.balance_radius_mm * options.balance_radius_mm;
    const Jet gr = Jet(1.0) + g.a[0] + r2 * (g.a[1] + r2 * (g.a[2] + r2 * g.a[3]));
    g = RescaledGeneralLens(g, Jet(1.0) / gr);
  }
  std::vector<Jet> target(std::max(m, 1));
  ModelFromGeneralLens(to, g, target.data());

  LensConversion result;
  result.lens.model = to;
  result.lens.principal_distance_mm = g.c_mm.a;
  result.lens.params.resize(m);
  Eigen::MatrixXd jacobian(1 + m, n);  // d[c', params'] / d[c, params]
  for (int j = 0; j < n; ++j) jacobian(0, j) = g.c_mm.v[j];
  for (int i = 0; i < m; ++i) {
    result.lens.params[i] = target[i].a;
    for (int j = 0; j < n; ++j) jacobian(1 + i, j) = target[i].v[j];
  }

  // The source field (for the target's focal length) against the target's, over the format.
  const std::vector<Eigen::Vector2d> grid = FormatGrid(options);
  const GeneralLens<double> source = ValuePart(g);
  std::vector<Eigen::Vector2d> source_field;
  for (const Eigen::Vector2d& point : grid) {
    Eigen::Vector2d d;
    ApplyGeneralLens(source, point.x(), point.y(), &d.x(), &d.y());
    source_field.push_back(d);
  }
  auto residual_lengths = [&](const std::vector<double>& params) {
    std::vector<double> lengths;
    VisitDistortionModel(to, [&](auto model) {
      using M = decltype(model);
      for (size_t k = 0; k < grid.size(); ++k) {
        double dx, dy;
        M::Apply(params.data(), grid[k].x(), grid[k].y(), &dx, &dy);
        lengths.push_back(std::hypot(dx - source_field[k].x(), dy - source_field[k].y()));
      }
    });
    return lengths;
  };
  ResidualStats stats = Stats(residual_lengths(result.lens.params));
  result.exact = stats.max_mm <= options.exact_tolerance_mm;

  if (!result.exact && m > 0) {
    // A least-squares fit of the target's field, started from the exact part.
    std::vector<double> fitted = result.lens.params;
    bool converged = false;
    Eigen::MatrixXd jp(2 * grid.size(), m);  // d residual / d target params at the solution
    VisitDistortionModel(to, [&](auto model) {
      using M = decltype(model);
      if constexpr (M::kNumParams > 0) {
        ceres::Problem problem;
        for (size_t k = 0; k < grid.size(); ++k) {
          problem.AddResidualBlock(
              new ceres::AutoDiffCostFunction<CorrectionResidual<M>, 2, M::kNumParams>(new CorrectionResidual<M>{
                  grid[k].x(), grid[k].y(), source_field[k].x(), source_field[k].y()}),
              nullptr, fitted.data());
        }
        ceres::Solver::Summary summary;
        ceres::Solve(FitSolverOptions(), &problem, &summary);
        converged = summary.IsSolutionUsable();
        using JetM = ceres::Jet<double, M::kNumParams>;
        std::array<JetM, M::kNumParams> p;
        for (int i = 0; i < M::kNumParams; ++i) p[i] = JetM(fitted[i], i);
        for (size_t k = 0; k < grid.size(); ++k) {
          JetM dx, dy;
          M::Apply(p.data(), JetM(grid[k].x()), JetM(grid[k].y()), &dx, &dy);
          for (int i = 0; i < M::kNumParams; ++i) {
            jp(2 * k, i) = dx.v[i];
            jp(2 * k + 1, i) = dy.v[i];
          }
        }
      }
    });
    // d source field / d [c, params] of the source.
    Eigen::MatrixXd jq(2 * grid.size(), n);
    for (size_t k = 0; k < grid.size(); ++k) {
      Jet dx, dy;
      ApplyGeneralLens(g, Jet(grid[k].x()), Jet(grid[k].y()), &dx, &dy);
      for (int j = 0; j < n; ++j) {
        jq(2 * k, j) = dx.v[j];
        jq(2 * k + 1, j) = dy.v[j];
      }
    }
    // At the solution J_p' r = 0, so dp = (J_p' J_p)^-1 J_p' J_q dq to first order.
    jacobian.bottomRows(m) = ScaledLeastSquares(jp, jq);
    result.lens.params = fitted;
    stats = Stats(residual_lengths(fitted));
    if (!converged) {
      throw Error("lens conversion", fmt::format("the fit of {} to {} did not converge", DistortionModelName(to),
                                                 DistortionModelName(from.model)));
    }
  }
  const Eigen::MatrixXd covariance = jacobian * from.covariance * jacobian.transpose();
  result.lens.covariance = 0.5 * (covariance + covariance.transpose());
  result.rms_residual_mm = stats.rms_mm;
  result.max_residual_mm = stats.max_mm;
  result.num_points = int(grid.size());
  result.summary =
      result.exact
          ? fmt::format("{} -> {}: exact (c = {:.6f} mm; field within {:.1e} mm over {} points)",
                        DistortionModelName(from.model), DistortionModelName(to), result.lens.principal_distance_mm,
                        stats.max_mm, grid.size())
      : m == 0
          ? fmt::format("{} -> none: the field left out has RMS {:.3f} um, max {:.3f} um",
                        DistortionModelName(from.model), stats.rms_mm * 1e3, stats.max_mm * 1e3)
          : fmt::format("{} -> {}: least-squares fit over {:g} x {:g} mm, RMS residual {:.3f} um, max {:.3f} um "
                        "(the target cannot hold the source exactly)",
                        DistortionModelName(from.model), DistortionModelName(to), options.format_width_mm,
                        options.format_height_mm, stats.rms_mm * 1e3, stats.max_mm * 1e3);
  return result;
}

// ---------------------------------------------------------------------------
FieldFit FitDistortionField(DistortionModelId from, const std::vector<double>& from_params, DistortionModelId to,
                            const std::vector<double>& initial_params, const ConversionOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("field fit", why);
  if (int(from_params.size()) != DistortionModelNumParams(from)) {
    throw Error("field fit", fmt::format("model {} has {} parameters, not {}", DistortionModelName(from),
                                         DistortionModelNumParams(from), from_params.size()));
  }
  const int m = DistortionModelNumParams(to);
  if (!initial_params.empty() && int(initial_params.size()) != m) {
    throw Error("field fit", fmt::format("model {} has {} parameters, not {} (initial values)",
                                         DistortionModelName(to), m, initial_params.size()));
  }
  const std::vector<Eigen::Vector2d> grid = FormatGrid(options);
  std::vector<Eigen::Vector2d> ideal_from(grid.size());
  VisitDistortionModel(from, [&](auto model) {
    using M = decltype(model);
    for (size_t k = 0; k < grid.size(); ++k) {
      if (!IdealFromMeasured<M>(from_params.data(), grid[k].x(), grid[k].y(), &ideal_from[k].x(),
                                &ideal_from[k].y())) {
        throw Error("field fit", fmt::format("the inverse of {} does not converge at ({:g}, {:g}) mm",
                                             DistortionModelName(from), grid[k].x(), grid[k].y()));
      }
    }
  });

  FieldFit fit;
  fit.params = initial_params.empty() ? std::vector<double>(m, 0.0) : initial_params;
  fit.num_points = int(grid.size());
  fit.converged = true;
  std::vector<double> lengths;
  VisitDistortionModel(to, [&](auto model) {
    using M = decltype(model);
    if constexpr (M::kNumParams > 0) {
      ceres::Problem problem;
      for (size_t k = 0; k < grid.size(); ++k) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<IdealResidual<M>, 2, M::kNumParams>(
                                     new IdealResidual<M>{grid[k].x(), grid[k].y(), ideal_from[k].x(),
                                                          ideal_from[k].y()}),
                                 nullptr, fit.params.data());
      }
      ceres::Solver::Summary summary;
      ceres::Solve(FitSolverOptions(), &problem, &summary);
      fit.converged = summary.IsSolutionUsable();
    }
    for (size_t k = 0; k < grid.size(); ++k) {
      double ix, iy;
      if (!IdealFromMeasured<M>(fit.params.data(), grid[k].x(), grid[k].y(), &ix, &iy)) {
        fit.converged = false;
        lengths.push_back(std::numeric_limits<double>::infinity());
        continue;
      }
      lengths.push_back(std::hypot(ix - ideal_from[k].x(), iy - ideal_from[k].y()));
    }
  });
  const ResidualStats stats = Stats(lengths);
  fit.rms_residual_mm = stats.rms_mm;
  fit.max_residual_mm = stats.max_mm;
  fit.summary = fmt::format("{} fitted to {} over {:g} x {:g} mm ({} points): RMS residual {:.4f} um, max {:.4f} um{}",
                            DistortionModelName(to), DistortionModelName(from), options.format_width_mm,
                            options.format_height_mm, grid.size(), stats.rms_mm * 1e3, stats.max_mm * 1e3,
                            fit.converged ? "" : " (NOT converged)");
  return fit;
}

}  // namespace platemeter
