// The emulsion-depth geometry (emulsion_depth.h).
#include "platemeter/measure/emulsion_depth.h"

#include <cmath>

namespace platemeter {

double EmulsionDepthModel::RadialShiftMm(double r_mm) const {
  const double n = refractive_index, c = principal_distance_mm;
  const double sin_theta = r_mm / std::hypot(r_mm, c);
  return depth_um * 1e-3 * sin_theta / std::sqrt(n * n - sin_theta * sin_theta);
}

double EmulsionDepthModel::RadialShiftDerivative(double r_mm) const {
  const double n = refractive_index, c = principal_distance_mm, d_mm = depth_um * 1e-3;
  const double h = std::hypot(r_mm, c), s = r_mm / h, cos_theta = c / h;
  // d/ds [s / sqrt(n^2 - s^2)] = n^2 / (n^2 - s^2)^1.5;  ds/dr = c^2 / (r^2 + c^2)^1.5 = cos^3(theta) / c
  // (the second form stays finite for any c: c^2 overflows above 1e154 mm).
  return d_mm * n * n / std::pow(n * n - s * s, 1.5) * cos_theta * cos_theta * cos_theta / c;
}

double EmulsionDepthModel::TrueRadiusMm(double image_radius_mm) const {
  if (image_radius_mm == 0.0 || depth_um == 0.0) return image_radius_mm;
  // Solve r + g(r) = r_image; g' > 0 and small, so Newton converges in a few steps.
  double r = image_radius_mm / EquivalentScale();
  for (int i = 0; i < 50; ++i) {
    const double step = (r + RadialShiftMm(r) - image_radius_mm) / (1.0 + RadialShiftDerivative(r));
    r -= step;
    if (std::abs(step) < 1e-15 * (1.0 + image_radius_mm)) break;
  }
  return r;
}

double EmulsionDepthModel::FittedScale(const std::vector<double>& radii_mm) const {
  double num = 0.0, den = 0.0;
  for (double r : radii_mm) {
    num += r * (r + RadialShiftMm(r));
    den += r * r;
  }
  return den > 0.0 ? num / den : 1.0;
}

double EmulsionDepthModel::DepthUmFromFittedScale(double scale, const std::vector<double>& radii_mm) const {
  EmulsionDepthModel unit = *this;
  unit.depth_um = 1.0;  // the shift is proportional to the depth
  return (scale - 1.0) / (unit.FittedScale(radii_mm) - 1.0);
}

double EmulsionDepthModel::EquivalentScale() const {
  return 1.0 + depth_um * 1e-3 / (refractive_index * principal_distance_mm);
}

double EmulsionDepthModel::DepthUmFromEquivalentScale(double scale, double refractive_index,
                                                      double principal_distance_mm) {
  return (scale - 1.0) * refractive_index * principal_distance_mm * 1e3;
}

}  // namespace platemeter
