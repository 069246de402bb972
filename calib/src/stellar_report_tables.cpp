// report.md of a stellar calibration job: seed 001 Tables 2 and 3 (stellar_report.h).
#include <cmath>

#include <fmt/format.h>

#include "platemeter/calib/stellar_report.h"
#include "platemeter/core/text_document.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {


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

// A table with a first column of row names and one column per item.
template <typename Items, typename Cell>
void AddRow(TextTable* table, const std::string& name, const Items& items, Cell cell, int cells_per_item = 1) {
  std::vector<std::string> row{name};
  for (const auto& item : items) {
    row.push_back(cell(item));
    for (int k = 1; k < cells_per_item; ++k) row.emplace_back();
  }
  table->rows.push_back(std::move(row));
}

void Table2(DistortionModelId lens, const StellarJobResult& result, TextDocument* doc) {
  // epsilon changes sign with y in seed 001's printed frame.
  const double epsilon_sign = lens == DistortionModelId::kSlama ? -1.0 : 1.0;
  doc->Heading(2, "Single-plate calibrations (seed 001 Table 2)");
  doc->Paragraph(FrameNote(lens) + "; values +- standard errors.");
  std::vector<std::string> header{""};
  for (const auto& s : result.singles) header.push_back(s.plate_id);
  TextTable& t = doc->Table(header, "l" + std::string(result.singles.size(), 'r'));
  const auto& plates = result.singles;
  AddRow(&t, "group", plates, [](const StellarPlateResult& s) { return s.group; });
  AddRow(&t, "catalog stars", plates, [](const StellarPlateResult& s) { return std::to_string(s.catalog_stars); });
  AddRow(&t, "unknown stars", plates, [](const StellarPlateResult& s) { return std::to_string(s.unknown_stars); });
  AddRow(&t, "star images", plates, [](const StellarPlateResult& s) { return std::to_string(s.images); });
  AddRow(&t, "rejected images", plates, [](const StellarPlateResult& s) { return std::to_string(s.rejected_images); });
  AddRow(&t, "epsilon (sec arc)", plates, [&](const StellarPlateResult& s) {
    return fmt::format("{:+.2f} +- {:.2f}", epsilon_sign * s.epsilon_rad * kArcsecPerRad,
                       s.epsilon_sigma_rad * kArcsecPerRad);
  });
  AddRow(&t, "Cx (um)", plates,
         [](const StellarPlateResult& s) { return fmt::format("{:.2f} +- {:.2f}", 1e3 * s.cx_mm, 1e3 * s.cx_sigma_mm); });
  AddRow(&t, "Cy (um)", plates,
         [](const StellarPlateResult& s) { return fmt::format("{:.2f} +- {:.2f}", 1e3 * s.cy_mm, 1e3 * s.cy_sigma_mm); });
  const StellarCamera nominal = NominalStellarCamera(1.0, lens);
  const std::vector<std::string> names = ReportCamera(lens, nominal, nominal).names;
  for (int i = 1; i < static_cast<int>(names.size()); ++i) {
    AddRow(&t, names[i], plates, [&, i](const StellarPlateResult& s) {
      const ReportedCamera c = ReportCamera(lens, s.camera, s.camera_sigma);
      return Value(c, i) + " +- " + Sigma(c, i);
    });
  }
  AddRow(&t, "m_p (um)", plates, [](const StellarPlateResult& s) { return fmt::format("{:.2f}", s.m_p_um); });
  AddRow(&t, "m_o", plates, [](const StellarPlateResult& s) { return fmt::format("{:.3f}", s.m_o); });
  AddRow(&t, "degrees of freedom", plates,
         [](const StellarPlateResult& s) { return fmt::format("{:.0f}", s.adjustment.dof); });
  AddRow(&t, "orientation sets", plates,
         [](const StellarPlateResult& s) { return std::to_string(s.orientation_sets.size()); });
  AddRow(&t, "largest camera motion (sec arc)", plates,
         [](const StellarPlateResult& s) { return fmt::format("{:.2f}", s.largest_motion_arcsec); });
}

// A table with a value and an s.e. column per camera (anything with name,
// camera and camera_sigma), one row per parameter as ReportCamera gives them.
template <typename Columns>
TextTable& CameraColumns(DistortionModelId lens, const Columns& columns, TextDocument* doc) {
  std::vector<ReportedCamera> cameras;
  for (const auto& c : columns) cameras.push_back(ReportCamera(lens, c.camera, c.camera_sigma));
  std::vector<std::string> header{""};
  for (const auto& c : columns) {
    header.push_back(c.name);
    header.push_back("s.e.");
  }
  TextTable& t = doc->Table(header, "l" + std::string(2 * columns.size(), 'r'));
  for (int i = 0; i < static_cast<int>(cameras.front().names.size()); ++i) {
    std::vector<std::string> row{cameras.front().names[i]};
    for (const ReportedCamera& c : cameras) {
      row.push_back(Value(c, i));
      row.push_back(Sigma(c, i));
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

void Table3(DistortionModelId lens, const StellarJobResult& result, TextDocument* doc) {
  if (result.combinations.empty()) return;
  doc->Heading(2, "Multiple-plate calibrations (seed 001 Table 3)");
  doc->Paragraph("Pope's generalized weighted mean, relinearized until it is the simultaneous solution "
                 "(docs/stellar.md). " + FrameNote(lens) + ".");
  TextTable& t = CameraColumns(lens, result.combinations, doc);
  const auto& c = result.combinations;
  AddRow(&t, "m_o", c, [](const StellarCombination& c) { return fmt::format("{:.3f}", c.m_0); }, 2);
  AddRow(&t, "v (dof)", c, [](const StellarCombination& c) { return fmt::format("{:.0f}", c.dof); }, 2);
  AddRow(&t, "m_p (um)", c, [](const StellarCombination& c) { return fmt::format("{:.2f}", c.m_p_um); }, 2);
  AddRow(&t, "m_p^a (um)", c, [](const StellarCombination& c) { return fmt::format("{:.2f}", c.m_p_after_um); }, 2);
  AddRow(&t, "plates", c, [](const StellarCombination& c) {
    std::string s;
    for (const auto& id : c.plate_ids) s += (s.empty() ? "" : ", ") + id;
    return s;
  }, 2);
  doc->Paragraph("Consistency of each plate with its combination (F test of the camera difference):");
  std::vector<std::string> items;
  for (const auto& combination : c) {
    for (const PlateConsistency& p : combination.consistency) {
      items.push_back(fmt::format("{}: plate {}: F = {:.2f} with {} and {:.0f} dof, p = {:.3f}{}", combination.name,
                                  p.plate_id, p.f_statistic, p.k, combination.dof, p.p_value,
                                  p.rejected ? " -- INCONSISTENT" : ""));
    }
  }
  doc->List(std::move(items));
}

// A 3 x 3 matrix as a table without a header row's words.
void MatrixTable(const Eigen::Matrix3d& m, const char* format, TextDocument* doc) {
  TextTable& t = doc->Table({"", "", ""}, "rrr");
  for (int a = 0; a < 3; ++a) {
    t.rows.push_back({fmt::format(fmt::runtime(format), m(a, 0)), fmt::format(fmt::runtime(format), m(a, 1)),
                      fmt::format(fmt::runtime(format), m(a, 2))});
  }
}

// Seed 004 Tables A.4-A.6: each camera of the joint adjustment and the
// relative orientation of every other camera to camera 0.
void TableInterlock(DistortionModelId lens, const StellarInterlockResult& r, TextDocument* doc) {
  doc->Heading(2, "Cameras exposed together (seed 004 SMAC, Tables A.4-A.6)");
  doc->Paragraph(fmt::format("Joint adjustment of {} exposures: sigma0 = {:.3f} with {:.0f} degrees of freedom "
                             "(chi-square test of the a-priori sigmas: p = {:.3f}{}).",
                             r.exposures, r.adjustment.sigma0, r.adjustment.dof, r.adjustment.chi_square.p_value,
                             r.adjustment.chi_square.rejected ? ", REJECTED" : ", accepted"));
  TextTable& t = CameraColumns(lens, r.cameras, doc);
  const auto& c = r.cameras;
  AddRow(&t, "plates", c, [](const InterlockCameraResult& c) { return std::to_string(c.plates); }, 2);
  AddRow(&t, "stars", c, [](const InterlockCameraResult& c) { return std::to_string(c.stars); }, 2);
  AddRow(&t, "star images", c, [](const InterlockCameraResult& c) { return std::to_string(c.images); }, 2);
  AddRow(&t, "rejected images", c, [](const InterlockCameraResult& c) { return std::to_string(c.rejected_images); }, 2);
  AddRow(&t, "unweighted mean error (um)", c,
         [](const InterlockCameraResult& c) { return fmt::format("{:.2f}", c.rms_residual_um); }, 2);
  for (const CameraInterlockResult& i : r.interlocks) {
    doc->Paragraph(fmt::format("Relative orientation matrix from camera {} to camera {} (seed 004's sequence: omega, "
                               "phi, kappa applied to the axes of {}):",
                               i.from, i.to, i.to));
    MatrixTable(i.matrix, "{:+.8f}", doc);
    doc->Paragraph("Covariance matrix of omega, phi, kappa (rad^2):");
    MatrixTable(i.angles.covariance_rad2, "{:+.5e}", doc);
    doc->List({fmt::format("OMEGA = {}  S.D. {:.1f}\"", DmsFromRadians(i.angles.angles.omega_rad),
                           i.angles.omega_sigma_arcsec),
               fmt::format("PHI = {}  S.D. {:.1f}\"", DmsFromRadians(i.angles.angles.phi_rad),
                           i.angles.phi_sigma_arcsec),
               fmt::format("KAPPA = {}  S.D. {:.1f}\"", DmsFromRadians(i.angles.angles.kappa_rad),
                           i.angles.kappa_sigma_arcsec)});
  }
}

}  // namespace

TextDocument StellarReportDocument(const StellarJob& job, const StellarJobResult& result) {
  TextDocument doc;
  doc.Heading(1, job.title);
  std::string cameras;
  for (const CameraDefinition& c : job.cameras) cameras += (cameras.empty() ? "" : ", ") + c.name;
  doc.Paragraph(fmt::format("Camera {}; catalog {} to V = {:.1f} ({} stars, position sigma {:.2f}\"); {} plate(s).",
                            cameras, job.catalog_path, job.magnitude_limit, result.catalog.size(),
                            job.catalog_sigma_arcsec, result.singles.size()));
  std::vector<std::string> identified;
  for (size_t i = 0; i < result.identification.size(); ++i) {
    if (!result.identification[i]) continue;
    const IdentificationResult& r = *result.identification[i];
    identified.push_back(fmt::format("plate {}: {} stars identified, {} unknown ({} ambiguous); false-alarm "
                                     "probability {:.1e}; rms {:.1f}\"",
                                     result.singles[i].plate_id, r.catalog_id.size(), r.unknown.size(),
                                     r.ambiguous.size(), r.false_alarm_probability, r.rms_arcsec));
  }
  if (!identified.empty()) doc.List(std::move(identified));
  Table2(job.options.lens_model, result, &doc);
  Table3(job.options.lens_model, result, &doc);
  if (result.interlock) TableInterlock(job.options.lens_model, *result.interlock, &doc);
  return doc;
}

std::string FormatStellarMarkdown(const StellarJob& job, const StellarJobResult& result) {
  return ToMarkdown(StellarReportDocument(job, result));
}

}  // namespace platemeter
