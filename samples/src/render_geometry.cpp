#include "render_geometry.h"
#include "platemeter/core/angles.h"

#include <algorithm>
#include <map>
#include <mutex>

namespace platemeter::sim::render_detail {

const GaussLegendreRule& GaussLegendre(int n) {
  static std::mutex mutex;
  static std::map<int, GaussLegendreRule> rules;  // node-stable: references stay valid
  std::lock_guard<std::mutex> lock(mutex);
  auto found = rules.find(n);
  if (found != rules.end()) return found->second;
  GaussLegendreRule rule;
  rule.nodes.resize(n);
  rule.weights.resize(n);
  // Newton on the Legendre polynomial P_n from Chebyshev-like starting guesses.
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double derivative = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      derivative = n * (x * p1 - p0) / (x * x - 1.0);
      const double step = p1 / derivative;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    // Recompute the derivative at the converged root for the weight.
    double p0 = 1.0, p1 = x;
    for (int k = 2; k <= n; ++k) {
      const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
      p0 = p1;
      p1 = p2;
    }
    derivative = n * (x * p1 - p0) / (x * x - 1.0);
    const double weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
    rule.nodes[i] = -x;
    rule.nodes[n - 1 - i] = x;
    rule.weights[i] = weight;
    rule.weights[n - 1 - i] = weight;
  }
  if (n == 1) {
    rule.nodes[0] = 0.0;
    rule.weights[0] = 2.0;
  }
  return rules.emplace(n, std::move(rule)).first->second;
}

NormalCdfTable::NormalCdfTable() {
  for (int i = 0; i < kIntervals; ++i) {
    const double z0 = -kLimit + (i + 0.5) / kPerUnit;
    const double pdf = kInvSqrt2Pi * std::exp(-0.5 * z0 * z0);
    double* c = coefficients[i];
    c[0] = 0.5 * std::erfc(-z0 * 0.70710678118654752440);
    // Phi^(k)(z0) / k! = (-1)^(k-1) He_{k-1}(z0) phi(z0) / k!, He the probabilists' Hermite polynomials.
    double he[kDegree];
    he[0] = 1.0;
    he[1] = z0;
    for (int n = 1; n + 1 < kDegree; ++n) he[n + 1] = z0 * he[n] - n * he[n - 1];
    double factorial = 1.0;
    for (int k = 1; k <= kDegree; ++k) {
      factorial *= k;
      c[k] = (k % 2 == 1 ? 1.0 : -1.0) * he[k - 1] * pdf / factorial;
    }
  }
}

const NormalCdfTable& TheNormalCdfTable() {
  static const NormalCdfTable table;
  return table;
}

namespace {

double Cross(Point2 a, Point2 b) { return a.x * b.y - a.y * b.x; }
double Dot(Point2 a, Point2 b) { return a.x * b.x + a.y * b.y; }

// Clips `in` (n vertices) to the half-plane sign * coordinate(axis) <= limit.
int ClipHalfPlane(const Point2* in, int n, int axis, double sign, double limit, Point2* out) {
  auto value = [&](const Point2& p) { return sign * (axis == 0 ? p.x : p.y) - limit; };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Point2& a = in[i];
    const Point2& b = in[(i + 1) % n];
    const double va = value(a), vb = value(b);
    if (va <= 0) out[m++] = a;
    if ((va < 0 && vb > 0) || (va > 0 && vb < 0)) {
      const double t = va / (va - vb);
      out[m++] = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
    }
  }
  return m;
}

// Signed area of the disk (radius r, centre origin) inside the triangle (0, a, b).
double DiskTriangleArea(Point2 a, Point2 b, double r) {
  auto sector = [r](Point2 u, Point2 v) { return 0.5 * r * r * std::atan2(Cross(u, v), Dot(u, v)); };
  const double r2 = r * r;
  const bool a_in = Dot(a, a) <= r2, b_in = Dot(b, b) <= r2;
  if (a_in && b_in) return 0.5 * Cross(a, b);
  const Point2 d{b.x - a.x, b.y - a.y};
  const double qa = Dot(d, d);
  if (qa <= 0) return 0.0;
  const double qb = Dot(a, d), qc = Dot(a, a) - r2;
  const double discriminant = qb * qb - qa * qc;
  if (discriminant <= 0) return sector(a, b);
  const double s = std::sqrt(discriminant);
  const double t1 = (-qb - s) / qa, t2 = (-qb + s) / qa;
  if (t2 <= 0 || t1 >= 1) return sector(a, b);
  const double u1 = std::max(t1, 0.0), u2 = std::min(t2, 1.0);
  const Point2 p1{a.x + u1 * d.x, a.y + u1 * d.y};
  const Point2 p2{a.x + u2 * d.x, a.y + u2 * d.y};
  return sector(a, p1) + 0.5 * Cross(p1, p2) + sector(p2, b);
}

}  // namespace

double ConvexPolygonBoxArea(const std::array<Point2, 4>& poly, double ax, double ay) {
  Point2 buffer_a[12], buffer_b[12];
  int n = 4;
  std::copy(poly.begin(), poly.end(), buffer_a);
  n = ClipHalfPlane(buffer_a, n, 0, 1.0, ax, buffer_b);
  n = ClipHalfPlane(buffer_b, n, 0, -1.0, ax, buffer_a);
  n = ClipHalfPlane(buffer_a, n, 1, 1.0, ay, buffer_b);
  n = ClipHalfPlane(buffer_b, n, 1, -1.0, ay, buffer_a);
  double twice_area = 0.0;
  for (int i = 0; i < n; ++i) twice_area += Cross(buffer_a[i], buffer_a[(i + 1) % n]);
  return 0.5 * std::abs(twice_area);
}

double DiskPolygonArea(const std::array<Point2, 4>& poly, double r) {
  double area = 0.0;
  for (int i = 0; i < 4; ++i) area += DiskTriangleArea(poly[i], poly[(i + 1) % 4], r);
  return std::abs(area);
}

void BlurredDisk(double r, double radius, double sigma, double* value, double* derivative) {
  // Place the point at (r, 0): value = int_{-R}^{R} g(x - r) erf(sqrt(R^2 - x^2) / (sqrt2 sigma)) dx,
  // with x = R sin(theta) so the integrand stays smooth at the rim.
  constexpr double kReach = 11.0;  // sigmas of g kept (exp(-60): nothing lost)
  const double x_lo = std::max(-radius, r - kReach * sigma);
  const double x_hi = std::min(radius, r + kReach * sigma);
  *value = 0.0;
  *derivative = 0.0;
  if (x_hi <= x_lo) return;
  const double theta_lo = std::asin(std::clamp(x_lo / radius, -1.0, 1.0));
  const double theta_hi = std::asin(std::clamp(x_hi / radius, -1.0, 1.0));
  const int panels = std::clamp(static_cast<int>(std::ceil((theta_hi - theta_lo) * radius / (0.25 * sigma))), 2, 100000);
  const GaussLegendreRule& rule = GaussLegendre(8);
  const double panel = (theta_hi - theta_lo) / panels;
  const double norm = 1.0 / (std::sqrt(2.0 * M_PI) * sigma);
  const double inv_2s2 = 0.5 / (sigma * sigma);
  const double inv_sqrt2_sigma = 1.0 / (std::sqrt(2.0) * sigma);
  double sum_value = 0.0, sum_derivative = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double mid = theta_lo + (p + 0.5) * panel;
    for (size_t k = 0; k < rule.nodes.size(); ++k) {
      const double theta = mid + 0.5 * panel * rule.nodes[k];
      const double c = std::cos(theta);
      const double t = radius * std::sin(theta) - r;
      const double g = norm * std::exp(-t * t * inv_2s2);
      const double chord = std::erf(radius * c * inv_sqrt2_sigma);
      const double w = rule.weights[k] * 0.5 * panel * radius * c;
      sum_value += w * g * chord;
      sum_derivative += w * g * chord * t / (sigma * sigma);  // d/dr g(x - r) = (x - r)/s^2 g
    }
  }
  *value = sum_value;
  *derivative = sum_derivative;
}

}  // namespace platemeter::sim::render_detail

namespace platemeter::sim::render_detail {
namespace {

inline double Cdf(double z) { return 0.5 * std::erfc(-z * 0.70710678118654752440); }
inline double Pdf(double z) { return kInvSqrt2Pi * std::exp(-0.5 * z * z); }
// Psi1 = int Phi, Psi2 = int Psi1.
inline double Psi1(double z) { return z * Cdf(z) + Pdf(z); }
inline double Psi2(double z) { return 0.5 * ((z * z + 1.0) * Cdf(z) + z * Pdf(z)); }

// E[Phi(z + V1 + V2)], V_i uniform on [-w_i/2, w_i/2], w1 >= w2 >= 0 (units of sigma).
double BoxAveragedCdf(double z, double w1, double w2) {
  constexpr double kSmall = 1e-2;  // below: a box of width w acts as its second-order moment (error ~ w^4 / 1920)
  if (w1 < kSmall) {
    // Phi(z) + (w1^2 + w2^2) / 24 Phi''(z), Phi'' = -z phi.
    return Cdf(z) - (w1 * w1 + w2 * w2) / 24.0 * z * Pdf(z);
  }
  const double h1 = 0.5 * w1;
  if (w2 < kSmall) {
    const double mean = (Psi1(z + h1) - Psi1(z - h1)) / w1;
    // second derivative of the one-box mean (Psi1'' = phi): (phi(z + h1) - phi(z - h1)) / w1
    const double curvature = (Pdf(z + h1) - Pdf(z - h1)) / w1;
    return mean + w2 * w2 / 24.0 * curvature;
  }
  const double h2 = 0.5 * w2;
  return (Psi2(z + h1 + h2) - Psi2(z + h1 - h2) - Psi2(z - h1 + h2) + Psi2(z - h1 - h2)) / (w1 * w2);
}

// E[phi(z + V1 + V2)], V_i uniform on [-w_i/2, w_i/2], w1 >= w2 >= 0 (units of sigma).
double BoxAveragedPdf(double z, double w1, double w2) {
  constexpr double kSmall = 1e-2;
  if (w1 < kSmall) return Pdf(z) + (w1 * w1 + w2 * w2) / 24.0 * (z * z - 1.0) * Pdf(z);  // phi'' = (z^2 - 1) phi
  const double h1 = 0.5 * w1;
  if (w2 < kSmall) {
    const double mean = (Cdf(z + h1) - Cdf(z - h1)) / w1;
    const double curvature = (-(z + h1) * Pdf(z + h1) + (z - h1) * Pdf(z - h1)) / w1;  // phi' = -z phi
    return mean + w2 * w2 / 24.0 * curvature;
  }
  const double h2 = 0.5 * w2;
  return (Psi1(z + h1 + h2) - Psi1(z + h1 - h2) - Psi1(z - h1 + h2) + Psi1(z - h1 - h2)) / (w1 * w2);
}

}  // namespace

double BoxAveragedDensity(double c, double s, double a, double b) {
  double w1 = std::abs(a) / s, w2 = std::abs(b) / s;
  if (w2 > w1) std::swap(w1, w2);
  // phi is even and V symmetric: use -|c| so the Psi1 terms stay small (Psi1 -> 0 on the left).
  return BoxAveragedPdf(-std::abs(c) / s, w1, w2) / s;
}

double BoxAveragedInterval(double c, double h, double s, double a, double b) {
  double w1 = std::abs(a) / s, w2 = std::abs(b) / s;
  if (w2 > w1) std::swap(w1, w2);
  // For c < 0 use the mirror image (the interval is symmetric): keeps z small where the terms cancel.
  const double z_hi = (std::abs(c) + h) / s, z_lo = (std::abs(c) - h) / s;
  // Phi(z_hi + V) - Phi(z_lo + V) = Phi(-z_lo - V) - Phi(-z_hi - V): evaluate the pair on the side of
  // small |z| to keep the differences of large Psi2 values away.
  return BoxAveragedCdf(-z_lo, w1, w2) - BoxAveragedCdf(-z_hi, w1, w2);
}

}  // namespace platemeter::sim::render_detail
