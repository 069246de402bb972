// FormatBundleHtmlReport (bundle_html_report.h): the page and its plot files.
#include "platemeter/report/bundle_html_report.h"

#include <fmt/format.h>

#include "bundle_figures.h"
#include "platemeter/core/error.h"
#include "platemeter/core/markup.h"

namespace platemeter::report {
namespace {

constexpr const char* kStyle = R"(body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 2em auto; max-width: 1300px; color: #222; }
h1 { font-size: 1.5em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; } h3 { font-size: 1.05em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.85em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; } th { background: #f0f0f0; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
nav ul { columns: 2; } figure { margin: 1.2em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #444; max-width: 60em; } .note { color: #a33; })";

std::string FigureHtml(const Figure& f) {
  return fmt::format(
      "<figure id=\"{0}\"><a href=\"plots/{0}.svg\"><img src=\"plots/{0}.png\" width=\"{1}\" height=\"{2}\" "
      "alt=\"{3}\"></a>\n<figcaption>{3} <a href=\"plots/{0}.svg\">SVG</a></figcaption></figure>\n",
      f.stem, f.files.width_px, f.files.height_px, EscapeMarkup(f.caption));
}

std::string Page(const std::string& title, const std::string& summary, const std::string& tables,
                 const std::vector<FigureSection>& sections) {
  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
                    EscapeMarkup(title) + "</title>\n<style>\n" + kStyle + "\n</style>\n</head>\n<body>\n";
  out += "<h1>" + EscapeMarkup(title) + "</h1>\n<p>" + EscapeMarkup(summary) + "</p>\n";
  out += "<nav><h2>Contents</h2>\n<ul>\n<li><a href=\"#tables\">Tables: the calibration (seed 000 Tables 1-4 form) "
         "and the adjustment</a></li>\n";
  for (const FigureSection& s : sections) {
    if (s.figures.empty() && s.notes.empty()) continue;
    out += fmt::format("<li><a href=\"#{}\">{}</a> ({} plot{})</li>\n", s.anchor, EscapeMarkup(s.title),
                       s.figures.size(), s.figures.size() == 1 ? "" : "s");
  }
  out += "</ul>\n</nav>\n<section id=\"tables\">\n" + tables + "</section>\n";
  for (const FigureSection& s : sections) {
    if (s.figures.empty() && s.notes.empty()) continue;
    out += fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n", s.anchor, EscapeMarkup(s.title));
    for (const std::string& note : s.notes) out += "<p class=\"note\">" + EscapeMarkup(note) + "</p>\n";
    for (const Figure& f : s.figures) out += FigureHtml(f);
    out += "</section>\n";
  }
  return out + "</body>\n</html>\n";
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
  files.emplace_back("report.html",
                     Page(report_options.title, result.adjustment.summary, ToHtmlElements(document), sections));
  for (const FigureSection& s : sections) {
    for (const Figure& f : s.figures) {
      files.emplace_back("plots/" + f.stem + ".png", f.files.png);
      files.emplace_back("plots/" + f.stem + ".svg", f.files.svg);
    }
  }
  return files;
}

}  // namespace platemeter::report
