#include "platemeter/calib/distortion_models.h"

#include <cmath>

namespace platemeter {

double BalancedRadialDistortion_mm(double k0, double k1_per_mm2, double k2_per_mm4, double r_mm) {
  const double r2 = r_mm * r_mm;
  return r_mm * (k0 + r2 * (k1_per_mm2 + r2 * k2_per_mm4));
}

double DecenteringProfile_mm(double p1_per_mm, double p2_per_mm, double r_mm) {
  return std::hypot(p1_per_mm, p2_per_mm) * r_mm * r_mm;
}

double DecenteringPhaseAngle_rad(double p1_per_mm, double p2_per_mm) {
  return std::atan2(-p1_per_mm, p2_per_mm);
}

bool DistortionInverseOptions::Check(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (!(tolerance_mm > 0.0)) return fail("tolerance_mm must be positive");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!(jacobian_step_mm > 0.0) || !(jacobian_step_mm < 1.0)) {
    return fail("jacobian_step_mm must be in (0, 1) mm");
  }
  return true;
}

const char* DistortionModelName(DistortionModelId id) {
  return VisitDistortionModel(id, [](auto model) { return decltype(model)::Name(); });
}

int DistortionModelNumParams(DistortionModelId id) {
  return VisitDistortionModel(id, [](auto model) { return decltype(model)::kNumParams; });
}

std::vector<std::string> DistortionModelParamNames(DistortionModelId id) {
  return VisitDistortionModel(id, [](auto model) {
    using Model = decltype(model);
    return std::vector<std::string>(Model::kParamNames.begin(), Model::kParamNames.end());
  });
}

bool ParseDistortionModel(const std::string& name, DistortionModelId* id) {
  for (DistortionModelId candidate :
       {DistortionModelId::kNone, DistortionModelId::kSmacRadialDecentering,
        DistortionModelId::kBrownConrady, DistortionModelId::kBrownBalanced,
        DistortionModelId::kSlama, DistortionModelId::kBrownAffine}) {
    if (name == DistortionModelName(candidate)) {
      *id = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace platemeter
