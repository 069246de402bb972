// Least-squares fit of one straight segment image: a circular Gaussian PSF
// swept uniformly along a segment (a dash or long dot of a duty-cycle trail),
// plus a constant (Ceres' TinySolver, analytic Jacobian). Pixel integration is
// approximated by adding a pixel's variance (1/12 px^2) to the PSF's; the
// centre is unbiased by symmetry, only the width absorbs the approximation.
#include <ceres/tiny_solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "star_internal.h"
#include "platemeter/core/angles.h"

namespace platemeter::star_internal {
namespace {

constexpr double kMinHalfLength = 0.05;  // px; below this the segment is a point (the model's limit is smooth)

// The unit-flux profile of a segment (half length h, PSF sigma widened by the pixel: se) at a pixel a along
// and b across it from its centre, and the parts of it the derivatives need.
struct SegmentProfile {
  double A, B, Pr, phiA, phiB, nb, shape;
  SegmentProfile(double a, double b, double h, double se, double se2) {
    A = (a + h) / se, B = (a - h) / se;
    Pr = 0.5 * (std::erf(A * kInvSqrt2) - std::erf(B * kInvSqrt2));
    phiA = kInvSqrt2Pi * std::exp(-0.5 * A * A), phiB = kInvSqrt2Pi * std::exp(-0.5 * B * B);
    nb = kInvSqrt2Pi / se * std::exp(-0.5 * b * b / se2);
    shape = nb * Pr / (2.0 * h);
  }
  double DShapeDa(double h, double se) const { return nb / (2.0 * h) * (phiA - phiB) / se; }
  double DShapeDb(double b, double se2) const { return shape * (-b / se2); }
};

// Parameters: offset, cx, cy (relative to the reference point), angle, half length, flux, log sigma;
// with a point (P = 10): its x, y (relative) and flux, its width the segment's.
template <int P>
struct SegmentCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = P };
  const std::vector<FitPixel>& pixels;
  double rx, ry;
  int NumResiduals() const { return static_cast<int>(pixels.size()); }
  bool operator()(const double* p, double* residuals, double* jacobian) const {
    const double c = std::cos(p[3]), s = std::sin(p[3]);
    const double h = std::max(std::abs(p[4]), kMinHalfLength), hsign = p[4] < 0 ? -1.0 : 1.0;
    const double sigma = std::exp(std::clamp(p[6], -3.0, 3.9));
    const double se2 = sigma * sigma + 1.0 / 12.0, se = std::sqrt(se2);
    const double flux = p[5];
    const long n = static_cast<long>(pixels.size());
    for (long i = 0; i < n; ++i) {
      const double du = pixels[i].x_px - rx - p[1], dv = pixels[i].y_px - ry - p[2];
      const double a = du * c + dv * s, b = -du * s + dv * c;
      const SegmentProfile g(a, b, h, se, se2);
      const double A = g.A, B = g.B, Pr = g.Pr, phiA = g.phiA, phiB = g.phiB, nb = g.nb, shape = g.shape;
      residuals[i] = p[0] + flux * shape - pixels[i].value_dn;
      if (!jacobian) continue;
      const double dm_da = flux * g.DShapeDa(h, se);
      const double dm_db = flux * g.DShapeDb(b, se2);
      const double dm_dh = flux * nb * ((phiA + phiB) / se / (2.0 * h) - Pr / (2.0 * h * h));
      const double dnb_dse = nb * (b * b / (se2 * se) - 1.0 / se);
      const double dP_dse = -(phiA * A - phiB * B) / se;
      const double dm_dse = flux / (2.0 * h) * (dnb_dse * Pr + nb * dP_dse);
      // Column-major n x 7.
      jacobian[0 * n + i] = 1.0;
      jacobian[1 * n + i] = dm_da * (-c) + dm_db * s;
      jacobian[2 * n + i] = dm_da * (-s) + dm_db * (-c);
      jacobian[3 * n + i] = dm_da * b + dm_db * (-a);
      jacobian[4 * n + i] = std::abs(p[4]) < kMinHalfLength ? 0.0 : dm_dh * hsign;
      jacobian[5 * n + i] = shape;
      jacobian[6 * n + i] = dm_dse * sigma * sigma / se;  // d se / d log sigma = sigma^2 / se
    }
    if constexpr (P == 10) {
      for (long i = 0; i < n; ++i) {
        const double du = pixels[i].x_px - rx - p[7], dv = pixels[i].y_px - ry - p[8];
        const double g = kInvSqrt2Pi * kInvSqrt2Pi / se2 * std::exp(-0.5 * (du * du + dv * dv) / se2);
        residuals[i] += p[9] * g;
        if (!jacobian) continue;
        jacobian[7 * n + i] = p[9] * g * du / se2;
        jacobian[8 * n + i] = p[9] * g * dv / se2;
        jacobian[9 * n + i] = g;
        const double dg_dse = g * ((du * du + dv * dv) / (se2 * se) - 2.0 / se);
        jacobian[6 * n + i] += p[9] * dg_dse * sigma * sigma / se;
      }
    }
    return true;
  }
};

// A segment of known shape (angle, half length, PSF sigma): parameters offset, cx, cy (relative to the
// reference point), flux.
struct PlacedSegmentCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = 4 };
  const std::vector<FitPixel>& pixels;
  double rx, ry, c, s, h, se, se2;
  int NumResiduals() const { return static_cast<int>(pixels.size()); }
  bool operator()(const double* p, double* residuals, double* jacobian) const {
    const long n = static_cast<long>(pixels.size());
    for (long i = 0; i < n; ++i) {
      const double du = pixels[i].x_px - rx - p[1], dv = pixels[i].y_px - ry - p[2];
      const double a = du * c + dv * s, b = -du * s + dv * c;
      const SegmentProfile g(a, b, h, se, se2);
      residuals[i] = p[0] + p[3] * g.shape - pixels[i].value_dn;
      if (!jacobian) continue;
      const double dm_da = p[3] * g.DShapeDa(h, se), dm_db = p[3] * g.DShapeDb(b, se2);
      jacobian[0 * n + i] = 1.0;
      jacobian[1 * n + i] = dm_da * (-c) + dm_db * s;
      jacobian[2 * n + i] = dm_da * (-s) + dm_db * (-c);
      jacobian[3 * n + i] = g.shape;
    }
    return true;
  }
};

}  // namespace

namespace {

// Runs the solver on `cost` from *x (parameter 0: the constant) over n_pixels pixels; fills r's convergence,
// residual sigma, chi^2 and offset and returns the parameters' covariance scaled by the residual variance
// (empty when the solve failed).
template <class Cost, int P>
Eigen::MatrixXd RunFit(const Cost& cost, Eigen::Matrix<double, P, 1>* x, size_t n_pixels, double noise_sigma_dn,
                       SegmentFitResult* r) {
  ceres::TinySolver<Cost> solver;
  solver.options.max_num_iterations = 60;
  solver.options.function_tolerance = 1e-10;
  solver.options.parameter_tolerance = 1e-10;
  const auto& summary = solver.Solve(cost, x);
  if (!std::isfinite(summary.final_cost) || !x->allFinite()) return {};
  r->converged = summary.status != decltype(solver)::HIT_MAX_ITERATIONS;
  std::vector<double> res(n_pixels);
  Eigen::MatrixXd j(n_pixels, P);
  cost(x->data(), res.data(), j.data());
  double rss = 0;
  for (double e : res) rss += e * e;
  r->residual_sigma_dn = std::sqrt(rss / (n_pixels - P));
  r->chi2 = rss / (noise_sigma_dn * noise_sigma_dn);
  r->offset_dn = (*x)(0);
  const Eigen::MatrixXd n = j.transpose() * j;
  return n.ldlt().solve(Eigen::MatrixXd::Identity(P, P)) * (r->residual_sigma_dn * r->residual_sigma_dn);
}

// Formal sigmas of the parameters i (x) and i + 1 (y) and their correlation.
void PositionSigmas(const Eigen::MatrixXd& cov, int i, double* sigma_x_px, double* sigma_y_px, double* correlation) {
  *sigma_x_px = std::sqrt(std::max(0.0, cov(i, i)));
  *sigma_y_px = std::sqrt(std::max(0.0, cov(i + 1, i + 1)));
  *correlation = (*sigma_x_px > 0 && *sigma_y_px > 0) ? cov(i, i + 1) / (*sigma_x_px * *sigma_y_px) : 0.0;
}

template <int P>
SegmentFitResult Solve(const std::vector<FitPixel>& pixels, const FittedSegment& start, const FittedPoint* point,
                       double noise_sigma_dn) {
  SegmentFitResult r;
  r.pixels = static_cast<int>(pixels.size());
  if (r.pixels <= P + 2) return r;
  const double rx = start.x_px, ry = start.y_px;
  const SegmentCost<P> cost{pixels, rx, ry};
  Eigen::Matrix<double, P, 1> x;
  x(0) = 0.0, x(1) = 0.0, x(2) = 0.0, x(3) = start.angle_rad;
  x(4) = std::max(0.5 * start.length_px, 2 * kMinHalfLength);
  x(5) = start.flux_dn, x(6) = std::log(start.sigma_px);
  if constexpr (P == 10) x(7) = point->x_px - rx, x(8) = point->y_px - ry, x(9) = point->flux_dn;
  const Eigen::MatrixXd cov = RunFit(cost, &x, pixels.size(), noise_sigma_dn, &r);
  if (cov.size() == 0) return r;
  FittedSegment& s = r.segment;
  s.x_px = rx + x(1);
  s.y_px = ry + x(2);
  s.angle_rad = std::remainder(x(3), std::numbers::pi);
  s.length_px = 2.0 * std::max(std::abs(x(4)), kMinHalfLength);
  s.flux_dn = x(5);
  s.sigma_px = std::exp(std::clamp(x(6), -3.0, 3.9));
  PositionSigmas(cov, 1, &s.sigma_x_px, &s.sigma_y_px, &s.correlation_xy);
  s.sigma_flux_dn = std::sqrt(std::max(0.0, cov(5, 5)));
  s.sigma_length_px = 2.0 * std::sqrt(std::max(0.0, cov(4, 4)));
  if constexpr (P == 10) {
    FittedPoint& q = r.point;
    q.x_px = rx + x(7), q.y_px = ry + x(8), q.flux_dn = x(9);
    PositionSigmas(cov, 7, &q.sigma_x_px, &q.sigma_y_px, &q.correlation_xy);
    q.sigma_flux_dn = std::sqrt(std::max(0.0, cov(9, 9)));
    r.has_point = true;
  }
  r.ok = true;
  return r;
}

}  // namespace

SegmentFitResult FitSegment(const std::vector<FitPixel>& pixels, const FittedSegment& start, double noise_sigma_dn) {
  return Solve<7>(pixels, start, nullptr, noise_sigma_dn);
}

SegmentFitResult FitSegmentAndPoint(const std::vector<FitPixel>& pixels, const FittedSegment& start,
                                    const FittedPoint& point, double noise_sigma_dn) {
  return Solve<10>(pixels, start, &point, noise_sigma_dn);
}

SegmentFitResult FitPlacedSegment(const std::vector<FitPixel>& pixels, const FittedSegment& start,
                                  double noise_sigma_dn) {
  SegmentFitResult r;
  r.pixels = static_cast<int>(pixels.size());
  if (r.pixels <= 4 + 2) return r;
  const double h = std::max(0.5 * start.length_px, kMinHalfLength);
  const double se2 = start.sigma_px * start.sigma_px + 1.0 / 12.0;
  const PlacedSegmentCost cost{pixels, start.x_px, start.y_px, std::cos(start.angle_rad), std::sin(start.angle_rad),
                               h, std::sqrt(se2), se2};
  Eigen::Vector4d x(0.0, 0.0, 0.0, start.flux_dn);
  const Eigen::MatrixXd cov = RunFit(cost, &x, pixels.size(), noise_sigma_dn, &r);
  if (cov.size() == 0) return r;
  FittedSegment& s = r.segment;
  s = start;
  s.x_px = start.x_px + x(1);
  s.y_px = start.y_px + x(2);
  s.flux_dn = x(3);
  PositionSigmas(cov, 1, &s.sigma_x_px, &s.sigma_y_px, &s.correlation_xy);
  s.sigma_flux_dn = std::sqrt(std::max(0.0, cov(3, 3)));
  s.sigma_length_px = 0.0;
  r.ok = true;
  return r;
}

double SegmentModel(const FittedSegment& s, double x_px, double y_px) {
  const double c = std::cos(s.angle_rad), sn = std::sin(s.angle_rad);
  const double h = std::max(0.5 * s.length_px, kMinHalfLength);
  const double se2 = s.sigma_px * s.sigma_px + 1.0 / 12.0, se = std::sqrt(se2);
  const double du = x_px - s.x_px, dv = y_px - s.y_px;
  const double a = du * c + dv * sn, b = -du * sn + dv * c;
  const double P = 0.5 * (std::erf((a + h) / se * kInvSqrt2) - std::erf((a - h) / se * kInvSqrt2));
  return s.flux_dn * kInvSqrt2Pi / se * std::exp(-0.5 * b * b / se2) * P / (2.0 * h);
}

}  // namespace platemeter::star_internal
