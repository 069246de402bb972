#pragma once
// The pixel-averaged profile of a blurred bar: the mean over [t - 1/2, t + 1/2]
// of a bar of width w (centred on 0) convolved with a Gaussian of sigma s,
//   P(t; w, s) = (k/2) * sum_i sign_i * F(a_i / k),   k = sqrt(2) s,
//   a = t + 1/2 + w/2, t - 1/2 + w/2, t + 1/2 - w/2, t - 1/2 - w/2 with signs +, -, -, +,
// where F(z) = z erf(z) + exp(-z^2) / sqrt(pi) is the integral of erf. Its
// derivatives are closed forms too (dF/dz = erf), which the fits use.
#include <cmath>

namespace platemeter::internal {

struct BarProfile {
  double value = 0.0;
  double d_t = 0.0;      // dP/dt
  double d_width = 0.0;  // dP/dw
  double d_sigma = 0.0;  // dP/ds
};

inline BarProfile EvaluateBarProfile(double t, double width, double sigma) {
  constexpr double kInvSqrtPi = 0.56418958354775628695;
  const double k = std::sqrt(2.0) * sigma;
  const double a[4] = {t + 0.5 + 0.5 * width, t - 0.5 + 0.5 * width, t + 0.5 - 0.5 * width, t - 0.5 - 0.5 * width};
  // Far from both edges every erf is +-1 to double precision (erf(6) = 1 - 2e-17):
  // the pixel is wholly outside (0) or wholly inside (1), with zero derivatives.
  const double saturated = 6.0 * k;
  if (a[3] > saturated || a[0] < -saturated) return {};
  if (a[1] > saturated && a[2] < -saturated) return {1.0, 0.0, 0.0, 0.0};
  const double sign[4] = {1.0, -1.0, -1.0, 1.0};
  const double da_dw[4] = {0.5, 0.5, -0.5, -0.5};
  BarProfile p;
  double sum_f = 0.0, sum_erf = 0.0, sum_erf_dw = 0.0, sum_gauss = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double z = a[i] / k;
    const double erf_z = std::erf(z);
    const double gauss = std::exp(-z * z) * kInvSqrtPi;
    sum_f += sign[i] * (z * erf_z + gauss);
    sum_erf += sign[i] * erf_z;
    sum_erf_dw += sign[i] * erf_z * da_dw[i];
    sum_gauss += sign[i] * gauss;
  }
  p.value = 0.5 * k * sum_f;
  p.d_t = 0.5 * sum_erf;
  p.d_width = 0.5 * sum_erf_dw;
  p.d_sigma = std::sqrt(2.0) * 0.5 * sum_gauss;  // dP/dk = (1/2) sum sign * exp(-z^2)/sqrt(pi); dk/ds = sqrt(2)
  return p;
}

}  // namespace platemeter::internal
