#pragma once
// The figures of the stellar calibration's HTML report (stellar_html_report.h),
// seed 001 Table 4, one function per kind; each returns its pictures with the
// words the page shows.
#include <map>
#include <string>
#include <vector>

#include "html_page.h"
#include "platemeter/calib/stellar_job.h"
#include "platemeter/report/stellar_html_report.h"
#include "platemeter/report/vector_plot.h"

namespace platemeter::report {

struct StellarReportContext {
  const StellarJob& job;
  const StellarJobResult& result;
  const StellarHtmlOptions& options;
  std::vector<std::vector<PlotLabel>> corner_labels;  // per camera: its corner reseau numbers
  std::vector<AxisRange> x_mm, y_mm;                  // per camera: the area shown (the format)
};

// One measured image with its residual (single-plate adjustment).
struct StellarImageResidual {
  const StarImageObservation* image = nullptr;
  double vx_um = 0.0, vy_um = 0.0;
  bool used = true;
};
// Plate i's images with their residuals, in the plate's order.
std::vector<StellarImageResidual> PlateResiduals(const StellarReportContext& c, size_t plate);
// A colour per trail name ("" = single star images), in a fixed order; and the key.
std::map<std::string, unsigned> TrailColours(const StellarReportContext& c);
std::vector<std::pair<std::string, unsigned>> TrailKey(const std::map<std::string, unsigned>& colours);

FigureSection StellarHistogramFigures(const StellarReportContext& c);
FigureSection StellarStarImageFigures(const StellarReportContext& c);
FigureSection StellarResidualVectorFigures(const StellarReportContext& c);
FigureSection StellarDistortionFigures(const StellarReportContext& c);
FigureSection StellarProfileFigures(const StellarReportContext& c);

}  // namespace platemeter::report
