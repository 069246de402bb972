#pragma once
// The pieces every HTML report of report/ shares: a figure (its PNG and SVG
// and the words the page shows), sections of figures, and the page itself
// (title, summary, index, the tables, the sections), self-contained: inline
// CSS, relative links, no JavaScript.
#include <string>
#include <utility>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

struct Figure {
  std::string stem;     // file name without extension: plots/<stem>.png and .svg
  std::string caption;  // what it shows, its scale and what was aggregated
  RenderedPlot files;
};

struct FigureSection {
  std::string anchor;  // id in the page
  std::string title;
  std::vector<Figure> figures;
  std::vector<std::string> notes;  // e.g. "no distortion profile: ..."
};

// A file-name-safe form of an id: letters, digits, '-', '_' and '.'; others '_'.
std::string Slug(const std::string& id);

struct HtmlPage {
  std::string title;
  std::string summary;        // one paragraph under the title
  std::vector<std::pair<std::string, std::string>> links;  // (href, words): other pages, listed under the summary
  std::string tables_words;   // the index's entry for the tables
  std::string tables_html;    // the tables (HTML elements)
  std::vector<FigureSection> sections;
};
std::string FormatHtmlPage(const HtmlPage& page);

// The page's plot files: ("plots/<stem>.png", bytes), ("plots/<stem>.svg", bytes) per figure.
void AppendFigureFiles(const std::vector<FigureSection>& sections,
                       std::vector<std::pair<std::string, std::string>>* files);

}  // namespace platemeter::report
