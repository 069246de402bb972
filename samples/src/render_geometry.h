#pragma once
// Small exact-geometry helpers of the renderer (private to samples/src):
// Gauss-Legendre rules, the tabulated normal CDF, box-averaged Gaussian edges,
// polygon clipping and the area of a circle cut by a polygon.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace platemeter::sim::render_detail {

// Nodes on [-1, 1] and weights (summing to 2) of the n-point Gauss-Legendre rule.
struct GaussLegendreRule {
  std::vector<double> nodes;
  std::vector<double> weights;
};
const GaussLegendreRule& GaussLegendre(int n);

// The standard normal CDF Phi(z) from a table of degree-7 Taylor polynomials
// on intervals of 1/32 (exact coefficients: Phi^(k) = (-1)^(k-1) He_{k-1} phi):
// absolute error < 5e-16 (erf's own rounding near +-1), 0 and 1 beyond +-8.5
// (Phi(-8.5) = 1e-17); a polynomial still holds to 3e-16 at twice its half
// width from its centre. Several times cheaper than std::erf, which dominated
// the render and Cramer-Rao time of trail images.
struct NormalCdfTable {
  static constexpr double kLimit = 8.5;             // |z| beyond which Phi is 0 or 1
  static constexpr double kPerUnit = 32.0;          // intervals per unit of z
  static constexpr int kDegree = 7;
  static constexpr int kIntervals = 544;            // 2 kLimit kPerUnit
  alignas(64) double coefficients[kIntervals][kDegree + 1];  // Taylor coefficients about each interval's centre
  NormalCdfTable();
};
const NormalCdfTable& TheNormalCdfTable();

// Branch-free (the clamp puts |z| >= kLimit on the table's end values, within
// 1e-17 of 0 and 1) and in Estrin's form: the trail quadrature calls it on
// unpredictable arguments, where branches and a serial Horner chain cost more
// than the arithmetic.
inline double FastNormalCdf(const NormalCdfTable& table, double z) {
  // (a NaN lands on -kLimit: never outside the table)
  z = std::max(-NormalCdfTable::kLimit, std::min(z, NormalCdfTable::kLimit));
  const double s = (z + NormalCdfTable::kLimit) * NormalCdfTable::kPerUnit;
  const int i = std::min(static_cast<int>(s), NormalCdfTable::kIntervals - 1);
  const double t = z - ((i + 0.5) * (1.0 / NormalCdfTable::kPerUnit) - NormalCdfTable::kLimit);  // exact centre
  const double* c = table.coefficients[i];
  const double t2 = t * t, t4 = t2 * t2;
  return ((c[0] + t * c[1]) + t2 * (c[2] + t * c[3])) + t4 * ((c[4] + t * c[5]) + t2 * (c[6] + t * c[7]));
}

// Mean of the blurred interval indicator Phi((q + h)/s) - Phi((q - h)/s) over
// q = c + a ox + b oy, with ox, oy uniform on [-1/2, 1/2] (one pixel): exact,
// from the second antiderivative of Phi.
double BoxAveragedInterval(double c, double h, double s, double a, double b);

// Mean of the normal density phi(q / s) / s over q = c + a ox + b oy, with ox,
// oy uniform on [-1/2, 1/2] (one pixel): exact, from the antiderivatives of phi.
double BoxAveragedDensity(double c, double s, double a, double b);

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

// Area of the convex polygon `poly` (any orientation) inside the axis-aligned
// box [-ax, ax] x [-ay, ay].
double ConvexPolygonBoxArea(const std::array<Point2, 4>& poly, double ax, double ay);

// Area of the disk of radius r about the origin inside the convex polygon
// `poly` (any orientation).
double DiskPolygonArea(const std::array<Point2, 4>& poly, double r);

// The disk of radius R (um) convolved with an isotropic Gaussian of sigma (um),
// at distance r from the disk's centre, and its derivative in r.
void BlurredDisk(double r, double radius, double sigma, double* value, double* derivative);

// SplitMix64 finaliser: a good 64-bit mixing function for counter-based streams.
inline uint64_t Mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace platemeter::sim::render_detail
