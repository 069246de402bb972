// DrawNetworkPlot (network_plot.h).
#include "platemeter/report/network_plot.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "plot_axes.h"
#include "plot_canvas.h"

namespace platemeter::report {
namespace {

int Stride(size_t count, int limit) {
  return limit > 0 && count > static_cast<size_t>(limit) ? static_cast<int>((count + limit - 1) / limit) : 1;
}

}  // namespace

NetworkPlot DrawNetworkPlot(const std::vector<std::array<double, 3>>& stations_m,
                            const std::vector<std::array<double, 3>>& points_m,
                            const std::vector<std::pair<int, int>>& rays, const NetworkPlotOptions& options) {
  NetworkPlot plot;
  const int v = options.view == NetworkView::kPlan ? 1 : 2;  // the vertical axis: Y or Z
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (const auto* set : {&stations_m, &points_m}) {
    for (const auto& p : *set) {
      x_lo = std::min(x_lo, p[0]);
      x_hi = std::max(x_hi, p[0]);
      y_lo = std::min(y_lo, p[v]);
      y_hi = std::max(y_hi, p[v]);
    }
  }
  if (!std::isfinite(x_lo)) x_lo = x_hi = y_lo = y_hi = 0.0;
  const double pad = 0.04 * std::max(x_hi - x_lo, y_hi - y_lo);
  plot.frame = MakePlotFrame(100, 50, options.width_px - 130, options.height_px - 110,
                             NiceRange(x_lo - pad, x_hi + pad), NiceRange(y_lo - pad, y_hi + pad), true);
  plot.point_stride = Stride(points_m.size(), options.max_points);
  plot.ray_stride = Stride(rays.size(), options.max_rays);
  // Counted here: the drawing runs once per file format.
  auto drawn = [](size_t count, int stride) { return static_cast<int>((count + stride - 1) / stride); };
  plot.points_drawn = drawn(points_m.size(), plot.point_stride);
  plot.rays_drawn = options.rays ? drawn(rays.size(), plot.ray_stride) : 0;
  plot.stations_drawn = static_cast<int>(stations_m.size());
  const char* vertical = v == 1 ? "Y (m)" : "Z (m)";
  plot.files = RenderPlot(options.width_px, options.height_px, [&](cairo_t* cr) {
    const PlotFrame& f = plot.frame;
    cairo_save(cr);
    cairo_rectangle(cr, f.left_px, f.top_px, f.width_px, f.height_px);
    cairo_clip(cr);
    if (options.rays) {
      SetColour(cr, 0x7f8c8d, rays.size() > 500 ? 0.15 : 0.4);
      cairo_set_line_width(cr, 0.5);
      for (size_t i = 0; i < rays.size(); i += plot.ray_stride) {
        const auto& p = points_m.at(rays[i].first);
        const auto& s = stations_m.at(rays[i].second);
        cairo_move_to(cr, f.PxX(p[0]), f.PxY(p[v]));
        cairo_line_to(cr, f.PxX(s[0]), f.PxY(s[v]));
      }
      cairo_stroke(cr);
    }
    SetColour(cr, 0x1f4e9a);
    const double r = points_m.size() > 2000 ? 0.8 : 1.6;
    for (size_t i = 0; i < points_m.size(); i += plot.point_stride) {
      cairo_rectangle(cr, f.PxX(points_m[i][0]) - r, f.PxY(points_m[i][v]) - r, 2 * r, 2 * r);
    }
    cairo_fill(cr);
    SetColour(cr, 0xc0392b);
    for (const auto& s : stations_m) {
      const double x = f.PxX(s[0]), y = f.PxY(s[v]);
      cairo_move_to(cr, x, y - 5);
      cairo_line_to(cr, x + 4.5, y + 3.5);
      cairo_line_to(cr, x - 4.5, y + 3.5);
      cairo_close_path(cr);
    }
    cairo_fill(cr);
    cairo_restore(cr);
    DrawAxes(cr, f, "X (m)", vertical);
    DrawText(cr, f.left_px, 22, options.title, TextAlign::kLeft, 13, true);
    std::string legend = fmt::format("▲ {} stations   ■ {} points", stations_m.size(), points_m.size());
    if (plot.point_stride > 1) legend += fmt::format(" (1 in {} drawn)", plot.point_stride);
    if (options.rays) {
      legend += fmt::format("   — {} rays", rays.size());
      if (plot.ray_stride > 1) legend += fmt::format(" (1 in {} drawn)", plot.ray_stride);
    }
    SetColour(cr, 0x000000);
    DrawText(cr, f.left_px, 40, legend, TextAlign::kLeft, 10);
  });
  return plot;
}

}  // namespace platemeter::report
