#pragma once
// The lens models the stellar calibration adjusts (stellar_plate.h,
// docs/stellar.md "Lens models"). The camera block is c_mm, xp_mm, yp_mm
// followed by the lens struct's parameters (distortion_models.h), and the
// image equation takes the direction from the struct's kDirection:
//   orbigon-11               seed 001, SlamaDistortion (kDistortion), the default
//   smac-radial-decentering  seed 004, SmacRadialDecentering (kCorrection)
//   brown-conrady            seed 000 eq. (1), BrownConrady (kCorrection)
// brown-balanced's k0 is c's scale and brown-affine's b1, b2 are the plate's
// s and epsilon: neither is determinable next to the plate's own parameters.
#include <string>
#include <vector>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/core/error.h"

namespace platemeter {

// True for kSlama, kSmacRadialDecentering and kBrownConrady.
bool IsStellarLensModel(DistortionModelId lens);
// Parses "orbigon-11", "smac-radial-decentering", "brown-conrady"; false otherwise.
bool ParseStellarLensModel(const std::string& name, DistortionModelId* lens);
// "orbigon-11, smac-radial-decentering, brown-conrady", for messages.
std::string StellarLensModelNames();
// 3 + the lens's parameter count.
int StellarCameraParamCount(DistortionModelId lens);
// "c_mm", "xp_mm", "yp_mm", then the lens's kParamNames.
std::vector<std::string> StellarCameraParamNames(DistortionModelId lens);

// A decentering term whose amplitudes multiply (cos, sin) of one angle is the
// same lens for (amplitudes, angle) and (-amplitudes, angle + pi): seed 001's
// (K4, K5, Phi_T) and seed 004's (J1, J2, theta0). Brown's p1, p2 have no such
// freedom. Indices into the camera values; angle = -1 when there is none.
struct StellarDecenteringSign {
  std::vector<int> amplitudes;
  int angle = -1;
};
StellarDecenteringSign StellarDecenteringSignOf(DistortionModelId lens);

// Calls f(Lens{}) with the lens struct of a stellar lens model, e.g. to build
// an AutoDiffCostFunction of the right camera block size. Throws
// platemeter::Error for another model.
template <typename F>
decltype(auto) VisitStellarLens(DistortionModelId lens, F&& f) {
  switch (lens) {
    case DistortionModelId::kSlama: return f(SlamaDistortion{});
    case DistortionModelId::kSmacRadialDecentering: return f(SmacRadialDecentering{});
    case DistortionModelId::kBrownConrady: return f(BrownConrady{});
    default: break;
  }
  throw Error("stellar calibration", std::string("lens model ") + DistortionModelName(lens) +
                                         " is not one the stellar calibration adjusts (" + StellarLensModelNames() + ")");
}

}  // namespace platemeter
