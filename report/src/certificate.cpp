// The calibration certificate page (certificate.h).
#include "platemeter/report/certificate.h"

#include <cmath>

#include <fmt/format.h>

#include "platemeter/core/markup.h"

namespace platemeter::report {
namespace {

constexpr const char* kCertificateStyle = R"(body { font-family: "DejaVu Serif", Georgia, serif; margin: 2em auto; max-width: 820px; color: #111; }
h1 { text-align: center; font-size: 1.6em; letter-spacing: 0.05em; } h2 { font-size: 1.1em; border-bottom: 1px solid #999; }
.sub { text-align: center; color: #444; } table { border-collapse: collapse; margin: 0.6em 0; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.7em; } th { background: #eee; }
td.num { text-align: right; font-variant-numeric: tabular-nums; } .foot { font-size: 0.8em; color: #555; margin-top: 2em; })";

std::string Esc(const std::string& s) { return EscapeMarkup(s); }

std::string ElementsTable(const std::vector<CertificateElement>& elements) {
  std::string out = "<table>\n<tr><th>Element</th><th>Value</th><th>Standard error</th></tr>\n";
  for (const CertificateElement& e : elements) {
    out += fmt::format("<tr><td>{}</td><td class=\"num\">{:.{}f} {}</td><td class=\"num\">{}</td></tr>\n", Esc(e.name),
                       e.value, e.decimals, Esc(e.unit),
                       e.sigma > 0 ? fmt::format("{:.{}f} {}", e.sigma, e.decimals, Esc(e.unit)) : "fixed");
  }
  return out + "</table>\n";
}

std::string DistortionTable(const std::vector<CertificateDistortionRow>& rows) {
  std::string out =
      "<table>\n<tr><th>Field angle (deg)</th><th>Distance (mm)</th><th>Radial distortion (µm)</th>"
      "<th>s.e. (µm)</th><th>Decentering (µm)</th><th>s.e. (µm)</th></tr>\n";
  for (const CertificateDistortionRow& r : rows) {
    out += fmt::format(
        "<tr><td class=\"num\">{:.1f}</td><td class=\"num\">{:.2f}</td><td class=\"num\">{:+.2f}</td>"
        "<td class=\"num\">{:.2f}</td><td class=\"num\">{:.2f}</td><td class=\"num\">{:.2f}</td></tr>\n",
        r.field_angle_deg, r.distance_mm, r.radial_um, r.radial_sigma_um, r.decentering_um, r.decentering_sigma_um);
  }
  return out + "</table>\n";
}

}  // namespace

std::string FormatCertificateHtml(const Certificate& c) {
  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>Report of calibration: " +
                    Esc(c.camera) + "</title>\n<style>\n" + kCertificateStyle + "\n</style>\n</head>\n<body>\n";
  out += "<h1>REPORT OF CALIBRATION</h1>\n<p class=\"sub\">" + Esc(c.camera) + "</p>\n<p class=\"sub\">" +
         Esc(c.method) + "</p>\n";
  out += "<h2>Calibrated elements</h2>\n" + ElementsTable(c.elements);
  out += "<h2>Lens distortion by field angle</h2>\n<p>" + Esc(c.distortion_words) + "</p>\n" +
         DistortionTable(c.distortion);
  out += "<h2>Data used</h2>\n<ul>\n";
  for (const std::string& line : c.data_used) out += "<li>" + Esc(line) + "</li>\n";
  out += "</ul>\n<p class=\"foot\">Standard errors are a-posteriori (scaled by the adjustment's standard error of "
         "unit weight) and propagated through the full covariance of the calibrated elements. The full report: "
         "<a href=\"report.html\">report.html</a>. Issued by " +
         Esc(c.issued_by) + ".</p>\n</body>\n</html>\n";
  return out;
}

std::vector<double> CertificateFieldAngles_deg(double focal_length_mm, double max_distance_mm) {
  std::vector<double> angles;
  if (!(focal_length_mm > 0) || !(max_distance_mm > 0)) return angles;
  const double largest = std::atan(max_distance_mm / focal_length_mm) * 180.0 / M_PI;
  for (double a = 0.0; a < largest - 0.5; a += 5.0) angles.push_back(a);
  angles.push_back(largest);
  return angles;
}

}  // namespace platemeter::report
