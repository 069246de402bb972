// The shared page of report/'s HTML reports (html_page.h).
#include "html_page.h"

#include <cctype>

#include <fmt/format.h>

#include "platemeter/core/markup.h"

namespace platemeter::report {
namespace {

constexpr const char* kPageStyle = R"(body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 2em auto; max-width: 1300px; color: #222; }
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

}  // namespace

std::string Slug(const std::string& id) {
  std::string out;
  for (char c : id) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  return out.empty() ? "_" : out;
}

std::string FormatHtmlPage(const HtmlPage& page) {
  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
                    EscapeMarkup(page.title) + "</title>\n<style>\n" + kPageStyle + "\n</style>\n</head>\n<body>\n";
  out += "<h1>" + EscapeMarkup(page.title) + "</h1>\n<p>" + EscapeMarkup(page.summary) + "</p>\n";
  if (!page.links.empty()) {
    out += "<p>";
    for (size_t i = 0; i < page.links.size(); ++i) {
      out += fmt::format("{}<a href=\"{}\">{}</a>", i == 0 ? "" : " · ", EscapeMarkup(page.links[i].first),
                         EscapeMarkup(page.links[i].second));
    }
    out += "</p>\n";
  }
  out += "<nav><h2>Contents</h2>\n<ul>\n<li><a href=\"#tables\">" + EscapeMarkup(page.tables_words) + "</a></li>\n";
  for (const FigureSection& s : page.sections) {
    if (s.figures.empty() && s.notes.empty()) continue;
    out += fmt::format("<li><a href=\"#{}\">{}</a> ({} plot{})</li>\n", s.anchor, EscapeMarkup(s.title),
                       s.figures.size(), s.figures.size() == 1 ? "" : "s");
  }
  out += "</ul>\n</nav>\n<section id=\"tables\">\n" + page.tables_html + "</section>\n";
  for (const FigureSection& s : page.sections) {
    if (s.figures.empty() && s.notes.empty()) continue;
    out += fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n", s.anchor, EscapeMarkup(s.title));
    for (const std::string& note : s.notes) out += "<p class=\"note\">" + EscapeMarkup(note) + "</p>\n";
    for (const Figure& f : s.figures) out += FigureHtml(f);
    out += "</section>\n";
  }
  return out + "</body>\n</html>\n";
}

void AppendFigureFiles(const std::vector<FigureSection>& sections,
                       std::vector<std::pair<std::string, std::string>>* files) {
  for (const FigureSection& s : sections) {
    for (const Figure& f : s.figures) {
      files->emplace_back("plots/" + f.stem + ".png", f.files.png);
      files->emplace_back("plots/" + f.stem + ".svg", f.files.svg);
    }
  }
}

}  // namespace platemeter::report
