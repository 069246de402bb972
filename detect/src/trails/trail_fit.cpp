// The sidereal track of one trail: weighted polynomial fits x(t), y(t) (trail_internal.h).
#include <algorithm>
#include <cmath>

#include "trail_internal.h"

namespace platemeter::trail_internal {

Eigen::VectorXd Track::Basis(double t_s) const {
  Eigen::VectorXd b(degree_ + 1);
  const double u = (t_s - t0_s_) / scale_s_;
  double v = 1.0;
  for (int k = 0; k <= degree_; ++k) b(k) = v, v *= u;
  return b;
}

bool Track::Fit(const std::vector<double>& t_s, const std::vector<PixelPoint>& p, const std::vector<double>& sigma_x_px,
                const std::vector<double>& sigma_y_px, int degree) {
  const int n = static_cast<int>(t_s.size());
  if (n < 2) return false;
  degree_ = std::max(1, std::min(degree, n - 2));
  if (n == 2) degree_ = 1;
  const auto [lo, hi] = std::minmax_element(t_s.begin(), t_s.end());
  t0_s_ = 0.5 * (*lo + *hi);
  scale_s_ = std::max(1.0, 0.5 * (*hi - *lo));  // u in [-1, 1]: a well-conditioned basis
  const bool weighted = !sigma_x_px.empty();
  Eigen::MatrixXd a(n, degree_ + 1);
  Eigen::VectorXd bx(n), by(n), wx(n), wy(n);
  for (int i = 0; i < n; ++i) {
    a.row(i) = Basis(t_s[i]).transpose();
    bx(i) = p[i].x_px, by(i) = p[i].y_px;
    wx(i) = weighted ? 1.0 / sigma_x_px[i] : 1.0;
    wy(i) = weighted ? 1.0 / sigma_y_px[i] : 1.0;
  }
  auto solve = [&](const Eigen::VectorXd& w, const Eigen::VectorXd& b, Eigen::VectorXd* coef, Eigen::MatrixXd* cov) {
    const Eigen::MatrixXd aw = w.asDiagonal() * a;
    const Eigen::MatrixXd normal = aw.transpose() * aw;
    Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
    if (ldlt.info() != Eigen::Success) return false;
    *coef = ldlt.solve(aw.transpose() * (w.asDiagonal() * b));
    *cov = ldlt.solve(Eigen::MatrixXd::Identity(degree_ + 1, degree_ + 1));
    return coef->allFinite();
  };
  if (!solve(wx, bx, &ax_, &cov_x_) || !solve(wy, by, &ay_, &cov_y_)) return false;
  const int dof = 2 * (n - degree_ - 1);
  double chi2 = 0;
  for (int i = 0; i < n; ++i) {
    const double rx = (a.row(i).dot(ax_) - bx(i)) * wx(i), ry = (a.row(i).dot(ay_) - by(i)) * wy(i);
    chi2 += rx * rx + ry * ry;
  }
  reduced_chi2_ = dof > 0 ? chi2 / dof : 1.0;
  return true;
}

PixelPoint Track::At(double t_s) const {
  const Eigen::VectorXd b = Basis(t_s);
  return {b.dot(ax_), b.dot(ay_)};
}

PixelPoint Track::VelocityAt(double t_s) const {
  const double u = (t_s - t0_s_) / scale_s_;
  double vx = 0, vy = 0, v = 1.0;
  for (int k = 1; k <= degree_; ++k) vx += k * ax_(k) * v, vy += k * ay_(k) * v, v *= u;
  return {vx / scale_s_, vy / scale_s_};
}

void Track::SigmaAt(double t_s, double* sigma_x_px, double* sigma_y_px) const {
  const Eigen::VectorXd b = Basis(t_s);
  const double scale = std::max(1.0, reduced_chi2_);
  *sigma_x_px = std::sqrt(std::max(0.0, b.dot(cov_x_ * b) * scale));
  *sigma_y_px = std::sqrt(std::max(0.0, b.dot(cov_y_ * b) * scale));
}

void Track::LeverageAt(double t_s, double sigma_x_px, double sigma_y_px, double* h_x, double* h_y) const {
  const Eigen::VectorXd b = Basis(t_s);
  *h_x = std::clamp(b.dot(cov_x_ * b) / (sigma_x_px * sigma_x_px), 0.0, 0.999);
  *h_y = std::clamp(b.dot(cov_y_ * b) / (sigma_y_px * sigma_y_px), 0.0, 0.999);
}

FitSigma FitSigmaOf(const TrailOptions& o, const DetectedStar& d) {
  return {std::hypot(d.point.sigma_x_px > 0 ? d.point.sigma_x_px : 0.05, o.position_floor_px),
          std::hypot(d.point.sigma_y_px > 0 ? d.point.sigma_y_px : 0.05, o.position_floor_px)};
}

bool FitTrackOf(const Context& c, const std::vector<std::pair<int, int>>& taken,
                const std::function<double(int)>& time_s, const std::function<bool(int)>& use, size_t min_images,
                Track* track) {
  std::vector<int> ids;
  for (const auto& [j, i] : taken)
    if (use(i)) ids.push_back(i);
  if (ids.size() < std::max<size_t>(min_images, 2)) return false;
  std::sort(ids.begin(), ids.end(), [&](int a, int b) { return time_s(a) < time_s(b); });
  std::vector<double> t, sx, sy;
  std::vector<PixelPoint> p;
  for (int i : ids) {
    const FitSigma s = FitSigmaOf(c.o, c.images[i]);
    t.push_back(time_s(i)), p.push_back(c.p[i]), sx.push_back(s.x_px), sy.push_back(s.y_px);
  }
  return track->Fit(t, p, sx, sy, DegreeFor(static_cast<int>(t.size()), t.back() - t.front(), c.o.track_degree));
}

}  // namespace platemeter::trail_internal
