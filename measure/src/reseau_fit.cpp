// The fit of the measured reseau to the master grid (reseau_fit.h).
#include "platemeter/measure/reseau_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <iterator>
#include <cmath>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

int ParameterCount(ReseauFitModel model) {
  switch (model) {
    case ReseauFitModel::kSimilarity: return 4;
    case ReseauFitModel::kAffine: return 6;
    case ReseauFitModel::kScales: return 6;
    case ReseauFitModel::kProjective: return 8;
  }
  return 8;
}

// F(g) for any scalar type (doubles and Ceres jets).
template <typename T>
void Model(ReseauFitModel model, const T* p, const T& gx, const T& gy, T* mx, T* my) {
  using std::cos;
  using std::sin;
  using std::tan;
  switch (model) {
    case ReseauFitModel::kSimilarity: {
      const T c = p[2] * cos(p[3]), s = p[2] * sin(p[3]);
      *mx = p[0] + c * gx - s * gy;
      *my = p[1] + s * gx + c * gy;
      return;
    }
    case ReseauFitModel::kAffine:
      *mx = p[0] + p[2] * gx + p[3] * gy;
      *my = p[1] + p[4] * gx + p[5] * gy;
      return;
    case ReseauFitModel::kScales: {
      const T ax = cos(p[4]) * gx - sin(p[4]) * gy, ay = sin(p[4]) * gx + cos(p[4]) * gy;
      *mx = p[0] + p[2] * (ax + tan(p[5]) * ay);
      *my = p[1] + p[3] * ay / cos(p[5]);
      return;
    }
    case ReseauFitModel::kProjective: {
      const T w = T(1.0) + p[6] * gx + p[7] * gy;
      *mx = (p[0] + p[2] * gx + p[3] * gy) / w;
      *my = (p[1] + p[4] * gx + p[5] * gy) / w;
      return;
    }
  }
}

// The linear part dF/dg at the grid origin, for any scalar type.
template <typename T>
void LinearPart(ReseauFitModel model, const T* p, T* a) {
  using Jet = ceres::Jet<T, 2>;
  Jet q[8];
  for (int i = 0; i < 8; ++i) q[i] = Jet(p[i]);
  Jet mx, my;
  Model(model, q, Jet(T(0.0), 0), Jet(T(0.0), 1), &mx, &my);
  a[0] = mx.v[0]; a[1] = mx.v[1]; a[2] = my.v[0]; a[3] = my.v[1];
}

// One cross: whitened residual L^-1 (m - F(g)), L L^T = cov.
struct CrossResidual {
  ReseauFitModel model;
  double gx, gy, mx, my;
  double w[4];  // L^-1, row-major lower triangular
  template <typename T>
  bool operator()(const T* p, T* r) const {
    T fx, fy;
    Model(model, p, T(gx), T(gy), &fx, &fy);
    const T dx = T(mx) - fx, dy = T(my) - fy;
    r[0] = w[0] * dx;
    r[1] = w[2] * dx + w[3] * dy;
    return true;
  }
};

void Whitening(const Covariance2& c, double min_sigma, double w[4]) {
  const double v = min_sigma * min_sigma;
  Eigen::Matrix2d m;
  m << std::max(c.xx, v), c.xy, c.xy, std::max(c.yy, v);
  if (m.determinant() <= 0.0) m = Eigen::Vector2d(m(0, 0), m(1, 1)).asDiagonal();
  const Eigen::Matrix2d l_inv = Eigen::Matrix2d(m.llt().matrixL()).inverse();
  w[0] = l_inv(0, 0); w[1] = 0.0; w[2] = l_inv(1, 0); w[3] = l_inv(1, 1);
}

// Start values from a linear affine least-squares fit.
void StartValues(ReseauFitModel model, const std::vector<ReseauObservation>& obs, const std::vector<bool>& rejected,
                 double p[8]) {
  Eigen::MatrixXd a(2 * obs.size(), 6);
  Eigen::VectorXd b(2 * obs.size());
  a.setZero();
  b.setZero();
  for (size_t i = 0; i < obs.size(); ++i) {
    if (rejected[i]) continue;
    a.row(2 * i) << 1, 0, obs[i].grid_x_mm, obs[i].grid_y_mm, 0, 0;
    a.row(2 * i + 1) << 0, 1, 0, 0, obs[i].grid_x_mm, obs[i].grid_y_mm;
    b(2 * i) = obs[i].measured.x;
    b(2 * i + 1) = obs[i].measured.y;
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
  std::fill(p, p + 8, 0.0);
  p[0] = x(0);
  p[1] = x(1);
  const double lin[4] = {x(2), x(3), x(4), x(5)};
  switch (model) {
    case ReseauFitModel::kSimilarity:
      p[2] = std::sqrt(std::abs(lin[0] * lin[3] - lin[1] * lin[2]));
      p[3] = std::atan2(lin[2] - lin[1], lin[0] + lin[3]);
      break;
    case ReseauFitModel::kAffine:
    case ReseauFitModel::kProjective:
      std::copy(lin, lin + 4, p + 2);
      break;
    case ReseauFitModel::kScales: {
      double d[4];
      DecomposeScalesNonOrthogonality(lin, d);
      p[2] = d[0]; p[3] = d[1]; p[5] = d[2]; p[4] = d[3];
      break;
    }
  }
}

struct Solution {
  double p[8];
  Eigen::MatrixXd covariance;  // parameter_count x parameter_count (unscaled)
  double chi2 = 0.0;
};

Solution Solve(ReseauFitModel model, const std::vector<ReseauObservation>& obs, const std::vector<bool>& rejected,
               const ReseauFitOptions& options) {
  Solution s;
  StartValues(model, obs, rejected, s.p);
  const int n = ParameterCount(model);
  ceres::Problem problem;
  for (size_t i = 0; i < obs.size(); ++i) {
    if (rejected[i]) continue;
    auto* f = new CrossResidual{model, obs[i].grid_x_mm, obs[i].grid_y_mm, obs[i].measured.x, obs[i].measured.y, {}};
    Whitening(obs[i].measured.cov, options.min_sigma_mm, f->w);
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CrossResidual, 2, 8>(f), nullptr, s.p);
  }
  if (n < 8) {
    std::vector<int> fixed;
    for (int k = n; k < 8; ++k) fixed.push_back(k);
    problem.SetManifold(s.p, new ceres::SubsetManifold(8, fixed));
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 100;
  solver.function_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    throw Error("reseau fit", "the " + std::string(ReseauFitModelName(model)) +
                                  " fit failed (" + OneLine(summary.message) + "): the crosses do not fit the grid");
  }
  // Covariance (J^T J)^-1 in the free parameters; the Jacobian comes back in
  // the manifold's tangent space, i.e. exactly the free parameters.
  double cost = 0.0;
  ceres::CRSMatrix crs;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, &crs) ||
      crs.num_cols != n || !std::isfinite(cost)) {
    throw Error("reseau fit", "the fit's residuals or Jacobian are not finite: the crosses do not fit the grid");
  }
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) j(r, crs.cols[k]) = crs.values[k];
  }
  const Eigen::LDLT<Eigen::MatrixXd> normal((j.transpose() * j).eval());
  s.covariance = normal.solve(Eigen::MatrixXd::Identity(n, n));
  if (normal.info() != Eigen::Success || !s.covariance.allFinite() || (s.covariance.diagonal().array() <= 0.0).any()) {
    throw Error("reseau fit", "the " + std::string(ReseauFitModelName(model)) +
                                  " model is not determined by the crosses used (singular normal equations)");
  }
  s.chi2 = 2.0 * cost;
  return s;
}

}  // namespace

const char* ReseauFitModelName(ReseauFitModel model) {
  switch (model) {
    case ReseauFitModel::kSimilarity: return "similarity";
    case ReseauFitModel::kAffine: return "affine";
    case ReseauFitModel::kScales: return "scales";
    case ReseauFitModel::kProjective: return "projective";
  }
  return "?";
}

bool ParseReseauFitModel(const std::string& name, ReseauFitModel* model) {
  for (ReseauFitModel m : {ReseauFitModel::kSimilarity, ReseauFitModel::kAffine, ReseauFitModel::kScales,
                           ReseauFitModel::kProjective}) {
    if (name == ReseauFitModelName(m)) {
      *model = m;
      return true;
    }
  }
  return false;
}

bool ReseauFitOptions::Check(std::string* why) const {
  if (!(rejection_threshold > 1.0)) {
    if (why) *why = "reseau fit rejection_threshold must exceed 1";
    return false;
  }
  if (!(min_sigma_mm > 0.0) || max_rejected < 0) {
    if (why) *why = "reseau fit min_sigma_mm must be positive and max_rejected non-negative";
    return false;
  }
  return true;
}

void DecomposeScalesNonOrthogonality(const double a[4], double out[4]) {
  // Row 2 = (sy / cos eps)(sin theta, cos theta); row 1 R^T = sx (1, tan eps).
  const double theta = std::atan2(a[2], a[3]);
  const double c = std::cos(theta), s = std::sin(theta);
  const double sx = a[0] * c - a[1] * s;
  const double eps = std::atan((a[0] * s + a[1] * c) / sx);  // sx < 0 for a mirrored frame
  out[0] = sx;
  out[1] = std::hypot(a[2], a[3]) * std::cos(eps);
  out[2] = eps;
  out[3] = theta;
}

std::vector<std::string> ReseauFit::ParameterNames() const {
  switch (model) {
    case ReseauFitModel::kSimilarity: return {"tx_mm", "ty_mm", "scale", "rotation_rad"};
    case ReseauFitModel::kAffine: return {"tx_mm", "ty_mm", "a", "b", "c", "d"};
    case ReseauFitModel::kScales: return {"tx_mm", "ty_mm", "scale_x", "scale_y", "rotation_rad", "non_orthogonality_rad"};
    case ReseauFitModel::kProjective: return {"tx_mm", "ty_mm", "a", "b", "c", "d", "h1_per_mm", "h2_per_mm"};
  }
  return {};
}

void ReseauFit::Forward(double gx, double gy, double* mx, double* my) const {
  Model(model, parameters, gx, gy, mx, my);
}

PlanePoint ReseauFit::ToGrid(const PlanePoint& measured) const {
  // Start from the inverse of the linear part, then Newton (exact for the linear models).
  double a[4];
  LinearPart(model, parameters, a);
  Eigen::Matrix2d lin;
  lin << a[0], a[1], a[2], a[3];
  Eigen::Vector2d g = lin.inverse() * Eigen::Vector2d(measured.x - parameters[0], measured.y - parameters[1]);
  Eigen::Matrix2d jf;
  for (int it = 0; it < 20; ++it) {
    using Jet = ceres::Jet<double, 2>;
    Jet q[8];
    for (int i = 0; i < 8; ++i) q[i] = Jet(parameters[i]);
    Jet mx, my;
    Model(model, q, Jet(g(0), 0), Jet(g(1), 1), &mx, &my);
    jf << mx.v[0], mx.v[1], my.v[0], my.v[1];
    const Eigen::Vector2d step = jf.inverse() * Eigen::Vector2d(measured.x - mx.a, measured.y - my.a);
    g += step;
    if (step.norm() < 1e-13) break;
  }
  const Eigen::Matrix2d inv = jf.inverse();
  const double j[4] = {inv(0, 0), inv(0, 1), inv(1, 0), inv(1, 1)};
  return {g(0), g(1), measured.cov.Transformed(j)};
}

ReseauFit FitReseau(const std::vector<ReseauObservation>& observations, const ReseauFitOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("reseau fit", why);
  for (const ReseauObservation& o : observations) {
    const double values[] = {o.grid_x_mm, o.grid_y_mm, o.measured.x, o.measured.y, o.measured.cov.xx,
                             o.measured.cov.xy, o.measured.cov.yy};
    if (!std::all_of(std::begin(values), std::end(values), [](double v) { return std::isfinite(v); })) {
      throw Error("reseau fit", "cross " + o.id + " has a non-finite position or covariance");
    }
  }
  const int n = ParameterCount(options.model);
  std::vector<bool> rejected(observations.size(), false);
  ReseauFit fit;
  fit.model = options.model;
  fit.parameter_count = n;
  for (;;) {
    const int used = static_cast<int>(std::count(rejected.begin(), rejected.end(), false));
    if (2 * used <= n) {
      throw Error("reseau fit", "the " + std::string(ReseauFitModelName(options.model)) + " model needs more than " +
                                    std::to_string(n / 2) + " crosses, " + std::to_string(used) + " usable");
    }
    const Solution s = Solve(options.model, observations, rejected, options);
    std::copy(s.p, s.p + 8, fit.parameters);
    fit.sigma0 = std::sqrt(s.chi2 / std::max(1, 2 * used - n));
    const double factor = options.scale_by_variance_factor ? std::max(1.0, fit.sigma0 * fit.sigma0) : 1.0;
    std::fill(fit.covariance, fit.covariance + 64, 0.0);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) fit.covariance[8 * r + c] = s.covariance(r, c) * factor;
    }
    // The worst normalized residual among the used crosses.
    int worst = -1;
    double worst_value = 0.0;
    for (size_t i = 0; i < observations.size(); ++i) {
      if (rejected[i]) continue;
      double w[4];
      Whitening(observations[i].measured.cov, options.min_sigma_mm, w);
      double fx, fy;
      fit.Forward(observations[i].grid_x_mm, observations[i].grid_y_mm, &fx, &fy);
      const double dx = observations[i].measured.x - fx, dy = observations[i].measured.y - fy;
      const double v = std::hypot(w[0] * dx, w[2] * dx + w[3] * dy) / std::max(1.0, fit.sigma0);
      if (v > worst_value) {
        worst_value = v;
        worst = static_cast<int>(i);
      }
    }
    const int n_rejected = static_cast<int>(observations.size()) - used;
    if (worst < 0 || worst_value <= options.rejection_threshold || n_rejected >= options.max_rejected ||
        2 * (used - 1) <= n) {
      fit.used = used;
      fit.rejected = n_rejected;
      break;
    }
    rejected[worst] = true;
  }
  fit.is_rejected = rejected;
  double sum2 = 0.0;
  for (size_t i = 0; i < observations.size(); ++i) {
    const PlanePoint g = fit.ToGrid(observations[i].measured);
    fit.residual_x_mm.push_back(observations[i].grid_x_mm - g.x);
    fit.residual_y_mm.push_back(observations[i].grid_y_mm - g.y);
    if (!rejected[i]) sum2 += fit.residual_x_mm.back() * fit.residual_x_mm.back() + fit.residual_y_mm.back() * fit.residual_y_mm.back();
  }
  fit.rms_mm = std::sqrt(sum2 / std::max(1, 2 * fit.used));
  // The decomposed linear part and its sigmas: d(decomposition)/d(parameters)
  // by central differences (the decomposition is smooth), then J C J^T.
  auto decomposed = [&](const double* p, double out[4]) {
    double a[4];
    LinearPart(fit.model, p, a);
    DecomposeScalesNonOrthogonality(a, out);
  };
  double d0[4];
  decomposed(fit.parameters, d0);
  Eigen::Matrix<double, 4, 8> jac = Eigen::Matrix<double, 4, 8>::Zero();
  for (int k = 0; k < n; ++k) {
    const double h = 1e-7 * std::max(1.0, std::abs(fit.parameters[k]));
    double pp[8], pm[8], dp[4], dm[4];
    std::copy(fit.parameters, fit.parameters + 8, pp);
    std::copy(fit.parameters, fit.parameters + 8, pm);
    pp[k] += h;
    pm[k] -= h;
    decomposed(pp, dp);
    decomposed(pm, dm);
    for (int r = 0; r < 4; ++r) jac(r, k) = (dp[r] - dm[r]) / (2 * h);
  }
  const Eigen::Matrix<double, 8, 8> cov = Eigen::Map<const Eigen::Matrix<double, 8, 8, Eigen::RowMajor>>(fit.covariance);
  const Eigen::Matrix4d cd = jac * cov * jac.transpose();
  fit.scale_x = {d0[0], std::sqrt(cd(0, 0))};
  fit.scale_y = {d0[1], std::sqrt(cd(1, 1))};
  fit.non_orthogonality_rad = {d0[2], std::sqrt(cd(2, 2))};
  fit.rotation_rad = {d0[3], std::sqrt(cd(3, 3))};
  fit.mean_scale = {0.5 * (d0[0] + d0[1]), 0.5 * std::sqrt(cd(0, 0) + cd(1, 1) + 2.0 * cd(0, 1))};
  return fit;
}

}  // namespace platemeter
