#pragma once
// The figures of the bundle's HTML report (bundle_html_report.h), one function
// per kind; each returns its pictures with the words the page shows.
#include <string>
#include <vector>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_report.h"
#include "platemeter/report/bundle_html_report.h"
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

FigureSection ResidualVectorFigures(const BundleResult& result, const BundleInput& input,
                                    const BundleHtmlOptions& options);
FigureSection ResidualHistogramFigures(const BundleResult& result);
FigureSection NetworkFigures(const BundleResult& result, const BundleInput& input);
FigureSection CorrelationFigures(const BundleResult& result);
FigureSection DistortionFigures(const BundleResult& result, const BundleReportOptions& report_options,
                                const BundleHtmlOptions& options);

}  // namespace platemeter::report
