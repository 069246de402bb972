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

DistortionProfile BundleDistortionProfile(const BundleResult& result, int camera_index,
                                          const BundleReportOptions& options, std::vector<double> radii_mm) {
  const BundleCameraResult& camera = result.cameras.at(camera_index);
  DistortionProfileOptions profile_options;
  const double half_diagonal = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  if (options.balance_radius_mm) {
    profile_options.balance = RadialBalance::kZeroAtRadius;
    profile_options.balance_radius_mm = *options.balance_radius_mm;
  } else {
    profile_options.balance = RadialBalance::kEqualLobeAreas;
  }
  profile_options.max_radius_mm = half_diagonal > 0 ? half_diagonal : 1.0;
  if (radii_mm.empty()) {
    radii_mm = options.profile_radii_mm.empty() ? DefaultProfileRadii_mm(camera.format_width_mm, camera.format_height_mm)
                                                : options.profile_radii_mm;
  }
  profile_options.radii_mm = radii_mm;
  return ComputeDistortionProfile(BundleLensEstimate(result, camera), profile_options);
}

std::string BundleBalanceWords(const BundleResult& result, int camera_index, const BundleReportOptions& options) {
  const BundleCameraResult& camera = result.cameras.at(camera_index);
  const double half_diagonal = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  return options.balance_radius_mm
             ? fmt::format("balanced to zero at r = {} mm", *options.balance_radius_mm)
             : fmt::format("balanced to equal positive and negative lobe areas over 0..{:.1f} mm",
                           half_diagonal > 0 ? half_diagonal : 1.0);
}

void AppendProfileTables(const BundleResult& result, const BundleCameraResult& camera,
                         const BundleReportOptions& options, TextDocument* doc) {
  const int index = static_cast<int>(&camera - result.cameras.data());
  DistortionProfile profile;
  try {
    profile = BundleDistortionProfile(result, index, options);
  } catch (const Error& e) {
    doc->Paragraph(fmt::format("No distortion profile: {}", e.reason()));
    return;
  }
  doc->Heading(3, fmt::format("Balanced constants ({}; seed 000 eq. 14)", BundleBalanceWords(result, index, options)));
  TextTable& constants = doc->Table({"Parameter", "Value", "Std. dev."}, "lrr");
  constants.rows.push_back({"c' (mm)", fmt::format("{:.4f}", profile.calibrated_focal_length_mm.value),
                            fmt::format("±{:.4f}", profile.calibrated_focal_length_mm.sigma)});
  const char* names[4] = {"k0'", "k1' (mm^-2)", "k2' (mm^-4)", "k3' (mm^-6)"};
  for (int i = 0; i < 4; ++i) {
    const ValueWithSigma& k = profile.radial_coefficients[i];
    if (k.value != 0.0 || k.sigma != 0.0) {
      constants.rows.push_back({names[i], fmt::format("{:.5e}", k.value), fmt::format("±{:.3e}", k.sigma)});
    }
  }
  if (std::isfinite(profile.phase_angle_rad.value)) {
    constants.rows.push_back({"decentering phase angle phi0 (deg, eq. 16)",
                              fmt::format("{:.1f}", profile.phase_angle_rad.value * 180 / M_PI),
                              fmt::format("±{:.1f}", profile.phase_angle_rad.sigma * 180 / M_PI)});
  }
  doc->Heading(3, "Balanced symmetric radial and decentering distortion (seed 000 Table 2 form)");
  TextTable& rows = doc->Table({"r (mm)", "δ'r (µm)", "σδ'r (µm)", "Pr (µm)", "σPr (µm)"}, "rrrrr");
  for (const DistortionProfileRow& row : profile.rows) {
    rows.rows.push_back({fmt::format("{:.2f}", row.r_mm), fmt::format("{:.1f}", row.radial_um),
                         fmt::format("{:.1f}", row.radial_sigma_um), fmt::format("{:.1f}", row.decentering_um),
                         fmt::format("{:.1f}", row.decentering_sigma_um)});
  }
}

}  // namespace platemeter
