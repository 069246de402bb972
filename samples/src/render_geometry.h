#pragma once
// Small exact-geometry helpers of the renderer (private to samples/src):
// Gauss-Legendre rules, Gaussian CDF differences, polygon clipping and the
// area of a circle cut by a polygon.
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

// Phi(hi) - Phi(lo) for the standard normal CDF Phi.
inline double NormalCdfDifference(double hi, double lo) {
  constexpr double kInvSqrt2 = 0.70710678118654752440;
  return 0.5 * (std::erf(hi * kInvSqrt2) - std::erf(lo * kInvSqrt2));
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
