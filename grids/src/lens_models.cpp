#include "platemeter/grids/lens_models.h"

namespace platemeter {

const std::vector<LensModelInfo>& KnownLensModels() {
  static const std::vector<LensModelInfo> models = {
      {"smac-radial-decentering",
       "seed 004 (SN-004 calibration), the dx, dy equations before Table A.4; r in mm from the principal point",
       {{"K1_per_mm2", "radial: dx = x (K1 r^2 + K2 r^4 + K3 r^6), 1/mm^2"},
        {"K2_per_mm4", "radial, 1/mm^4"},
        {"K3_per_mm6", "radial, 1/mm^6"},
        {"J1_per_mm", "decentering: (J1 r^2 + J2 r^4) times the theta0 terms, 1/mm"},
        {"J2_per_mm3", "decentering, 1/mm^3"},
        {"theta0_rad", "decentering phase angle theta0, radians"}}},
      {"brown-balanced",
       "seed 000 (Apollo 14 Hasselblad), eq. (14)-(16): balanced radial distortion "
       "dr = k0 r + k1 r^3 + k2 r^5 (mm), decentering p1, p2",
       {{"k0", "balanced radial, linear term (dimensionless)"},
        {"k1_per_mm2", "balanced radial, 1/mm^2"},
        {"k2_per_mm4", "balanced radial, 1/mm^4 (0 for the one-term Gaussian of Tables 1 and 3)"},
        {"p1_per_mm", "decentering p1, 1/mm"},
        {"p2_per_mm", "decentering p2, 1/mm"}}},
      {"brown-conrady",
       "seed 000 eq. (1): Gaussian radial k1 r^3 + k2 r^5 + k3 r^7 and decentering p1, p2 "
       "(corrections added to the measured coordinates, r in mm from the principal point)",
       {{"k1_per_mm2", "radial: dx = x (k1 r^2 + k2 r^4 + k3 r^6), 1/mm^2"},
        {"k2_per_mm4", "radial, 1/mm^4"},
        {"k3_per_mm6", "radial, 1/mm^6"},
        {"p1_per_mm", "decentering p1, 1/mm"},
        {"p2_per_mm", "decentering p2, 1/mm"}}},
      {"brown-affine",
       "seed 000 eq. (1): Gaussian radial k1 r^3 + k2 r^5 + k3 r^7 and decentering p1, p2 "
       "(corrections added to the measured coordinates, r in mm from the principal point), "
       "plus the image frame's affinity dx += b1 x + b2 y (the self-calibrating bundle's camera)",
       {{"k1_per_mm2", "radial: dx = x (k1 r^2 + k2 r^4 + k3 r^6), 1/mm^2"},
        {"k2_per_mm4", "radial, 1/mm^4"},
        {"k3_per_mm6", "radial, 1/mm^6"},
        {"p1_per_mm", "decentering p1, 1/mm"},
        {"p2_per_mm", "decentering p2, 1/mm"},
        {"b1", "affinity: x scale correction (dimensionless)"},
        {"b2", "affinity: non-orthogonality, dx = b2 y (dimensionless)"}}},
      {"orbigon-11",
       "seed 001 (Orbigon), the 11-parameter model: dR = K1 d^3 + K2 d^5 + K3 d^7, "
       "Dx, Dy = (K4 + K5 d^2)(...), d from the point of symmetry; C, xp, yp are the "
       "lens' principal distance and principal point",
       {{"xs_um", "point of symmetry x, um"},
        {"ys_um", "point of symmetry y, um"},
        {"K1_per_m2", "radial, with d in metres (the paper prints no unit), 1/m^2"},
        {"K2_per_m4", "radial, 1/m^4"},
        {"K3_per_m6", "radial, 1/m^6"},
        {"K4_per_m", "decentering, 1/m"},
        {"K5_per_m3", "decentering, 1/m^3"},
        {"Phi_T_deg", "orientation of the axis of maximum tangential distortion, degrees"}}},
  };
  return models;
}

const LensModelInfo* FindLensModel(const std::string& name) {
  for (const LensModelInfo& model : KnownLensModels()) {
    if (model.name == name) return &model;
  }
  return nullptr;
}

std::string KnownLensModelNames() {
  std::string names;
  for (const LensModelInfo& model : KnownLensModels()) {
    if (!names.empty()) names += ", ";
    names += model.name;
  }
  return names;
}

}  // namespace platemeter
