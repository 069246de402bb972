// CameraSetupFromDefinition (bundle_input_io.h): a camera definition's lens as
// the bundle's camera (c, xp, yp and BrownAffine's seven), exact where the
// models allow, fitted (with the fit's residual) otherwise.
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

enum Index { kC, kXp, kYp, kK1, kK2, kK3, kP1, kP2, kB1, kB2 };

double Coefficient(const LensCalibration& lens, const char* key, const std::string& subject) {
  const auto it = lens.coefficients.find(key);
  if (it == lens.coefficients.end() || !std::isfinite(it->second)) {
    throw Error(subject, "lens model " + lens.model + " needs a finite coefficient " + key);
  }
  return it->second;
}

std::string Um(double mm) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g um", mm * 1000.0);
  return buffer;
}

// Least-squares BrownAffine (and the principal distance) for any lens model:
// measured + dx_BA(measured) = (c_new / c) * ideal(measured) over a 21 x 21 grid
// of the format, linear in (c_new / c, k1..b2).
void FitBrownAffine(const LensCalibration& lens, double width_mm, double height_mm, const std::string& subject,
                    std::array<double, kBundleCameraParams>* values, std::string* note) {
  const CameraModel model = CameraModelFromLensCalibration(lens, subject);
  constexpr int kGrid = 21;
  Eigen::MatrixXd a(2 * kGrid * kGrid, 8);
  Eigen::VectorXd b(2 * kGrid * kGrid);
  int row = 0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const Eigen::Vector2d plate(width_mm * (i / (kGrid - 1.0) - 0.5), height_mm * (j / (kGrid - 1.0) - 0.5));
      const std::optional<Eigen::Vector2d> ideal = model.IdealFromMeasured(plate);
      if (!ideal) continue;
      const double xb = plate.x() - lens.principal_point_x_mm;
      const double yb = plate.y() - lens.principal_point_y_mm;
      a(row, 0) = -ideal->x();
      a(row + 1, 0) = -ideal->y();
      for (int k = 0; k < BrownAffine::kNumParams; ++k) {
        double unit[BrownAffine::kNumParams] = {};
        unit[k] = 1.0;
        double dx = 0.0, dy = 0.0;
        BrownAffine::Apply(unit, xb, yb, &dx, &dy);
        a(row, 1 + k) = dx;
        a(row + 1, 1 + k) = dy;
      }
      b(row) = -xb;
      b(row + 1) = -yb;
      row += 2;
    }
  }
  if (row < 16) throw Error(subject, "lens model " + lens.model + " cannot be inverted over the format");
  a.conservativeResize(row, Eigen::NoChange);
  b.conservativeResize(row);
  const Eigen::VectorXd scale = a.colwise().norm().transpose();
  const Eigen::MatrixXd scaled = a * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd q = scaled.colPivHouseholderQr().solve(b).cwiseQuotient(scale);
  const Eigen::VectorXd residual = a * q - b;
  double max_mm = 0.0, sum2 = 0.0;
  for (int r = 0; r < row; r += 2) {
    const double d = std::hypot(residual(r), residual(r + 1));
    max_mm = std::max(max_mm, d);
    sum2 += d * d;
  }
  (*values)[kC] = q(0) * lens.principal_distance_mm;
  for (int k = 0; k < BrownAffine::kNumParams; ++k) (*values)[kK1 + k] = q(1 + k);
  char format[64];
  std::snprintf(format, sizeof(format), "%g x %g mm", width_mm, height_mm);
  *note = "lens model " + lens.model + " has no exact brown-affine form: fitted over the " + format +
          " format, RMS " + Um(std::sqrt(sum2 / (row / 2))) + ", largest " + Um(max_mm) +
          " (initial values only: free or weight the parameters)";
}

}  // namespace

CameraSetup CameraSetupFromDefinition(const CameraDefinition& definition, const std::string& name,
                                      std::vector<BundleWarning>* warnings) {
  CameraSetup camera;
  camera.name = name.empty() ? definition.name : name;
  camera.format_width_mm = definition.format_width_mm;
  camera.format_height_mm = definition.format_height_mm;
  camera.definition = definition;
  const std::string subject = "camera " + definition.name;
  auto warn = [&](const std::string& reason) {
    if (warnings != nullptr) warnings->push_back({"camera " + camera.name, reason});
  };
  if (!definition.lens) {
    camera.values[kC] = definition.nominal_principal_distance_mm;
    return camera;
  }
  const LensCalibration& lens = *definition.lens;
  camera.values[kC] = lens.principal_distance_mm;
  camera.values[kXp] = lens.principal_point_x_mm;
  camera.values[kYp] = lens.principal_point_y_mm;
  if (lens.model == "brown-affine") {
    const char* keys[] = {"k1_per_mm2", "k2_per_mm4", "k3_per_mm6", "p1_per_mm", "p2_per_mm", "b1", "b2"};
    for (int k = 0; k < 7; ++k) camera.values[kK1 + k] = Coefficient(lens, keys[k], subject);
  } else if (lens.model == "brown-balanced") {
    // x (1 + k0') + x (k1' r^2 + k2' r^4) + dec' = c' u/w; divided by (1 + k0'):
    // the Gaussian form with c = c' / (1 + k0').
    const double k0 = Coefficient(lens, "k0", subject);
    if (!(1.0 + k0 > 0.0)) throw Error(subject, "lens k0 must be greater than -1");
    const double f = 1.0 / (1.0 + k0);
    camera.values[kC] = lens.principal_distance_mm * f;
    camera.values[kK1] = Coefficient(lens, "k1_per_mm2", subject) * f;
    camera.values[kK2] = Coefficient(lens, "k2_per_mm4", subject) * f;
    camera.values[kP1] = Coefficient(lens, "p1_per_mm", subject) * f;
    camera.values[kP2] = Coefficient(lens, "p2_per_mm", subject) * f;
  } else if (lens.model == "smac-radial-decentering") {
    camera.values[kK1] = Coefficient(lens, "K1_per_mm2", subject);
    camera.values[kK2] = Coefficient(lens, "K2_per_mm4", subject);
    camera.values[kK3] = Coefficient(lens, "K3_per_mm6", subject);
    const double j1 = Coefficient(lens, "J1_per_mm", subject);
    const double j2 = Coefficient(lens, "J2_per_mm3", subject);
    const double theta0 = Coefficient(lens, "theta0_rad", subject);
    camera.values[kP1] = -j1 * std::sin(theta0);
    camera.values[kP2] = j1 * std::cos(theta0);
    if (j2 != 0.0) {
      // The dropped term at the format's corner (or at c if the format is unknown).
      const double half_x = definition.format_width_mm > 0 ? definition.format_width_mm / 2 : lens.principal_distance_mm;
      const double half_y = definition.format_height_mm > 0 ? definition.format_height_mm / 2 : lens.principal_distance_mm;
      const double params[6] = {0, 0, 0, 0, j2, theta0};
      double dx = 0.0, dy = 0.0;
      SmacRadialDecentering::Apply(params, half_x, half_y, &dx, &dy);
      warn("lens model smac-radial-decentering: J2 (an r^4 decentering profile brown-affine lacks) is dropped; "
           "it moves the format's corner by " + Um(std::hypot(dx, dy)));
    }
  } else {
    double width = definition.format_width_mm, height = definition.format_height_mm;
    if (!(width > 0.0) || !(height > 0.0)) {
      width = height = lens.principal_distance_mm;  // a 53 degree field when the format is unknown
    }
    std::string note;
    FitBrownAffine(lens, width, height, subject, &camera.values, &note);
    warn(note);
  }
  return camera;
}

}  // namespace platemeter
