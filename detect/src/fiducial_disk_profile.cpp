// Radial profile of a blurred disk (mark_disk_profile.h).
#include <unsupported/Eigen/SpecialFunctions>

#include <algorithm>
#include <cmath>

#include "mark_disk_profile.h"

namespace platemeter::internal {
namespace {

constexpr double kTailSigmas = 8.5;  // exp(-36) beyond: nothing left
constexpr int kStepsPerSigma = 8;  // cubic Hermite: error ~ (1/8)^4 / 384 of the profile

// 8-node Gauss-Legendre on [-1, 1].
constexpr double kNodes[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                              0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
constexpr double kWeights[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

}  // namespace

DiskProfileValue DiskProfileDerivatives(double r, double radius, double sigma) {
  const double s2 = sigma * sigma;
  const double z = r * radius / s2;
  const double d = radius - r;
  const double e = std::exp(-0.5 * d * d / s2);
  const double i0 = Eigen::numext::bessel_i0e(z), i1 = Eigen::numext::bessel_i1e(z);
  DiskProfileValue v;
  v.d_r = -(radius / s2) * e * i1;
  v.d_radius = (radius / s2) * e * i0;
  v.d_sigma = -(radius / (s2 * sigma)) * e * (radius * i0 - r * i1);
  return v;
}

DiskProfileTable::DiskProfileTable(double radius_px, double sigma_px) : radius_(radius_px), sigma_(sigma_px) {
  r_lo_ = std::max(0.0, radius_px - kTailSigmas * sigma_px);
  r_hi_ = radius_px + kTailSigmas * sigma_px;
  const int count = std::max(8, static_cast<int>(std::ceil((r_hi_ - r_lo_) / sigma_px * kStepsPerSigma)) + 1);
  step_ = (r_hi_ - r_lo_) / (count - 1);
  value_.resize(count);
  d_r_.resize(count);
  d_radius_.resize(count);
  d_sigma_.resize(count);
  for (int i = 0; i < count; ++i) {
    const DiskProfileValue v = DiskProfileDerivatives(r_lo_ + i * step_, radius_px, sigma_px);
    d_r_[i] = v.d_r;
    d_radius_[i] = v.d_radius;
    d_sigma_[i] = v.d_sigma;
  }
  // D(r_hi) = 0; integrate dD/dr inward step by step.
  value_[count - 1] = 0.0;
  for (int i = count - 2; i >= 0; --i) {
    const double a = r_lo_ + i * step_;
    double integral = 0.0;
    for (int k = 0; k < 8; ++k)
      integral += kWeights[k] * DiskProfileDerivatives(a + 0.5 * step_ * (1.0 + kNodes[k]), radius_px, sigma_px).d_r;
    value_[i] = value_[i + 1] - 0.5 * step_ * integral;
  }
}

DiskProfileValue DiskProfileTable::At(double r) const {
  DiskProfileValue v;
  if (r >= r_hi_) return v;
  if (r <= r_lo_) {
    if (r_lo_ > 0.0) {
      v.value = 1.0;
      return v;
    }
    r = std::max(r, 0.0);
  }
  const double s = (r - r_lo_) / step_;
  const size_t i = std::min(static_cast<size_t>(s), value_.size() - 2);
  const double t = s - static_cast<double>(i), t2 = t * t, t3 = t2 * t;
  v.value = (2 * t3 - 3 * t2 + 1) * value_[i] + (t3 - 2 * t2 + t) * step_ * d_r_[i] + (-2 * t3 + 3 * t2) * value_[i + 1] +
            (t3 - t2) * step_ * d_r_[i + 1];
  // The interpolant's own slope, so that value and position derivative agree (clean convergence).
  v.d_r = ((6 * t2 - 6 * t) * (value_[i] - value_[i + 1])) / step_ + (3 * t2 - 4 * t + 1) * d_r_[i] +
          (3 * t2 - 2 * t) * d_r_[i + 1];
  v.d_radius = (1 - t) * d_radius_[i] + t * d_radius_[i + 1];
  v.d_sigma = (1 - t) * d_sigma_[i] + t * d_sigma_[i + 1];
  return v;
}

}  // namespace platemeter::internal
