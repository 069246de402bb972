// FormatBundleHtmlReport (bundle_html_report.h): the page and its plot files.
#include "platemeter/report/bundle_html_report.h"

#include <cmath>

#include <fmt/format.h>

#include "bundle_figures.h"
#include "platemeter/core/error.h"
#include "platemeter/core/markup.h"
#include "platemeter/core/version.h"
#include "platemeter/report/certificate.h"

namespace platemeter::report {
namespace {

// The certificate of camera k: the balanced lens of seed 000 section 3.2.
Certificate BundleCertificate(const BundleResult& result, int k, const BundleReportOptions& report_options) {
  const BundleCameraResult& camera = result.cameras[k];
  Certificate c;
  c.camera = camera.name + (camera.definition && !camera.definition->description.empty()
                                ? " — " + camera.definition->description
                                : "");
  c.issued_by = std::string("platemeter ") + kVersion;
  c.method = fmt::format("Self-calibrating bundle adjustment (seed 000): sigma0 = {:.3f} with {:.0f} degrees of "
                         "freedom; datum: {}",
                         result.adjustment.sigma0, result.adjustment.dof, result.datum_words);
  const double corner = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  const DistortionProfile whole = BundleDistortionProfile(result, k, report_options, {corner});
  const double c_prime = whole.calibrated_focal_length_mm.value;
  c.elements.push_back({"Calibrated focal length c'", c_prime, whole.calibrated_focal_length_mm.sigma, "mm", 4});
  c.elements.push_back({"Principal distance c", camera.values[0], camera.sigmas[0].value_or(0.0), "mm", 4});
  c.elements.push_back({"Principal point xp (from the frame's origin)", 1e3 * camera.values[1],
                        1e3 * camera.sigmas[1].value_or(0.0), "µm", 2});
  c.elements.push_back({"Principal point yp", 1e3 * camera.values[2], 1e3 * camera.sigmas[2].value_or(0.0), "µm", 2});
  std::vector<double> radii;
  const std::vector<double> angles = CertificateFieldAngles_deg(c_prime, corner);
  for (double a : angles) radii.push_back(c_prime * std::tan(a * M_PI / 180.0));
  const DistortionProfile table = BundleDistortionProfile(result, k, report_options, radii);
  for (size_t i = 0; i < angles.size() && i < table.rows.size(); ++i) {
    const DistortionProfileRow& r = table.rows[i];
    c.distortion.push_back(
        {angles[i], r.r_mm, r.radial_um, r.radial_sigma_um, r.decentering_um, r.decentering_sigma_um});
  }
  c.distortion_words = "Radial distortion δ'r (seed 000 eq. 14), " + BundleBalanceWords(result, k, report_options) +
                       ", at the distance c' tan(field angle) from the principal point; decentering: the profile P(r) "
                       "(eq. 15), the largest tangential component there.";
  long observations = 0;
  int frames = 0;
  for (const BundleFrameResult& f : result.frames) {
    if (f.camera != camera.name) continue;
    ++frames;
    observations += f.observations;
  }
  c.data_used = {fmt::format("{} frames of this camera, {} image observations used", frames, observations),
                 fmt::format("{} points in the adjustment", result.points.size()),
                 result.adjustment.summary};
  return c;
}

}  // namespace

bool BundleHtmlOptions::Check(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (max_frame_plots < 0) return fail("max_frame_plots must be >= 0");
  if (frames_per_grid < 1) return fail("frames_per_grid must be >= 1");
  if (max_vectors_per_panel < 1) return fail("max_vectors_per_panel must be >= 1");
  if (profile_samples < 2) return fail("profile_samples must be >= 2");
  return true;
}

std::vector<std::pair<std::string, std::string>> FormatBundleHtmlReport(const BundleResult& result,
                                                                        const BundleInput& input,
                                                                        const BundleReportOptions& report_options,
                                                                        const BundleHtmlOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("bundle HTML report options", why);
  TextDocument document = BundleReportDocument(result, report_options);
  // The title and the summary head the page; the rest are the tables.
  const size_t head = std::min<size_t>(2, document.blocks.size());
  document.blocks.erase(document.blocks.begin(), document.blocks.begin() + head);
  const std::vector<FigureSection> sections = {
      ResidualVectorFigures(result, input, options), ResidualHistogramFigures(result), NetworkFigures(result, input),
      CorrelationFigures(result), DistortionFigures(result, report_options, options)};
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::pair<std::string, std::string>> links;
  for (size_t k = 0; k < result.cameras.size(); ++k) {
    const std::string name = result.cameras.size() == 1 ? "certificate.html"
                                                        : "certificate-" + Slug(result.cameras[k].name) + ".html";
    try {
      files.emplace_back(name, FormatCertificateHtml(BundleCertificate(result, static_cast<int>(k), report_options)));
      links.emplace_back(name, "Report of calibration, camera " + result.cameras[k].name);
    } catch (const Error&) {
      // A camera whose lens was not adjusted has no distortion to certify; the report says why.
    }
  }
  HtmlPage page{report_options.title, result.adjustment.summary, links,
                "Tables: the calibration (seed 000 Tables 1-4 form) and the adjustment", ToHtmlElements(document),
                sections};
  files.insert(files.begin(), {"report.html", FormatHtmlPage(page)});
  AppendFigureFiles(sections, &files);
  return files;
}

}  // namespace platemeter::report
