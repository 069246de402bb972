// The profile tables of the bundle's report (seed 000 Tables 2 and 4 form):
// the balanced radial and the decentering profiles of the adjusted inner cone
// with sigmas propagated through its full covariance (distortion_profile.h).
#include <cmath>

#include <fmt/format.h>

#include "bundle_report_internal.h"
#include "platemeter/calib/bundle_report.h"
#include "platemeter/calib/distortion_profile.h"
#include "platemeter/core/error.h"

namespace platemeter {

LensEstimate BundleLensEstimate(const BundleResult& result, const BundleCameraResult& camera) {
  LensEstimate lens;
  lens.model = DistortionModelId::kBrownAffine;
  lens.principal_distance_mm = camera.values[0];
  lens.params.assign(camera.values.begin() + 3, camera.values.end());
  // [c, k1, k2, k3, p1, p2, b1, b2]: xp and yp move no profile.
  std::vector<int> indices = {camera.parameter_index[0]};
  for (int i = 3; i < kBundleCameraParams; ++i) indices.push_back(camera.parameter_index[i]);
  lens.covariance = result.adjustment.Covariance(indices, true);
  return lens;
}

void AppendProfileTables(const BundleResult& result, const BundleCameraResult& camera,
                         const BundleReportOptions& options, std::string* out) {
  DistortionProfileOptions profile_options;
  const double half_diagonal = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  if (options.balance_radius_mm) {
    profile_options.balance = RadialBalance::kZeroAtRadius;
    profile_options.balance_radius_mm = *options.balance_radius_mm;
  } else {
    profile_options.balance = RadialBalance::kEqualLobeAreas;
  }
  profile_options.max_radius_mm = half_diagonal > 0 ? half_diagonal : 1.0;
  profile_options.radii_mm = options.profile_radii_mm.empty()
                                 ? DefaultProfileRadii_mm(camera.format_width_mm, camera.format_height_mm)
                                 : options.profile_radii_mm;
  DistortionProfile profile;
  try {
    profile = ComputeDistortionProfile(BundleLensEstimate(result, camera), profile_options);
  } catch (const Error& e) {
    *out += fmt::format("\nNo distortion profile: {}\n", e.reason());
    return;
  }
  const std::string balance = options.balance_radius_mm
                                  ? fmt::format("balanced to zero at r = {} mm", *options.balance_radius_mm)
                                  : fmt::format("balanced to equal positive and negative lobe areas over 0..{:.1f} mm",
                                                profile_options.max_radius_mm);
  *out += fmt::format("\n### Balanced constants ({}; seed 000 eq. 14)\n\n| Parameter | Value | Std. dev. |\n|---|---:|---:|\n",
                      balance);
  *out += fmt::format("| c' (mm) | {:.4f} | ±{:.4f} |\n", profile.calibrated_focal_length_mm.value,
                      profile.calibrated_focal_length_mm.sigma);
  const char* names[4] = {"k0'", "k1' (mm^-2)", "k2' (mm^-4)", "k3' (mm^-6)"};
  for (int i = 0; i < 4; ++i) {
    const ValueWithSigma& k = profile.radial_coefficients[i];
    if (k.value != 0.0 || k.sigma != 0.0) *out += fmt::format("| {} | {:.5e} | ±{:.3e} |\n", names[i], k.value, k.sigma);
  }
  if (std::isfinite(profile.phase_angle_rad.value)) {
    *out += fmt::format("| decentering phase angle phi0 (deg, eq. 16) | {:.1f} | ±{:.1f} |\n",
                        profile.phase_angle_rad.value * 180 / M_PI, profile.phase_angle_rad.sigma * 180 / M_PI);
  }
  *out += "\n### Balanced symmetric radial and decentering distortion (seed 000 Table 2 form)\n\n"
          "| r (mm) | δ'r (µm) | σδ'r (µm) | Pr (µm) | σPr (µm) |\n|---:|---:|---:|---:|---:|\n";
  for (const DistortionProfileRow& row : profile.rows) {
    *out += fmt::format("| {:.2f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} |\n", row.r_mm, row.radial_um,
                        row.radial_sigma_um, row.decentering_um, row.decentering_sigma_um);
  }
}

}  // namespace platemeter
