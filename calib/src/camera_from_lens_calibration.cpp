// Builds a CameraModel from a published LensCalibration, converting the
// published units (grids/lens_models.h keys) to the distortion models' units.
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "platemeter/calib/camera_model.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/lens_models.h"

namespace platemeter {
namespace {

struct KeyConversion {
  const char* key;  // as in LensCalibration::coefficients
  double scale;     // model unit per published unit
  bool relative_to_principal_point_x = false;  // subtract xp after scaling
  bool relative_to_principal_point_y = false;  // subtract yp after scaling
};

struct ModelKeys {
  const char* name;
  DistortionModelId id;
  std::vector<KeyConversion> keys;  // in the model's parameter order
};

const std::vector<ModelKeys>& AllModelKeys() {
  static const std::vector<ModelKeys> all = {
      {"smac-radial-decentering",
       DistortionModelId::kSmacRadialDecentering,
       {{"K1_per_mm2", 1.0},
        {"K2_per_mm4", 1.0},
        {"K3_per_mm6", 1.0},
        {"J1_per_mm", 1.0},
        {"J2_per_mm3", 1.0},
        {"theta0_rad", 1.0}}},
      {"brown-balanced",
       DistortionModelId::kBrownBalanced,
       {{"k0", 1.0}, {"k1_per_mm2", 1.0}, {"k2_per_mm4", 1.0}, {"p1_per_mm", 1.0}, {"p2_per_mm", 1.0}}},
      {"brown-conrady",
       DistortionModelId::kBrownConrady,
       {{"k1_per_mm2", 1.0}, {"k2_per_mm4", 1.0}, {"k3_per_mm6", 1.0}, {"p1_per_mm", 1.0}, {"p2_per_mm", 1.0}}},
      {"brown-affine",
       DistortionModelId::kBrownAffine,
       {{"k1_per_mm2", 1.0},
        {"k2_per_mm4", 1.0},
        {"k3_per_mm6", 1.0},
        {"p1_per_mm", 1.0},
        {"p2_per_mm", 1.0},
        {"b1", 1.0},
        {"b2", 1.0}}},
      {"orbigon-11",
       DistortionModelId::kSlama,
       {{"xs_um", 1e-3, true, false},  // um from the reseau centre -> mm from the principal point
        {"ys_um", 1e-3, false, true},
        {"K1_per_m2", 1.0},
        {"K2_per_m4", 1.0},
        {"K3_per_m6", 1.0},
        {"K4_per_m", 1.0},
        {"K5_per_m3", 1.0},
        {"Phi_T_deg", M_PI / 180.0}}},
  };
  return all;
}

}  // namespace

CameraModel CameraModelFromLensCalibration(const LensCalibration& lens, const std::string& subject) {
  const ModelKeys* keys = nullptr;
  for (const ModelKeys& candidate : AllModelKeys()) {
    if (lens.model == candidate.name) keys = &candidate;
  }
  if (keys == nullptr) {
    throw Error(subject, fmt::format("unknown lens model \"{}\" (known: {})", lens.model,
                                     KnownLensModelNames()));
  }
  std::set<std::string> expected;
  std::vector<double> params;
  for (const KeyConversion& conversion : keys->keys) {
    expected.insert(conversion.key);
    const auto found = lens.coefficients.find(conversion.key);
    if (found == lens.coefficients.end()) {
      throw Error(subject, fmt::format("lens model {} needs coefficient {}", lens.model,
                                       conversion.key));
    }
    if (!std::isfinite(found->second)) {
      throw Error(subject, fmt::format("coefficient {} is not finite", conversion.key));
    }
    double value = found->second * conversion.scale;
    if (conversion.relative_to_principal_point_x) value -= lens.principal_point_x_mm;
    if (conversion.relative_to_principal_point_y) value -= lens.principal_point_y_mm;
    params.push_back(value);
  }
  for (const auto& [key, value] : lens.coefficients) {
    if (expected.count(key) == 0) {
      throw Error(subject, fmt::format("lens model {} has no coefficient {}", lens.model, key));
    }
  }
  InteriorOrientation interior;
  interior.principal_distance_mm = lens.principal_distance_mm;
  interior.principal_point_x_mm = lens.principal_point_x_mm;
  interior.principal_point_y_mm = lens.principal_point_y_mm;
  try {
    return CameraModel(interior, keys->id, std::move(params));
  } catch (const Error& error) {
    throw Error(subject, error.reason());
  }
}

}  // namespace platemeter
