// Joint least-squares fit of pixel-integrated circular Gaussians (Ceres'
// TinySolver, with an analytic Jacobian) and their formal covariance.
#include <ceres/tiny_solver.h>

#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <numbers>

#include "star_internal.h"
#include "platemeter/core/angles.h"

namespace platemeter::star_internal {
namespace {


// Integral of a unit 1-D Gaussian (centre c, sigma s) over the pixel [u - 1/2, u + 1/2]
// and its derivatives with respect to c and s.
struct Profile {
  double g, dc, ds;
};
Profile PixelProfile(double u, double c, double s) {
  const double a = (u + 0.5 - c) / s, b = (u - 0.5 - c) / s;
  const double ea = std::exp(-0.5 * a * a), eb = std::exp(-0.5 * b * b);
  const double k = 1.0 / (std::sqrt(2.0 * std::numbers::pi) * s);
  Profile p;
  p.g = 0.5 * (std::erf(a * kInvSqrt2) - std::erf(b * kInvSqrt2));
  p.dc = -k * (ea - eb);
  p.ds = -k * (ea * a - eb * b);
  return p;
}

// Pixel layout of a fit: the window's integer columns and rows, so each
// star's 1-D profiles are computed once per column and row (the model is
// separable), not once per pixel.
struct Layout {
  long x0 = 0, y0 = 0, width = 0, height = 0;
  std::vector<int> col, row;  // per pixel, relative to x0, y0
  explicit Layout(const std::vector<FitPixel>& pixels) {
    if (pixels.empty()) return;
    long x1 = long(pixels[0].x_px), y1 = long(pixels[0].y_px);
    x0 = x1, y0 = y1;
    for (const FitPixel& p : pixels) {
      x0 = std::min(x0, long(p.x_px)), x1 = std::max(x1, long(p.x_px));
      y0 = std::min(y0, long(p.y_px)), y1 = std::max(y1, long(p.y_px));
    }
    width = x1 - x0 + 1, height = y1 - y0 + 1;
    for (const FitPixel& p : pixels) col.push_back(int(long(p.x_px) - x0)), row.push_back(int(long(p.y_px) - y0));
  }
};

// Parameters: offset, then per star x, y, flux, sigma (x, y relative to the reference point). The
// jacobian, when not null, is column-major with one row per pixel (TinySolver's and Eigen's layout).
void Model(const std::vector<FitPixel>& pixels, const Layout& layout, const double* p, int stars, double rx, double ry,
           double* residuals, double* jacobian) {
  const size_t rows = pixels.size();
  auto jac = [&](size_t i, int column) -> double& { return jacobian[static_cast<size_t>(column) * rows + i]; };
  std::vector<Profile> px(layout.width * stars), py(layout.height * stars);
  for (int k = 0; k < stars; ++k) {
    const double* q = p + 1 + 4 * k;
    for (long c = 0; c < layout.width; ++c) px[k * layout.width + c] = PixelProfile(layout.x0 + c - rx, q[0], q[3]);
    for (long r = 0; r < layout.height; ++r) py[k * layout.height + r] = PixelProfile(layout.y0 + r - ry, q[1], q[3]);
  }
  for (size_t i = 0; i < pixels.size(); ++i) {
    double m = p[0];
    if (jacobian) jac(i, 0) = 1.0;
    for (int k = 0; k < stars; ++k) {
      const double* q = p + 1 + 4 * k;
      const Profile& ux = px[k * layout.width + layout.col[i]];
      const Profile& uy = py[k * layout.height + layout.row[i]];
      m += q[2] * ux.g * uy.g;
      if (jacobian) {
        jac(i, 1 + 4 * k) = q[2] * ux.dc * uy.g;
        jac(i, 2 + 4 * k) = q[2] * ux.g * uy.dc;
        jac(i, 3 + 4 * k) = ux.g * uy.g;
        jac(i, 4 + 4 * k) = q[2] * (ux.ds * uy.g + ux.g * uy.ds);
      }
    }
    residuals[i] = m - pixels[i].value_dn;
  }
}

// The cost for ceres::TinySolver (a dense Levenberg-Marquardt for small
// problems without the general solver's per-call overhead). The widths are
// fitted as log(sigma), which keeps them positive. kParams is the parameter count when known at
// compile time (one star: 5, a pair: 9): TinySolver's small matrices are then fixed-size, which
// spares the general matrix product most of a star's fit time went to.
template <int kParams>
struct GaussiansCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kParams };
  const std::vector<FitPixel>& pixels;
  Layout layout;
  int stars;
  double rx, ry;
  int NumResiduals() const { return static_cast<int>(pixels.size()); }
  int NumParameters() const { return 1 + 4 * stars; }
  bool operator()(const double* parameters, double* residuals, double* jacobian) const {
    std::vector<double> p(parameters, parameters + NumParameters());
    // Widths clamped to 0.05..50 px: a wandering step cannot reach a zero width (NaN profiles).
    for (int k = 0; k < stars; ++k) p[4 + 4 * k] = std::exp(std::clamp(p[4 + 4 * k], -3.0, 3.9));
    if (!jacobian) {
      Model(pixels, layout, p.data(), stars, rx, ry, residuals, nullptr);
      return true;
    }
    Model(pixels, layout, p.data(), stars, rx, ry, residuals, jacobian);
    for (int k = 0; k < stars; ++k)  // d/d(log sigma) = sigma d/d(sigma)
      for (size_t i = 0; i < pixels.size(); ++i) jacobian[static_cast<size_t>(4 + 4 * k) * pixels.size() + i] *= p[4 + 4 * k];
    return true;
  }
};

// Levenberg-Marquardt from *x; false when it ran out of iterations.
template <int kParams>
bool SolveGaussians(const GaussiansCost<kParams>& cost, Eigen::VectorXd* x, double* final_cost) {
  using Solver = ceres::TinySolver<GaussiansCost<kParams>>;
  Solver solver;
  solver.options.max_num_iterations = 50;
  solver.options.function_tolerance = 1e-9;
  solver.options.parameter_tolerance = 1e-9;
  typename Solver::Parameters parameters = *x;
  const auto& summary = solver.Solve(cost, &parameters);
  *x = parameters;
  *final_cost = summary.final_cost;
  return summary.status != Solver::HIT_MAX_ITERATIONS;
}

}  // namespace

GaussianFitResult FitGaussians(const std::vector<FitPixel>& pixels, std::vector<FittedGaussian> stars,
                               double noise_sigma_dn, double min_sigma_px) {
  GaussianFitResult r;
  const int k = static_cast<int>(stars.size());
  const int np = 1 + 4 * k;
  r.pixels = static_cast<int>(pixels.size());
  if (k == 0 || r.pixels <= np + 2) return r;
  const double rx = stars[0].x_px, ry = stars[0].y_px;
  std::vector<double> p(np, 0.0);
  for (int i = 0; i < k; ++i) {
    p[1 + 4 * i] = stars[i].x_px - rx;
    p[2 + 4 * i] = stars[i].y_px - ry;
    p[3 + 4 * i] = stars[i].flux_dn;
    p[4 + 4 * i] = std::max(stars[i].sigma_px, min_sigma_px * 1.01);
  }
  Eigen::VectorXd x(np);
  for (int i = 0; i < np; ++i) x(i) = p[i];
  for (int i = 0; i < k; ++i) x(4 + 4 * i) = std::log(p[4 + 4 * i]);
  const Layout layout(pixels);
  double final_cost = 0.0;
  if (k == 1) {
    r.converged = SolveGaussians(GaussiansCost<5>{pixels, layout, k, rx, ry}, &x, &final_cost);
  } else if (k == 2) {
    r.converged = SolveGaussians(GaussiansCost<9>{pixels, layout, k, rx, ry}, &x, &final_cost);
  } else {
    r.converged = SolveGaussians(GaussiansCost<Eigen::Dynamic>{pixels, layout, k, rx, ry}, &x, &final_cost);
  }
  if (!std::isfinite(final_cost) || !x.allFinite()) {
    r.converged = false;
    return r;
  }
  for (int i = 0; i < np; ++i) p[i] = x(i);
  for (int i = 0; i < k; ++i) p[4 + 4 * i] = std::exp(std::clamp(x(4 + 4 * i), -3.0, 3.9));
  std::vector<double> res(pixels.size());
  Eigen::MatrixXd j(pixels.size(), np);
  Model(pixels, layout, p.data(), k, rx, ry, res.data(), j.data());
  double rss = 0;
  for (double e : res) rss += e * e;
  r.residual_sigma_dn = std::sqrt(rss / (pixels.size() - np));
  r.chi2 = rss / (noise_sigma_dn * noise_sigma_dn);
  r.offset_dn = p[0];
  // Formal covariance scaled by the fit's own residual variance.
  const Eigen::MatrixXd n = j.transpose() * j;
  const Eigen::MatrixXd cov = n.ldlt().solve(Eigen::MatrixXd::Identity(np, np)) * (r.residual_sigma_dn * r.residual_sigma_dn);
  for (int i = 0; i < k; ++i) {
    FittedGaussian& s = stars[i];
    const int o = 1 + 4 * i;
    s.x_px = p[o] + rx;
    s.y_px = p[o + 1] + ry;
    s.flux_dn = p[o + 2];
    s.sigma_px = p[o + 3];
    s.sigma_x_px = std::sqrt(std::max(0.0, cov(o, o)));
    s.sigma_y_px = std::sqrt(std::max(0.0, cov(o + 1, o + 1)));
    s.correlation_xy = (s.sigma_x_px > 0 && s.sigma_y_px > 0) ? cov(o, o + 1) / (s.sigma_x_px * s.sigma_y_px) : 0.0;
    s.sigma_flux_dn = std::sqrt(std::max(0.0, cov(o + 2, o + 2)));
  }
  r.stars = std::move(stars);
  return r;
}

}  // namespace platemeter::star_internal
