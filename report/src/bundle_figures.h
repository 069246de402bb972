#pragma once
// The figures of the bundle's HTML report (bundle_html_report.h), one function
// per kind; each returns its pictures with the words the page shows.
#include <string>
#include <vector>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_report.h"
#include "platemeter/report/bundle_html_report.h"
#include "html_page.h"
#include "platemeter/report/plot.h"

namespace platemeter::report {

FigureSection ResidualVectorFigures(const BundleResult& result, const BundleInput& input,
                                    const BundleHtmlOptions& options);
FigureSection ResidualHistogramFigures(const BundleResult& result);
FigureSection NetworkFigures(const BundleResult& result, const BundleInput& input);
FigureSection CorrelationFigures(const BundleResult& result);
FigureSection DistortionFigures(const BundleResult& result, const BundleReportOptions& report_options,
                                const BundleHtmlOptions& options);

}  // namespace platemeter::report
