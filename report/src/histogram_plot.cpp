// DrawHistogram (histogram_plot.h).
#include "platemeter/report/histogram_plot.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "plot_axes.h"
#include "plot_canvas.h"

namespace platemeter::report {
namespace {

struct Binned {
  std::vector<double> edges;
  std::vector<long> counts;
  long outside = 0;
  double mean = 0.0, sigma = 0.0;  // of the finite values
};

Binned Bin(const std::vector<double>& values, const HistogramPlotOptions& options) {
  Binned b;
  double lo = INFINITY, hi = -INFINITY, sum = 0.0, sum2 = 0.0;
  long finite = 0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    sum += v;
    sum2 += v * v;
    ++finite;
  }
  if (finite > 0) {
    b.mean = sum / finite;
    b.sigma = std::sqrt(std::max(0.0, sum2 / finite - b.mean * b.mean));
  }
  AxisRange range = options.range.value_or(AxisRange{finite ? lo : 0.0, finite ? hi : 1.0});
  if (!(range.max > range.min)) range = {range.min - 0.5, range.min + 0.5};
  const int bins = options.bins > 0 ? options.bins : std::clamp(static_cast<int>(std::sqrt(double(finite))), 10, 80);
  const double width = (range.max - range.min) / bins;
  for (int i = 0; i <= bins; ++i) b.edges.push_back(range.min + i * width);
  b.counts.assign(bins, 0);
  for (double v : values) {
    if (!(v >= range.min && v <= range.max)) {
      ++b.outside;
      continue;
    }
    b.counts[std::min(bins - 1, static_cast<int>((v - range.min) / width))]++;
  }
  return b;
}

void DrawNormal(cairo_t* cr, const PlotFrame& frame, double scale, double mean, double sigma) {
  if (!(sigma > 0.0)) return;
  SetColour(cr, 0xc0392b);
  cairo_set_line_width(cr, 1.5);
  const int samples = 200;
  for (int i = 0; i <= samples; ++i) {
    const double x = frame.x.min + (frame.x.max - frame.x.min) * i / samples;
    const double z = (x - mean) / sigma;
    const double y = scale * std::exp(-0.5 * z * z) / (sigma * std::sqrt(2 * M_PI));
    const double py = std::max(frame.top_px, frame.PxY(y));
    i == 0 ? cairo_move_to(cr, frame.PxX(x), py) : cairo_line_to(cr, frame.PxX(x), py);
  }
  cairo_stroke(cr);
}

}  // namespace

HistogramPlot DrawHistogram(const std::vector<double>& values, const HistogramPlotOptions& options) {
  HistogramPlot plot;
  Binned b = Bin(values, options);
  plot.bin_edges = b.edges;
  plot.counts = b.counts;
  plot.outside = b.outside;
  plot.normal_mean = options.normal_mean.value_or(b.mean);
  plot.normal_sigma = options.normal_sigma.value_or(b.sigma);
  const double bin_width = b.edges[1] - b.edges[0];
  const long binned = static_cast<long>(values.size()) - b.outside;
  // The curve's peak must fit as well as the tallest bar.
  double top = static_cast<double>(*std::max_element(b.counts.begin(), b.counts.end()));
  if (options.normal_curve && plot.normal_sigma > 0) {
    top = std::max(top, binned * bin_width / (plot.normal_sigma * std::sqrt(2 * M_PI)));
  }
  const AxisRange y_range = NiceRange(0.0, std::max(1.0, top * 1.05));
  plot.frame = MakePlotFrame(80, 40, options.width_px - 100, options.height_px - 100,
                             {b.edges.front(), b.edges.back()}, {0.0, y_range.max}, false);
  for (long c : b.counts) plot.bar_height_px.push_back(c * plot.frame.PxPerY());
  plot.files = RenderPlot(options.width_px, options.height_px, [&](cairo_t* cr) {
    const PlotFrame& f = plot.frame;
    SetColour(cr, 0x5d8aa8);
    for (size_t i = 0; i < b.counts.size(); ++i) {
      const double x0 = f.PxX(b.edges[i]), x1 = f.PxX(b.edges[i + 1]);
      cairo_rectangle(cr, x0, f.PxY(0) - plot.bar_height_px[i], x1 - x0, plot.bar_height_px[i]);
    }
    cairo_fill(cr);
    if (options.normal_curve) DrawNormal(cr, f, binned * bin_width, plot.normal_mean, plot.normal_sigma);
    DrawAxes(cr, f, options.x_label, "count");
    DrawText(cr, f.left_px, 24, options.title, TextAlign::kLeft, 13, true);
    std::string legend = fmt::format("{} values in {} bins of {:.3g}", binned, b.counts.size(), bin_width);
    if (b.outside > 0) legend += fmt::format("; {} outside [{:.3g}, {:.3g}] not shown", b.outside, f.x.min, f.x.max);
    SetColour(cr, 0x000000);
    DrawText(cr, f.left_px + f.width_px - 4, f.top_px + 14, legend, TextAlign::kRight, 10);
    if (options.normal_curve) {
      SetColour(cr, 0xc0392b);
      const std::string words = options.normal_words.empty()
                                    ? fmt::format("normal curve N({:.3g}, {:.3g})", plot.normal_mean, plot.normal_sigma)
                                    : options.normal_words;
      DrawText(cr, f.left_px + f.width_px - 4, f.top_px + 28, words, TextAlign::kRight, 10);
    }
  });
  return plot;
}

}  // namespace platemeter::report
