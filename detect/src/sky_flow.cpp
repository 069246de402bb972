// The plate's diurnal flow: polynomial velocity field, Runge-Kutta transport (sky_flow.h).
#include "platemeter/detect/sky_flow.h"

#include <algorithm>
#include <cmath>

namespace platemeter {

Eigen::VectorXd SkyFlow::Basis(const PixelPoint& p) const {
  const double u = (p.x_px - centre_.x_px) / scale_px_, v = (p.y_px - centre_.y_px) / scale_px_;
  Eigen::VectorXd b((degree_ + 1) * (degree_ + 2) / 2);
  int k = 0;
  double ui = 1.0;
  for (int i = 0; i <= degree_; ++i, ui *= u) {
    double vj = 1.0;
    for (int j = 0; i + j <= degree_; ++j, vj *= v) b(k++) = ui * vj;
  }
  return b;
}

bool SkyFlow::Fit(const std::vector<PixelPoint>& p, const std::vector<PixelPoint>& velocity_px_per_s, int degree) {
  ok_ = false;
  degree_ = std::max(1, degree);
  const int n = static_cast<int>(p.size()), terms = (degree_ + 1) * (degree_ + 2) / 2;
  if (n < 3 * terms || velocity_px_per_s.size() != p.size()) return false;
  double x0 = p[0].x_px, x1 = x0, y0 = p[0].y_px, y1 = y0;
  for (const PixelPoint& q : p) x0 = std::min(x0, q.x_px), x1 = std::max(x1, q.x_px), y0 = std::min(y0, q.y_px), y1 = std::max(y1, q.y_px);
  centre_ = {0.5 * (x0 + x1), 0.5 * (y0 + y1)};
  scale_px_ = std::max(1.0, 0.5 * std::max(x1 - x0, y1 - y0));  // u, v in [-1, 1]: a well-conditioned basis
  Eigen::MatrixXd a(n, terms);
  for (int i = 0; i < n; ++i) a.row(i) = Basis(p[i]).transpose();
  std::vector<bool> keep(n, true);
  for (int round = 0; round < 8; ++round) {
    std::vector<int> rows;
    for (int i = 0; i < n; ++i)
      if (keep[i]) rows.push_back(i);
    const int m = static_cast<int>(rows.size());
    if (m < 3 * terms) return false;
    Eigen::MatrixXd am(m, terms);
    Eigen::VectorXd bx(m), by(m);
    for (int r = 0; r < m; ++r) am.row(r) = a.row(rows[r]), bx(r) = velocity_px_per_s[rows[r]].x_px, by(r) = velocity_px_per_s[rows[r]].y_px;
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(am);
    if (qr.rank() < terms) return false;
    ax_ = qr.solve(bx), ay_ = qr.solve(by);
    // Robust spread of the residuals over all samples (per axis, from the median length of the 2D residual).
    std::vector<double> r(n), sorted;
    for (int i = 0; i < n; ++i) {
      const Eigen::VectorXd b = a.row(i).transpose();
      r[i] = std::hypot(b.dot(ax_) - velocity_px_per_s[i].x_px, b.dot(ay_) - velocity_px_per_s[i].y_px);
      if (keep[i]) sorted.push_back(r[i]);
    }
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    // |r| of a 2D Gaussian with sigma s per axis has the median s sqrt(2 ln 2) = 1.1774 s.
    residual_px_per_s_ = sorted[sorted.size() / 2] / 1.1774;
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      const bool k = r[i] <= 5.0 * residual_px_per_s_ + 1e-12;
      changed |= k != keep[i];
      keep[i] = k;
    }
    samples_used_ = m;
    if (!changed) break;
  }
  ok_ = ax_.allFinite() && ay_.allFinite();
  return ok_;
}

PixelPoint SkyFlow::Velocity(const PixelPoint& p) const {
  // Basis(p) dotted with the coefficients without allocating it (the transport calls this millions of times).
  const double u = (p.x_px - centre_.x_px) / scale_px_, v = (p.y_px - centre_.y_px) / scale_px_;
  double vx = 0, vy = 0, ui = 1.0;
  int k = 0;
  for (int i = 0; i <= degree_; ++i, ui *= u) {
    double b = ui;
    for (int j = 0; i + j <= degree_; ++j, b *= v, ++k) vx += b * ax_(k), vy += b * ay_(k);
  }
  return {vx, vy};
}

PixelPoint SkyFlow::Carry(const PixelPoint& p, double dt_s, double step_s) const {
  const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(dt_s) / step_s)));
  const double h = dt_s / steps;
  PixelPoint q = p;
  auto add = [](const PixelPoint& a, const PixelPoint& v, double s) { return PixelPoint{a.x_px + s * v.x_px, a.y_px + s * v.y_px}; };
  for (int k = 0; k < steps; ++k) {
    const PixelPoint k1 = Velocity(q), k2 = Velocity(add(q, k1, h / 2)), k3 = Velocity(add(q, k2, h / 2)),
                     k4 = Velocity(add(q, k3, h));
    q = {q.x_px + h / 6 * (k1.x_px + 2 * k2.x_px + 2 * k3.x_px + k4.x_px),
         q.y_px + h / 6 * (k1.y_px + 2 * k2.y_px + 2 * k3.y_px + k4.y_px)};
  }
  return q;
}

FlowPath::FlowPath(const SkyFlow& flow, const PixelPoint& p, double span_s, double step_s,
                   const std::function<bool(const PixelPoint&)>& inside)
    : span_s_(span_s), step_s_(step_s) {
  const int half = std::max(1, static_cast<int>(std::ceil(span_s / step_s)));
  span_s_ = half * step_s;
  p_.assign(2 * half + 1, p);
  v_.assign(p_.size(), flow.Velocity(p));
  // Integrated outwards until the path leaves `inside` (one sample beyond, so that the interpolation
  // reaches its edge); the rest is never read (Covers).
  int last = half, first = half;
  for (int k = half + 1; k <= 2 * half; ++k) {
    p_[k] = flow.Carry(p_[k - 1], step_s, step_s), v_[k] = flow.Velocity(p_[k]), last = k;
    if (inside && !inside(p_[k])) break;
  }
  for (int k = half - 1; k >= 0; --k) {
    p_[k] = flow.Carry(p_[k + 1], -step_s, step_s), v_[k] = flow.Velocity(p_[k]), first = k;
    if (inside && !inside(p_[k])) break;
  }
  from_s_ = (first - half) * step_s, to_s_ = (last - half) * step_s;
}

size_t FlowPath::Interval(double dt_s, double* s) const {
  const double f = std::clamp((dt_s + span_s_) / step_s_, 0.0, static_cast<double>(p_.size() - 1));
  const size_t k = std::min(static_cast<size_t>(f), p_.size() - 2);
  *s = f - k;
  return k;
}

PixelPoint FlowPath::At(double dt_s) const {
  double s = 0;
  const size_t k = Interval(dt_s, &s);
  const double h = step_s_;
  // Cubic Hermite on [k, k + 1] with the flow's velocities as the end slopes.
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
               h11 = s * s * s - s * s;
  return {h00 * p_[k].x_px + h10 * h * v_[k].x_px + h01 * p_[k + 1].x_px + h11 * h * v_[k + 1].x_px,
          h00 * p_[k].y_px + h10 * h * v_[k].y_px + h01 * p_[k + 1].y_px + h11 * h * v_[k + 1].y_px};
}

PixelPoint FlowPath::VelocityAt(double dt_s) const {
  double s = 0;
  const size_t k = Interval(dt_s, &s);
  const double h = step_s_;
  // The Hermite cubic's derivative (d/ds divided by h).
  const double d00 = 6 * s * s - 6 * s, d10 = 3 * s * s - 4 * s + 1, d01 = -6 * s * s + 6 * s, d11 = 3 * s * s - 2 * s;
  return {(d00 * p_[k].x_px + d01 * p_[k + 1].x_px) / h + d10 * v_[k].x_px + d11 * v_[k + 1].x_px,
          (d00 * p_[k].y_px + d01 * p_[k + 1].y_px) / h + d10 * v_[k].y_px + d11 * v_[k + 1].y_px};
}

}  // namespace platemeter
