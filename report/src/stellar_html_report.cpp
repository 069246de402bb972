// FormatStellarHtmlReport (stellar_html_report.h): the page, the certificates
// and the plot files.
#include "platemeter/report/stellar_html_report.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "platemeter/calib/distortion_profile.h"
#include "platemeter/calib/stellar_distortion.h"
#include "platemeter/calib/stellar_report.h"
#include "platemeter/core/error.h"
#include "platemeter/core/version.h"
#include "platemeter/report/certificate.h"
#include "stellar_figures.h"

namespace platemeter::report {
namespace {

// The four corner crosses of a grid, labelled with their numbers (ids).
std::vector<PlotLabel> CornerLabels(const MasterGrid* grid) {
  std::vector<PlotLabel> labels;
  if (grid == nullptr) return labels;
  for (int i : {1, grid->columns}) {
    for (int j : {1, grid->rows}) {
      if (const GridPoint* p = grid->Find(fmt::format("X{}Y{}", i, j))) labels.push_back({p->x_mm, p->y_mm, p->id});
    }
  }
  return labels;
}

StellarReportContext MakeContext(const StellarJob& job, const StellarJobResult& result,
                                 const std::vector<const MasterGrid*>& grids, const StellarHtmlOptions& options) {
  StellarReportContext c{job, result, options, {}, {}, {}};
  for (size_t k = 0; k < job.cameras.size(); ++k) {
    const CameraDefinition& d = job.cameras[k];
    c.corner_labels.push_back(CornerLabels(k < grids.size() ? grids[k] : nullptr));
    // The format, centred on the reseau origin; unknown: the images' extent.
    c.x_mm.push_back(d.format_width_mm > 0 ? AxisRange{-d.format_width_mm / 2, d.format_width_mm / 2} : AxisRange{});
    c.y_mm.push_back(d.format_height_mm > 0 ? AxisRange{-d.format_height_mm / 2, d.format_height_mm / 2}
                                            : AxisRange{});
  }
  return c;
}

double SumSigma(const Eigen::MatrixXd& covariance, int a, int b) {
  const double v = covariance(a, a) + covariance(b, b) + 2 * covariance(a, b);
  return std::sqrt(std::max(0.0, v));
}

// The certificate of camera k: its last combination, or its first plate.
Certificate StellarCertificate(const StellarJob& job, const StellarJobResult& result, int k) {
  const CameraDefinition& camera = job.cameras[k];
  const DistortionModelId model = job.options.lens_model;
  Certificate c;
  c.camera = camera.name + (camera.description.empty() ? "" : " — " + camera.description);
  c.issued_by = std::string("platemeter ") + kVersion;
  StellarLensEstimate lens;
  std::string solution;
  std::vector<std::string> plate_ids;
  for (size_t i = 0; i < result.combinations.size(); ++i) {
    if (result.combination_camera[i] != k) continue;
    lens = CombinationLensEstimate(result.combinations[i], model);
    solution = fmt::format("the weighted mean of plates (combination {}, m_o = {:.3f} with {:.0f} degrees of "
                           "freedom)",
                           result.combinations[i].name, result.combinations[i].m_0, result.combinations[i].dof);
    plate_ids = result.combinations[i].plate_ids;
  }
  for (size_t i = 0; lens.values.empty() && i < result.singles.size(); ++i) {
    if (job.plates[i].camera != k) continue;
    lens = PlateLensEstimate(result.singles[i], model);
    solution = fmt::format("plate {} (m_o = {:.3f} with {:.0f} degrees of freedom)", result.singles[i].plate_id,
                           result.singles[i].m_o, result.singles[i].adjustment.dof);
    plate_ids = {result.singles[i].plate_id};
  }
  if (lens.values.empty()) throw Error("stellar certificate", "camera " + camera.name + " has no calibrated plate");
  c.method = "Stellar calibration (seed 001), lens model " + std::string(DistortionModelName(model)) + ": " + solution;
  const double corner = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  const double max_mm = corner > 0 ? corner : 0.7 * lens.values[0];
  const StellarProfile whole = ComputeStellarProfile(lens, max_mm, 2);
  const double sigma = std::sqrt(std::max(0.0, lens.covariance(0, 0)));
  c.elements.push_back({"Calibrated focal length C' (equal-area radial distortion)", whole.transformed_focal_length_mm,
                        whole.transformed_focal_length_sigma_mm, "mm", 5});
  c.elements.push_back({"Primary focal length C", lens.values[0], sigma, "mm", 5});
  c.elements.push_back({"Principal point x (from the reseau centre)", 1e3 * lens.values[1],
                        1e3 * std::sqrt(std::max(0.0, lens.covariance(1, 1))), "µm", 2});
  c.elements.push_back({"Principal point y", 1e3 * lens.values[2], 1e3 * std::sqrt(std::max(0.0, lens.covariance(2, 2))),
                        "µm", 2});
  if (model == DistortionModelId::kSlama) {
    c.elements.push_back({"Point of symmetry x (from the reseau centre)", 1e3 * (lens.values[1] + lens.values[3]),
                          1e3 * SumSigma(lens.covariance, 1, 3), "µm", 1});
    c.elements.push_back({"Point of symmetry y", 1e3 * (lens.values[2] + lens.values[4]),
                          1e3 * SumSigma(lens.covariance, 2, 4), "µm", 1});
  }
  std::vector<double> distances;
  const std::vector<double> angles = CertificateFieldAngles_deg(whole.transformed_focal_length_mm, max_mm);
  for (double a : angles) distances.push_back(whole.transformed_focal_length_mm * std::tan(a * M_PI / 180.0));
  const StellarProfile table = ComputeStellarProfile(lens, max_mm, distances);
  for (size_t i = 0; i < angles.size(); ++i) {
    const StellarProfileRow& r = table.rows[i];
    c.distortion.push_back({angles[i], r.d_mm, r.transformed_um, r.transformed_sigma_um, r.decentering_um,
                            r.decentering_sigma_um});
  }
  c.distortion_words = fmt::format(
      "Radial distortion referred to the calibrated focal length C' (the positive and negative lobes enclose equal "
      "areas out to {:.1f} mm, seed 001 Fig. 8), at the distance C' tan(field angle) from the point of symmetry; "
      "decentering: the largest tangential component at that distance. Plate frame: x right, y up.",
      max_mm);
  long images = 0, rejected = 0, catalog_stars = 0, unknown = 0;
  for (size_t i = 0; i < result.singles.size(); ++i) {
    if (std::find(plate_ids.begin(), plate_ids.end(), result.singles[i].plate_id) == plate_ids.end()) continue;
    images += result.singles[i].images;
    rejected += result.singles[i].rejected_images;
    catalog_stars += result.singles[i].catalog_stars;
    unknown += result.singles[i].unknown_stars;
  }
  std::string plates;
  for (const std::string& id : plate_ids) plates += (plates.empty() ? "" : ", ") + id;
  c.data_used = {fmt::format("{} plate(s): {}", plate_ids.size(), plates),
                 fmt::format("{} star images ({} rejected by data snooping), {} catalog stars and {} unknown stars "
                             "summed over the plates",
                             images, rejected, catalog_stars, unknown),
                 fmt::format("catalog {} to V = {:.1f}, position sigma {:.2f}\"", job.catalog_path,
                             job.magnitude_limit, job.catalog_sigma_arcsec),
                 "Job: " + job.path};
  return c;
}

}  // namespace

bool StellarHtmlOptions::Check(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (subtrail_images < 1) return fail("subtrail_images must be >= 1");
  if (field_grid < 2) return fail("field_grid must be >= 2");
  if (profile_samples < 2) return fail("profile_samples must be >= 2");
  if (max_vectors_per_panel < 1) return fail("max_vectors_per_panel must be >= 1");
  return true;
}

std::vector<std::pair<std::string, std::string>> FormatStellarHtmlReport(const StellarJob& job,
                                                                         const StellarJobResult& result,
                                                                         const std::vector<const MasterGrid*>& grids,
                                                                         const StellarHtmlOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("stellar HTML report options", why);
  const StellarReportContext context = MakeContext(job, result, grids, options);
  TextDocument document = StellarReportDocument(job, result);
  // The title and the summary head the page; the rest are the tables.
  std::string summary = document.blocks.size() > 1 ? document.blocks[1].text : "";
  document.blocks.erase(document.blocks.begin(), document.blocks.begin() + std::min<size_t>(2, document.blocks.size()));
  const std::vector<FigureSection> sections = {
      StellarHistogramFigures(context), StellarStarImageFigures(context), StellarResidualVectorFigures(context),
      StellarDistortionFigures(context), StellarProfileFigures(context)};
  std::vector<std::pair<std::string, std::string>> files;
  HtmlPage page{job.title, summary, {}, "Tables: seed 001 Tables 2 and 3 (and seed 004 A.4-A.6)",
                ToHtmlElements(document), sections};
  for (size_t k = 0; k < job.cameras.size(); ++k) {
    const std::string name = job.cameras.size() == 1 ? "certificate.html"
                                                     : "certificate-" + Slug(job.cameras[k].name) + ".html";
    files.emplace_back(name, FormatCertificateHtml(StellarCertificate(job, result, static_cast<int>(k))));
    page.links.emplace_back(name, "Report of calibration, camera " + job.cameras[k].name);
  }
  files.insert(files.begin(), {"report.html", FormatHtmlPage(page)});
  AppendFigureFiles(sections, &files);
  return files;
}

}  // namespace platemeter::report
