#pragma once
// The radial profile of a uniform disk of radius R blurred by an isotropic
// Gaussian of sigma s (pixel units): D(r) = the Gaussian's mass inside the
// disk when centred at distance r from the disk's centre (1 - Marcum Q1).
// Its derivatives are closed forms in the exponentially scaled Bessel
// functions (boundary integrals over the circle; z = r R / s^2,
// E = exp(-(R - r)^2 / (2 s^2))):
//   dD/dr = -(R / s^2) E I1e(z)
//   dD/dR =  (R / s^2) E I0e(z)
//   dD/ds = -(R / s^3) E (R I0e(z) - r I1e(z))      (heat equation: dG/ds = s lap G)
// D itself has no closed form: it is the integral of -dD/dr from far outside
// (where D = 0), taken per table step with an 8-node Gauss-Legendre rule. The
// table holds D and its derivatives on [r_lo, r_hi] (D = 1 inside r_lo when
// R > 8.5 s, 0 beyond r_hi) and is read by cubic Hermite interpolation
// (value) and linear interpolation (derivatives, which only steer the fit).
#include <vector>

namespace platemeter::internal {

struct DiskProfileValue {
  double value = 0.0;
  double d_r = 0.0;
  double d_radius = 0.0;
  double d_sigma = 0.0;
};

class DiskProfileTable {
 public:
  DiskProfileTable(double radius_px, double sigma_px);
  DiskProfileValue At(double r_px) const;
  double reach_px() const { return r_hi_; }  // D is 0 beyond
  double inner_px() const { return r_lo_; }  // D is 1 (derivatives 0) inside, when > 0

 private:
  double radius_, sigma_;
  double r_lo_ = 0.0, r_hi_ = 0.0, step_ = 1.0;
  std::vector<double> value_, d_r_, d_radius_, d_sigma_;
};

// The closed-form derivatives at one r (exposed for tests).
DiskProfileValue DiskProfileDerivatives(double r_px, double radius_px, double sigma_px);

}  // namespace platemeter::internal
