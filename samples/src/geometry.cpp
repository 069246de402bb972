// The simulator's geometry chain (docs/simulator.md).
#include "platemeter/samples/geometry.h"

#include <cmath>
#include <numbers>

#include "platemeter/core/error.h"
#include "platemeter/core/why.h"
#include "platemeter/core/angles.h"

namespace platemeter::sim {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

PlatePoint Apply(const Matrix2& m, PlatePoint p) {
  return {m.a[0] * p.x_mm + m.a[1] * p.y_mm, m.a[2] * p.x_mm + m.a[3] * p.y_mm};
}

Matrix2 Rotation(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return Matrix2{{c, -s, s, c}};
}

// Exact quarter turns (no rounding in cos(pi/2)).
Matrix2 QuarterTurns(int orientation_deg) {
  switch (((orientation_deg % 360) + 360) % 360) {
    case 90: return Matrix2{{0, -1, 1, 0}};
    case 180: return Matrix2{{-1, 0, 0, -1}};
    case 270: return Matrix2{{0, 1, -1, 0}};
    default: return Matrix2{{1, 0, 0, 1}};
  }
}

}  // namespace

Matrix2 Matrix2::operator*(const Matrix2& b) const {
  return Matrix2{{a[0] * b.a[0] + a[1] * b.a[2], a[0] * b.a[1] + a[1] * b.a[3], a[2] * b.a[0] + a[3] * b.a[2],
                  a[2] * b.a[1] + a[3] * b.a[3]}};
}

Matrix2 Matrix2::operator*(double s) const { return Matrix2{{a[0] * s, a[1] * s, a[2] * s, a[3] * s}}; }

Matrix2 Matrix2::Inverse() const {
  const double det = Determinant();
  return Matrix2{{a[3] / det, -a[1] / det, -a[2] / det, a[0] / det}};
}

// ---- thermal

PlatePoint ThermalStep::Forward(PlatePoint p) const { return {p.x_mm * Scale(), p.y_mm * Scale()}; }
PlatePoint ThermalStep::Inverse(PlatePoint p) const { return {p.x_mm / Scale(), p.y_mm / Scale()}; }
Matrix2 ThermalStep::Jacobian(PlatePoint) const { return Matrix2{{Scale(), 0, 0, Scale()}}; }

bool ThermalStep::Check(std::string* why) const {
  if (!std::isfinite(temperature_degC) || temperature_degC < -100 || temperature_degC > 100) {
    return Fail(why, "thermal temperature_degC must lie in -100..100");
  }
  if (!std::isfinite(calibration_temperature_degC) || calibration_temperature_degC < -100 ||
      calibration_temperature_degC > 100) {
    return Fail(why, "thermal calibration_temperature_degC must lie in -100..100");
  }
  if (!std::isfinite(expansion_per_degC) || std::abs(expansion_per_degC) > 1e-3) {
    return Fail(why, "thermal expansion_per_degC must lie in -1e-3..1e-3");
  }
  return true;
}

// ---- emulsion depth

// The radial model lives in measure/emulsion_depth.h (shared with the corrections).
EmulsionDepthModel EmulsionDepthStep::Model() const { return {depth_um, refractive_index, principal_distance_mm}; }

double EmulsionDepthStep::RadialShiftMm(double r_mm) const { return Model().RadialShiftMm(r_mm); }

double EmulsionDepthStep::EquivalentScale() const { return Model().EquivalentScale(); }

double EmulsionDepthStep::DepthUmFromEquivalentScale(double scale, double refractive_index,
                                                     double principal_distance_mm) {
  return EmulsionDepthModel::DepthUmFromEquivalentScale(scale, refractive_index, principal_distance_mm);
}

namespace {
std::vector<double> RadiiMm(const std::vector<PlatePoint>& points, PlatePoint centre) {
  std::vector<double> radii;
  for (const PlatePoint& p : points) radii.push_back(std::hypot(p.x_mm - centre.x_mm, p.y_mm - centre.y_mm));
  return radii;
}
}  // namespace

double EmulsionDepthStep::FittedScale(const std::vector<PlatePoint>& points) const {
  return Model().FittedScale(RadiiMm(points, principal_point_mm));
}

double EmulsionDepthStep::DepthUmFromFittedScale(double scale, const std::vector<PlatePoint>& points) const {
  return Model().DepthUmFromFittedScale(scale, RadiiMm(points, principal_point_mm));
}

PlatePoint EmulsionDepthStep::Forward(PlatePoint p) const {
  const double dx = p.x_mm - principal_point_mm.x_mm, dy = p.y_mm - principal_point_mm.y_mm;
  const double r = std::hypot(dx, dy);
  if (r == 0.0 || depth_um == 0.0) return p;
  const double factor = 1.0 + RadialShiftMm(r) / r;
  return {principal_point_mm.x_mm + dx * factor, principal_point_mm.y_mm + dy * factor};
}

PlatePoint EmulsionDepthStep::Inverse(PlatePoint q) const {
  const double dx = q.x_mm - principal_point_mm.x_mm, dy = q.y_mm - principal_point_mm.y_mm;
  const double r_image = std::hypot(dx, dy);
  if (r_image == 0.0 || depth_um == 0.0) return q;
  const double factor = Model().TrueRadiusMm(r_image) / r_image;
  return {principal_point_mm.x_mm + dx * factor, principal_point_mm.y_mm + dy * factor};
}

Matrix2 EmulsionDepthStep::Jacobian(PlatePoint p) const {
  const double dx = p.x_mm - principal_point_mm.x_mm, dy = p.y_mm - principal_point_mm.y_mm;
  const double r = std::hypot(dx, dy);
  const double n = refractive_index, c = principal_distance_mm, d_mm = depth_um * 1e-3;
  if (r == 0.0) {
    const double s0 = 1.0 + d_mm / (n * c);
    return Matrix2{{s0, 0, 0, s0}};
  }
  // Radial map f(r) = r + g(r): J = (f/r) I + (f' - f/r) u u^T, u = p / r.
  const double f_over_r = 1.0 + RadialShiftMm(r) / r;
  const double f_prime = 1.0 + Model().RadialShiftDerivative(r);
  const double ux = dx / r, uy = dy / r, k = f_prime - f_over_r;
  return Matrix2{{f_over_r + k * ux * ux, k * ux * uy, k * ux * uy, f_over_r + k * uy * uy}};
}

bool EmulsionDepthStep::Check(std::string* why) const {
  if (!std::isfinite(depth_um) || depth_um < 0 || depth_um > 1000) {
    return Fail(why, "emulsion depth_um must lie in 0..1000");
  }
  if (!std::isfinite(refractive_index) || refractive_index < 1.0 || refractive_index > 3.0) {
    return Fail(why, "emulsion refractive_index must lie in 1..3");
  }
  if (!std::isfinite(principal_distance_mm) || principal_distance_mm <= 1.0) {
    return Fail(why, "emulsion principal_distance_mm must be greater than 1");
  }
  if (!std::isfinite(principal_point_mm.x_mm) || !std::isfinite(principal_point_mm.y_mm)) {
    return Fail(why, "emulsion principal point must be finite");
  }
  return true;
}

// ---- film deformation

PlatePoint FilmDeformationStep::DisplacementUm(PlatePoint p) const {
  const double* a = affine_ppm;
  double ux = shift_um[0] + 1e-3 * (a[0] * p.x_mm + a[1] * p.y_mm);  // ppm * mm = 1e-3 um
  double uy = shift_um[1] + 1e-3 * (a[2] * p.x_mm + a[3] * p.y_mm);
  for (const FilmWave& w : waves) {
    const double dir = w.direction_deg * kDegToRad;
    const double s = p.x_mm * std::cos(dir) + p.y_mm * std::sin(dir);
    const double value = std::sin(2 * std::numbers::pi * s / w.wavelength_mm + w.phase_deg * kDegToRad);
    ux += w.amplitude_x_um * value;
    uy += w.amplitude_y_um * value;
  }
  const double x = p.x_mm / normalization_mm, y = p.y_mm / normalization_mm;
  for (const FilmPolynomialTerm& t : polynomial) {
    const double value = std::pow(x, t.power_x) * std::pow(y, t.power_y);
    ux += t.amplitude_x_um * value;
    uy += t.amplitude_y_um * value;
  }
  return {ux, uy};
}

PlatePoint FilmDeformationStep::Forward(PlatePoint p) const {
  const PlatePoint d = DisplacementUm(p);
  return {p.x_mm + 1e-3 * d.x_mm, p.y_mm + 1e-3 * d.y_mm};
}

PlatePoint FilmDeformationStep::Inverse(PlatePoint q) const {
  // Newton on p + D(p) = q, starting from q; D is micrometres on millimetres, so
  // the Jacobian is the identity to ~1e-4 and two or three steps suffice.
  PlatePoint p = q;
  for (int i = 0; i < 50; ++i) {
    const PlatePoint f = Forward(p);
    const PlatePoint residual{f.x_mm - q.x_mm, f.y_mm - q.y_mm};
    const PlatePoint step = Apply(Jacobian(p).Inverse(), residual);
    p.x_mm -= step.x_mm;
    p.y_mm -= step.y_mm;
    if (std::abs(step.x_mm) + std::abs(step.y_mm) < 1e-15 * (1.0 + std::abs(q.x_mm) + std::abs(q.y_mm))) break;
  }
  return p;
}

Matrix2 FilmDeformationStep::Jacobian(PlatePoint p) const {
  double j[4] = {1e-6 * affine_ppm[0], 1e-6 * affine_ppm[1], 1e-6 * affine_ppm[2], 1e-6 * affine_ppm[3]};
  for (const FilmWave& w : waves) {
    const double dir = w.direction_deg * kDegToRad;
    const double s = p.x_mm * std::cos(dir) + p.y_mm * std::sin(dir);
    const double k = 2 * std::numbers::pi / w.wavelength_mm;
    const double derivative = std::cos(k * s + w.phase_deg * kDegToRad) * k;  // per mm of s
    const double ds_dx = std::cos(dir), ds_dy = std::sin(dir);
    j[0] += 1e-3 * w.amplitude_x_um * derivative * ds_dx;
    j[1] += 1e-3 * w.amplitude_x_um * derivative * ds_dy;
    j[2] += 1e-3 * w.amplitude_y_um * derivative * ds_dx;
    j[3] += 1e-3 * w.amplitude_y_um * derivative * ds_dy;
  }
  const double R = normalization_mm, x = p.x_mm / R, y = p.y_mm / R;
  for (const FilmPolynomialTerm& t : polynomial) {
    const double d_dx = t.power_x == 0 ? 0.0 : t.power_x * std::pow(x, t.power_x - 1) * std::pow(y, t.power_y) / R;
    const double d_dy = t.power_y == 0 ? 0.0 : t.power_y * std::pow(x, t.power_x) * std::pow(y, t.power_y - 1) / R;
    j[0] += 1e-3 * t.amplitude_x_um * d_dx;
    j[1] += 1e-3 * t.amplitude_x_um * d_dy;
    j[2] += 1e-3 * t.amplitude_y_um * d_dx;
    j[3] += 1e-3 * t.amplitude_y_um * d_dy;
  }
  return Matrix2{{1.0 + j[0], j[1], j[2], 1.0 + j[3]}};
}

bool FilmDeformationStep::Check(std::string* why) const {
  for (double a : affine_ppm) {
    if (!std::isfinite(a) || std::abs(a) > 1e4) return Fail(why, "film affine_ppm entries must lie in -1e4..1e4");
  }
  for (double s : shift_um) {
    if (!std::isfinite(s) || std::abs(s) > 1e4) return Fail(why, "film shift_um must lie in -1e4..1e4");
  }
  if (!std::isfinite(normalization_mm) || normalization_mm <= 0) {
    return Fail(why, "film normalization_mm must be positive");
  }
  for (const FilmWave& w : waves) {
    if (!std::isfinite(w.amplitude_x_um) || !std::isfinite(w.amplitude_y_um) || std::abs(w.amplitude_x_um) > 100 ||
        std::abs(w.amplitude_y_um) > 100) {
      return Fail(why, "film wave amplitudes must lie in -100..100 um");
    }
    if (!std::isfinite(w.wavelength_mm) || w.wavelength_mm < 5.0) {
      return Fail(why, "film wave wavelength_mm must be at least 5 (a smooth field)");
    }
    if (!std::isfinite(w.direction_deg) || !std::isfinite(w.phase_deg)) {
      return Fail(why, "film wave direction_deg and phase_deg must be finite");
    }
  }
  for (const FilmPolynomialTerm& t : polynomial) {
    if (t.power_x < 0 || t.power_y < 0 || t.power_x + t.power_y > 5) {
      return Fail(why, "film polynomial powers must be >= 0 with power_x + power_y <= 5");
    }
    if (!std::isfinite(t.amplitude_x_um) || !std::isfinite(t.amplitude_y_um) || std::abs(t.amplitude_x_um) > 100 ||
        std::abs(t.amplitude_y_um) > 100) {
      return Fail(why, "film polynomial amplitudes must lie in -100..100 um");
    }
  }
  return true;
}

// ---- scanner

Matrix2 ScannerStep::PixelPerMm() const {
  const double eps = non_orthogonality_arcsec * kRadPerArcsec;
  const double width_mm = pixel_size_um * 1e-3, height_mm = pixel_size_um * pixel_aspect * 1e-3;
  const Matrix2 oblique{{1.0 / width_mm, std::tan(eps) / width_mm, 0.0, -1.0 / (std::cos(eps) * height_mm)}};
  const Matrix2 mirror{{mirrored ? -1.0 : 1.0, 0.0, 0.0, 1.0}};
  return oblique * Rotation(rotation_deg * kDegToRad) * QuarterTurns(orientation_deg) * mirror;
}

PixelPoint ScannerStep::Forward(PlatePoint p) const {
  const PlatePoint q = Apply(PixelPerMm(), p);
  return {origin_px.x_px + q.x_mm, origin_px.y_px + q.y_mm};
}

PlatePoint ScannerStep::Inverse(PixelPoint q) const {
  return Apply(PixelPerMm().Inverse(), PlatePoint{q.x_px - origin_px.x_px, q.y_px - origin_px.y_px});
}

bool ScannerStep::Check(std::string* why) const {
  if (!std::isfinite(pixel_size_um) || pixel_size_um <= 0 || pixel_size_um > 1000) {
    return Fail(why, "scanner pixel_size_um must lie in (0, 1000]");
  }
  if (!std::isfinite(pixel_aspect) || pixel_aspect < 0.5 || pixel_aspect > 2.0) {
    return Fail(why, "scanner pixel_aspect must lie in 0.5..2");
  }
  if (!std::isfinite(rotation_deg) || std::abs(rotation_deg) > 45) {
    return Fail(why, "scanner rotation_deg must lie in -45..45 (use orientation_deg for quarter turns)");
  }
  if (!std::isfinite(non_orthogonality_arcsec) || std::abs(non_orthogonality_arcsec) > 3600) {
    return Fail(why, "scanner non_orthogonality_arcsec must lie in -3600..3600");
  }
  if (orientation_deg != 0 && orientation_deg != 90 && orientation_deg != 180 && orientation_deg != 270) {
    return Fail(why, "scanner orientation_deg must be 0, 90, 180 or 270");
  }
  if (!std::isfinite(origin_px.x_px) || !std::isfinite(origin_px.y_px)) {
    return Fail(why, "scanner origin_px must be finite");
  }
  return true;
}

// ---- chain

PixelPoint GeometryChain::PixelFromPlate(PlatePoint p) const {
  return scanner.Forward(film.Forward(emulsion.Forward(thermal.Forward(p))));
}

PlatePoint GeometryChain::PlateFromPixel(PixelPoint q) const {
  return thermal.Inverse(emulsion.Inverse(film.Inverse(scanner.Inverse(q))));
}

Matrix2 GeometryChain::PixelFromPlateJacobian(PlatePoint p) const {
  const PlatePoint p1 = thermal.Forward(p);
  const PlatePoint p2 = emulsion.Forward(p1);
  return scanner.PixelPerMm() * film.Jacobian(p2) * emulsion.Jacobian(p1) * thermal.Jacobian(p);
}

Matrix2 GeometryChain::PxFromUm(PlatePoint p) const { return PixelFromPlateJacobian(p) * 1e-3; }

bool GeometryChain::Check(std::string* why) const {
  return thermal.Check(why) && emulsion.Check(why) && film.Check(why) && scanner.Check(why);
}

}  // namespace platemeter::sim
