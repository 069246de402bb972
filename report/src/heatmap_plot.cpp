// DrawHeatmap (heatmap_plot.h).
#include "platemeter/report/heatmap_plot.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "plot_axes.h"
#include "plot_canvas.h"

namespace platemeter::report {

std::array<double, 3> HeatmapColour(double value, const AxisRange& range) {
  const double t = std::clamp((value - range.min) / (range.max - range.min), 0.0, 1.0);
  // Blue (0.13, 0.40, 0.67) -> white -> red (0.70, 0.09, 0.17): the ColorBrewer RdBu ends.
  const std::array<double, 3> blue = {0.13, 0.40, 0.67}, red = {0.70, 0.09, 0.17};
  std::array<double, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = t < 0.5 ? blue[c] + (1.0 - blue[c]) * (t / 0.5) : 1.0 + (red[c] - 1.0) * ((t - 0.5) / 0.5);
  }
  return rgb;
}

HeatmapPlot DrawHeatmap(const std::vector<std::vector<double>>& matrix, const std::vector<std::string>& labels,
                        const HeatmapPlotOptions& options) {
  const int n = static_cast<int>(matrix.size());
  for (const auto& row : matrix) {
    if (static_cast<int>(row.size()) != n) throw Error("heat map", "the matrix is not square");
  }
  if (static_cast<int>(labels.size()) != n) throw Error("heat map", "one label per row is needed");
  HeatmapPlot plot;
  plot.cell_px = options.cell_px > 0 ? options.cell_px : n <= 10 ? 64 : std::max(4, 640 / std::max(1, n));
  plot.left_px = 130;
  plot.top_px = 130;
  for (const auto& row : matrix) {
    auto& colours = plot.cell_rgb.emplace_back();
    for (double v : row) colours.push_back(HeatmapColour(v, options.value_range));
  }
  const double side = n * plot.cell_px;
  const int width = static_cast<int>(plot.left_px + side + 130), height = static_cast<int>(plot.top_px + side + 30);
  const bool annotate = n <= options.max_annotated;
  const double font = std::clamp(plot.cell_px * 0.22, 6.0, 12.0);
  plot.files = RenderPlot(width, std::max(height, 360), [&](cairo_t* cr) {
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < n; ++k) {
        const auto& c = plot.cell_rgb[i][k];
        cairo_set_source_rgb(cr, c[0], c[1], c[2]);
        cairo_rectangle(cr, plot.left_px + k * plot.cell_px, plot.top_px + i * plot.cell_px, plot.cell_px, plot.cell_px);
        cairo_fill(cr);
        if (!annotate) continue;
        SetColour(cr, std::abs(matrix[i][k]) > 0.7 * options.value_range.max ? 0xffffff : 0x000000);
        DrawText(cr, plot.left_px + (k + 0.5) * plot.cell_px, plot.top_px + (i + 0.5) * plot.cell_px + font / 3,
                 fmt::format("{:+.2f}", matrix[i][k]), TextAlign::kCenter, font);
      }
    }
    SetColour(cr, 0x000000);
    const double label_font = std::clamp(plot.cell_px * 0.4, 6.0, 11.0);
    for (int i = 0; i < n; ++i) {
      DrawText(cr, plot.left_px - 6, plot.top_px + (i + 0.5) * plot.cell_px + label_font / 3, labels[i],
               TextAlign::kRight, label_font);
      cairo_save(cr);
      cairo_translate(cr, plot.left_px + (i + 0.5) * plot.cell_px + label_font / 3, plot.top_px - 6);
      cairo_rotate(cr, -M_PI / 2);
      DrawText(cr, 0, 0, labels[i], TextAlign::kLeft, label_font);
      cairo_restore(cr);
    }
    DrawText(cr, 10, 22, options.title, TextAlign::kLeft, 13, true);
    // The colour scale: a vertical bar from min (bottom) to max (top).
    const double bar_x = plot.left_px + side + 30, bar_h = std::max(side, 200.0), steps = 100;
    for (int s = 0; s < steps; ++s) {
      const double v = options.value_range.min + (options.value_range.max - options.value_range.min) * (s + 0.5) / steps;
      const auto c = HeatmapColour(v, options.value_range);
      cairo_set_source_rgb(cr, c[0], c[1], c[2]);
      cairo_rectangle(cr, bar_x, plot.top_px + bar_h * (1 - (s + 1) / steps), 18, bar_h / steps + 0.5);
      cairo_fill(cr);
    }
    SetColour(cr, 0x000000);
    for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
      const double v = options.value_range.min + t * (options.value_range.max - options.value_range.min);
      DrawText(cr, bar_x + 24, plot.top_px + bar_h * (1 - t) + 4, fmt::format("{:+.2f}", v), TextAlign::kLeft, 10);
    }
  });
  return plot;
}

}  // namespace platemeter::report
