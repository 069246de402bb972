#pragma once
// A histogram of values with, optionally, the normal curve N(mean, sigma)
// scaled to the counts (n x bin width x density) over it.
#include <optional>
#include <string>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

struct HistogramPlotOptions {
  std::string title;
  std::string x_label = "value";  // with its unit, e.g. "normalized residual (-)"
  int bins = 0;                   // 0: sqrt(n), between 10 and 80
  // The binned range. Unset: the values' range. Values outside it are counted
  // in `outside` (and said in the legend), not in the bins.
  std::optional<AxisRange> range;
  bool normal_curve = false;
  std::optional<double> normal_mean;   // unset: the values' mean
  std::optional<double> normal_sigma;  // unset: the values' standard deviation
  std::string normal_words;            // legend of the curve, e.g. "N(0, sigma0 = 1.02)"
  int width_px = 640;
  int height_px = 400;
};

struct HistogramPlot {
  RenderedPlot files;
  std::vector<double> bin_edges;  // bins + 1 edges; bin i is [edge i, edge i+1), the last one closed
  std::vector<long> counts;       // per bin
  long outside = 0;               // values outside the binned range (and not finite)
  double normal_mean = 0.0, normal_sigma = 0.0;  // of the curve drawn (if drawn)
  PlotFrame frame;                // x: the values, y: counts
  std::vector<double> bar_height_px;  // per bin: counts[i] x frame.PxPerY()
};

HistogramPlot DrawHistogram(const std::vector<double>& values, const HistogramPlotOptions& options);

}  // namespace platemeter::report
