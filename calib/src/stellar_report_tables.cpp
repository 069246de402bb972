// report.md of a stellar calibration job: seed 001 Tables 2 and 3 (stellar_report.h).
#include <cmath>

#include <fmt/format.h>

#include "platemeter/calib/stellar_report.h"

namespace platemeter {
namespace {

constexpr double kRadToArcsec = 180.0 * 3600.0 / M_PI;

// Seed 001 prints K as mantissa and power of ten ("+3.1602-1"); we print 5 significant digits.
std::string Value(const ReportedCamera& c, int i) {
  return c.exponent[i] ? fmt::format("{:+.4e}", c.value[i]) : fmt::format("{:.{}f}", c.value[i], c.decimals);
}
std::string Sigma(const ReportedCamera& c, int i) {
  return c.exponent[i] ? fmt::format("{:.2e}", c.sigma[i]) : fmt::format("{:.{}f}", c.sigma[i], c.decimals);
}

// What the camera rows are in (ReportCamera).
std::string FrameNote(DistortionModelId lens) {
  if (lens == DistortionModelId::kSlama)
    return "Seed 001's printed frame: origin at the reseau centre, left-handed as viewed on the focal plane (y down); "
           "xs, ys from the reseau centre; K1..K5 with d in metres";
  return std::string("Lens model ") + DistortionModelName(lens) +
         ", plate frame: origin at the reseau centre, x right, y up; c, xp, yp in mm, the lens's parameters in the "
         "units of their names, about the principal point";
}

void Table2(DistortionModelId lens, const StellarJobResult& result, std::string* md) {
  // epsilon changes sign with y in seed 001's printed frame.
  const double epsilon_sign = lens == DistortionModelId::kSlama ? -1.0 : 1.0;
  *md += "## Single-plate calibrations (seed 001 Table 2)\n\n";
  *md += FrameNote(lens) + "; values +- standard errors.\n\n";
  *md += "| |";
  for (const auto& s : result.singles) *md += " " + s.plate_id + " |";
  *md += "\n|---|";
  for (size_t k = 0; k < result.singles.size(); ++k) *md += "---|";
  *md += "\n";
  auto row = [&](const std::string& name, auto cell) {
    *md += "| " + name + " |";
    for (const auto& s : result.singles) *md += " " + cell(s) + " |";
    *md += "\n";
  };
  row("group", [](const StellarPlateResult& s) { return s.group; });
  row("catalog stars", [](const StellarPlateResult& s) { return std::to_string(s.catalog_stars); });
  row("unknown stars", [](const StellarPlateResult& s) { return std::to_string(s.unknown_stars); });
  row("star images", [](const StellarPlateResult& s) { return std::to_string(s.images); });
  row("rejected images", [](const StellarPlateResult& s) { return std::to_string(s.rejected_images); });
  row("epsilon (sec arc)", [&](const StellarPlateResult& s) {
    return fmt::format("{:+.2f} +- {:.2f}", epsilon_sign * s.epsilon_rad * kRadToArcsec,
                       s.epsilon_sigma_rad * kRadToArcsec);
  });
  row("Cx (um)", [](const StellarPlateResult& s) { return fmt::format("{:.2f} +- {:.2f}", 1e3 * s.cx_mm, 1e3 * s.cx_sigma_mm); });
  row("Cy (um)", [](const StellarPlateResult& s) { return fmt::format("{:.2f} +- {:.2f}", 1e3 * s.cy_mm, 1e3 * s.cy_sigma_mm); });
  const StellarCamera nominal = NominalStellarCamera(1.0, lens);
  const std::vector<std::string> names = ReportCamera(lens, nominal, nominal).names;
  for (int i = 1; i < static_cast<int>(names.size()); ++i) {
    row(names[i], [&, i](const StellarPlateResult& s) {
      const ReportedCamera c = ReportCamera(lens, s.camera, s.camera_sigma);
      return Value(c, i) + " +- " + Sigma(c, i);
    });
  }
  row("m_p (um)", [](const StellarPlateResult& s) { return fmt::format("{:.2f}", s.m_p_um); });
  row("m_o", [](const StellarPlateResult& s) { return fmt::format("{:.3f}", s.m_o); });
  row("degrees of freedom", [](const StellarPlateResult& s) { return fmt::format("{:.0f}", s.adjustment.dof); });
  row("orientation sets", [](const StellarPlateResult& s) { return std::to_string(s.orientation_sets.size()); });
  row("largest camera motion (sec arc)", [](const StellarPlateResult& s) { return fmt::format("{:.2f}", s.largest_motion_arcsec); });
  *md += "\n";
}

// A table with a value and an s.e. column per camera (anything with name,
// camera and camera_sigma), one row per parameter as ReportCamera gives them.
template <typename Columns>
void CameraColumns(DistortionModelId lens, const Columns& columns, std::string* md) {
  std::vector<ReportedCamera> cameras;
  for (const auto& c : columns) cameras.push_back(ReportCamera(lens, c.camera, c.camera_sigma));
  *md += "| |";
  for (const auto& c : columns) *md += " " + c.name + " | s.e. |";
  *md += "\n|---|";
  for (size_t k = 0; k < columns.size(); ++k) *md += "---|---|";
  *md += "\n";
  for (int i = 0; i < static_cast<int>(cameras.front().names.size()); ++i) {
    *md += "| " + cameras.front().names[i] + " |";
    for (const ReportedCamera& c : cameras) *md += " " + Value(c, i) + " | " + Sigma(c, i) + " |";
    *md += "\n";
  }
}

void Table3(DistortionModelId lens, const StellarJobResult& result, std::string* md) {
  if (result.combinations.empty()) return;
  *md += "## Multiple-plate calibrations (seed 001 Table 3)\n\n";
  *md += "Pope's generalized weighted mean, relinearized until it is the simultaneous solution (docs/stellar.md). " +
         FrameNote(lens) + ".\n\n";
  CameraColumns(lens, result.combinations, md);
  auto row = [&](const std::string& name, auto cell) {
    *md += "| " + name + " |";
    for (const auto& c : result.combinations) *md += " " + cell(c) + " | |";
    *md += "\n";
  };
  row("m_o", [](const StellarCombination& c) { return fmt::format("{:.3f}", c.m_0); });
  row("v (dof)", [](const StellarCombination& c) { return fmt::format("{:.0f}", c.dof); });
  row("m_p (um)", [](const StellarCombination& c) { return fmt::format("{:.2f}", c.m_p_um); });
  row("m_p^a (um)", [](const StellarCombination& c) { return fmt::format("{:.2f}", c.m_p_after_um); });
  row("plates", [](const StellarCombination& c) {
    std::string s;
    for (const auto& id : c.plate_ids) s += (s.empty() ? "" : ", ") + id;
    return s;
  });
  *md += "\nConsistency of each plate with its combination (F test of the camera difference):\n\n";
  for (const auto& c : result.combinations) {
    for (const PlateConsistency& t : c.consistency) {
      *md += fmt::format("- {}: plate {}: F = {:.2f} with {} and {:.0f} dof, p = {:.3f}{}\n", c.name, t.plate_id,
                         t.f_statistic, t.k, c.dof, t.p_value, t.rejected ? " -- INCONSISTENT" : "");
    }
  }
  *md += "\n";
}

// Seed 004 Tables A.4-A.6: each camera of the joint adjustment and the
// relative orientation of every other camera to camera 0.
void TableInterlock(DistortionModelId lens, const StellarInterlockResult& r, std::string* md) {
  *md += "## Cameras exposed together (seed 004 SMAC, Tables A.4-A.6)\n\n";
  *md += fmt::format("Joint adjustment of {} exposures: sigma0 = {:.3f} with {:.0f} degrees of freedom (chi-square "
                     "test of the a-priori sigmas: p = {:.3f}{}).\n\n",
                     r.exposures, r.adjustment.sigma0, r.adjustment.dof, r.adjustment.chi_square.p_value,
                     r.adjustment.chi_square.rejected ? ", REJECTED" : ", accepted");
  CameraColumns(lens, r.cameras, md);
  auto row = [&](const std::string& name, auto cell) {
    *md += "| " + name + " |";
    for (const auto& c : r.cameras) *md += " " + cell(c) + " | |";
    *md += "\n";
  };
  row("plates", [](const InterlockCameraResult& c) { return std::to_string(c.plates); });
  row("stars", [](const InterlockCameraResult& c) { return std::to_string(c.stars); });
  row("star images", [](const InterlockCameraResult& c) { return std::to_string(c.images); });
  row("rejected images", [](const InterlockCameraResult& c) { return std::to_string(c.rejected_images); });
  row("unweighted mean error (um)", [](const InterlockCameraResult& c) { return fmt::format("{:.2f}", c.rms_residual_um); });
  for (const CameraInterlockResult& i : r.interlocks) {
    *md += fmt::format("\nRelative orientation matrix from camera {} to camera {} (seed 004's sequence: omega, phi, "
                       "kappa applied to the axes of {}):\n\n",
                       i.from, i.to, i.to);
    *md += "| | | |\n|---|---|---|\n";
    for (int a = 0; a < 3; ++a) {
      *md += fmt::format("| {:+.8f} | {:+.8f} | {:+.8f} |\n", i.matrix(a, 0), i.matrix(a, 1), i.matrix(a, 2));
    }
    *md += "\nCovariance matrix of omega, phi, kappa (rad^2):\n\n| | | |\n|---|---|---|\n";
    for (int a = 0; a < 3; ++a) {
      const Eigen::Matrix3d& c = i.angles.covariance_rad2;
      *md += fmt::format("| {:+.5e} | {:+.5e} | {:+.5e} |\n", c(a, 0), c(a, 1), c(a, 2));
    }
    *md += fmt::format("\n- OMEGA = {}  S.D. {:.1f}\"\n- PHI = {}  S.D. {:.1f}\"\n- KAPPA = {}  S.D. {:.1f}\"\n",
                       DmsFromRadians(i.angles.angles.omega_rad), i.angles.omega_sigma_arcsec,
                       DmsFromRadians(i.angles.angles.phi_rad), i.angles.phi_sigma_arcsec,
                       DmsFromRadians(i.angles.angles.kappa_rad), i.angles.kappa_sigma_arcsec);
  }
  *md += "\n";
}

}  // namespace

std::string FormatStellarMarkdown(const StellarJob& job, const StellarJobResult& result) {
  std::string md = "# " + job.title + "\n\n";
  std::string cameras;
  for (const CameraDefinition& c : job.cameras) cameras += (cameras.empty() ? "" : ", ") + c.name;
  md += fmt::format("Camera {}; catalog {} to V = {:.1f} ({} stars, position sigma {:.2f}\"); {} plate(s).\n\n",
                    cameras, job.catalog_path, job.magnitude_limit, result.catalog.size(),
                    job.catalog_sigma_arcsec, result.singles.size());
  for (size_t i = 0; i < result.identification.size(); ++i) {
    if (!result.identification[i]) continue;
    const IdentificationResult& r = *result.identification[i];
    md += fmt::format("- plate {}: {} stars identified, {} unknown ({} ambiguous); false-alarm probability {:.1e}; "
                      "rms {:.1f}\"\n",
                      result.singles[i].plate_id, r.catalog_id.size(), r.unknown.size(), r.ambiguous.size(),
                      r.false_alarm_probability, r.rms_arcsec);
  }
  md += "\n";
  Table2(job.options.lens_model, result, &md);
  Table3(job.options.lens_model, result, &md);
  if (result.interlock) TableInterlock(job.options.lens_model, *result.interlock, &md);
  return md;
}

}  // namespace platemeter
