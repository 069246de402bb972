// The comparator corrections before the reseau fit (corrections.h).
#include "platemeter/measure/corrections.h"

#include <array>
#include <cmath>

#include <fmt/format.h>

#include "platemeter/core/scan_orientation.h"
#include "platemeter/core/why.h"
#include "platemeter/core/number_text.h"

namespace platemeter {
namespace {


}  // namespace

Covariance2 Covariance2::Transformed(const double j[4]) const {
  // (J C)
  const double a = j[0] * xx + j[1] * xy, b = j[0] * xy + j[1] * yy;
  const double c = j[2] * xx + j[3] * xy, d = j[2] * xy + j[3] * yy;
  return {a * j[0] + b * j[1], a * j[2] + b * j[3], c * j[2] + d * j[3]};
}

// ---- comparator

void ComparatorCorrection::Jacobian(double j[4]) const {
  // Pixels come from plate axes through detect's axis map A (orthogonal, 0/+-1);
  // back to plate mm: A^T times the pixel size.
  const double p_mm = pixel_size_um * 1e-3;
  const std::array<int, 4> a = ScanOrientation{orientation_deg, mirrored}.PixelAxesFromPlate();
  j[0] = a[0] * p_mm;
  j[1] = a[2] * p_mm;
  j[2] = a[1] * p_mm;
  j[3] = a[3] * p_mm;
}

PlanePoint ComparatorCorrection::Apply(const PlanePoint& px) const {
  double j[4];
  Jacobian(j);
  return {j[0] * px.x + j[1] * px.y, j[2] * px.x + j[3] * px.y, px.cov.Transformed(j)};
}

AppliedCorrection ComparatorCorrection::Record() const {
  return {"comparator",
          {{"pixel_size_um", ShortestText(pixel_size_um)},
           {"orientation_deg", std::to_string(orientation_deg)},
           {"mirrored", mirrored ? "true" : "false"}}};
}

bool ComparatorCorrection::Check(std::string* why) const {
  if (!(pixel_size_um > 0.0 && pixel_size_um < 1000.0)) return Fail(why, "comparator pixel_size_um must lie in 0..1000");
  const int o = ((orientation_deg % 360) + 360) % 360;
  if (o % 90 != 0) return Fail(why, "comparator orientation_deg must be 0, 90, 180 or 270");
  return true;
}

// ---- thermal

PlanePoint ThermalCorrection::Apply(const PlanePoint& mm) const {
  if (!enabled) return mm;
  const double f = Factor();
  const double j[4] = {f, 0, 0, f};
  return {mm.x * f, mm.y * f, mm.cov.Transformed(j)};
}

AppliedCorrection ThermalCorrection::Record() const {
  return {"thermal",
          {{"temperature_degC", ShortestText(temperature_degC)},
           {"calibration_temperature_degC", ShortestText(calibration_temperature_degC)},
           {"expansion_per_degC", ShortestText(expansion_per_degC)},
           {"factor", ShortestText(Factor())}}};
}

bool ThermalCorrection::Check(std::string* why) const {
  if (!std::isfinite(temperature_degC) || std::abs(temperature_degC) > 100) return Fail(why, "thermal temperature_degC must lie in -100..100");
  if (!std::isfinite(calibration_temperature_degC) || std::abs(calibration_temperature_degC) > 100) {
    return Fail(why, "thermal calibration_temperature_degC must lie in -100..100");
  }
  if (!std::isfinite(expansion_per_degC) || std::abs(expansion_per_degC) > 1e-3) {
    return Fail(why, "thermal expansion_per_degC must lie in -1e-3..1e-3");
  }
  return true;
}

// ---- emulsion depth

PlanePoint EmulsionDepthCorrection::Apply(const PlanePoint& mm) const {
  if (!enabled || model.depth_um == 0.0) return mm;
  const double dx = mm.x - centre_x_mm, dy = mm.y - centre_y_mm;
  const double r_image = std::hypot(dx, dy);
  if (r_image == 0.0) {
    const double s = 1.0 / model.EquivalentScale();
    const double j[4] = {s, 0, 0, s};
    return {mm.x, mm.y, mm.cov.Transformed(j)};
  }
  const double r = model.TrueRadiusMm(r_image);
  const double k = r / r_image;
  // Radial map h(r') = r: J = (h/r') I + (h' - h/r') u u^T, h' = 1 / f'(r).
  const double h_prime = 1.0 / (1.0 + model.RadialShiftDerivative(r));
  const double ux = dx / r_image, uy = dy / r_image, q = h_prime - k;
  const double j[4] = {k + q * ux * ux, q * ux * uy, q * ux * uy, k + q * uy * uy};
  return {centre_x_mm + dx * k, centre_y_mm + dy * k, mm.cov.Transformed(j)};
}

AppliedCorrection EmulsionDepthCorrection::Record() const {
  return {"emulsion_depth",
          {{"depth_um", ShortestText(model.depth_um)},
           {"refractive_index", ShortestText(model.refractive_index)},
           {"principal_distance_mm", ShortestText(model.principal_distance_mm)},
           {"centre_x_mm", ShortestText(centre_x_mm)},
           {"centre_y_mm", ShortestText(centre_y_mm)},
           {"equivalent_scale", ShortestText(model.EquivalentScale())}}};
}

bool EmulsionDepthCorrection::Check(std::string* why) const {
  if (!(model.depth_um >= 0.0 && model.depth_um < 1000.0)) return Fail(why, "emulsion depth_um must lie in 0..1000");
  if (!(model.refractive_index >= 1.0 && model.refractive_index < 3.0)) return Fail(why, "emulsion refractive_index must lie in 1..3");
  if (!(model.principal_distance_mm > 1.0)) return Fail(why, "emulsion principal_distance_mm must exceed 1");
  return true;
}

}  // namespace platemeter
