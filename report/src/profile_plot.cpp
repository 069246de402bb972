// DrawProfilePlot (profile_plot.h).
#include "platemeter/report/profile_plot.h"

#include <algorithm>
#include <cmath>

#include "platemeter/core/error.h"
#include "plot_axes.h"
#include "plot_canvas.h"

namespace platemeter::report {
namespace {

void DrawBand(cairo_t* cr, const PlotFrame& f, const ProfileSeries& s) {
  if (s.sigma.empty()) return;
  for (size_t i = 0; i < s.x.size(); ++i) {
    const double px = f.PxX(s.x[i]), py = f.PxY(s.value[i] + s.sigma[i]);
    i == 0 ? cairo_move_to(cr, px, py) : cairo_line_to(cr, px, py);
  }
  for (size_t i = s.x.size(); i-- > 0;) cairo_line_to(cr, f.PxX(s.x[i]), f.PxY(s.value[i] - s.sigma[i]));
  cairo_close_path(cr);
  SetColour(cr, s.rgb, 0.25);
  cairo_fill(cr);
}

void DrawCurve(cairo_t* cr, const PlotFrame& f, const ProfileSeries& s) {
  for (size_t i = 0; i < s.x.size(); ++i) {
    i == 0 ? cairo_move_to(cr, f.PxX(s.x[i]), f.PxY(s.value[i])) : cairo_line_to(cr, f.PxX(s.x[i]), f.PxY(s.value[i]));
  }
  SetColour(cr, s.rgb);
  cairo_set_line_width(cr, 1.6);
  cairo_stroke(cr);
}

}  // namespace

ProfilePlot DrawProfilePlot(const std::vector<ProfileSeries>& series, const ProfilePlotOptions& options) {
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = 0.0, y_hi = 0.0;  // y always shows 0
  for (const ProfileSeries& s : series) {
    if (s.value.size() != s.x.size() || (!s.sigma.empty() && s.sigma.size() != s.x.size())) {
      throw Error("profile plot", "series '" + s.name + "': x, value and sigma differ in length");
    }
    for (size_t i = 0; i < s.x.size(); ++i) {
      const double sigma = s.sigma.empty() ? 0.0 : s.sigma[i];
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.value[i] - sigma);
      y_hi = std::max(y_hi, s.value[i] + sigma);
    }
  }
  if (!std::isfinite(x_lo)) x_lo = 0.0, x_hi = 1.0;
  ProfilePlot plot;
  plot.frame = MakePlotFrame(90, 40, options.width_px - 110, options.height_px - 100, {x_lo, x_hi},
                             NiceRange(y_lo, y_hi), false);
  for (const ProfileSeries& s : series) {
    auto& half = plot.band_half_height_px.emplace_back();
    for (double sigma : s.sigma) half.push_back(sigma * plot.frame.PxPerY());
  }
  plot.files = RenderPlot(options.width_px, options.height_px, [&](cairo_t* cr) {
    const PlotFrame& f = plot.frame;
    for (const ProfileSeries& s : series) DrawBand(cr, f, s);
    SetColour(cr, 0x999999);
    cairo_set_line_width(cr, 0.8);
    cairo_move_to(cr, f.left_px, f.PxY(0));
    cairo_line_to(cr, f.left_px + f.width_px, f.PxY(0));
    cairo_stroke(cr);
    for (const ProfileSeries& s : series) DrawCurve(cr, f, s);
    DrawAxes(cr, f, options.x_label, options.y_label);
    DrawText(cr, f.left_px, 24, options.title, TextAlign::kLeft, 13, true);
    double y = f.top_px + 16;
    for (const ProfileSeries& s : series) {
      SetColour(cr, s.rgb);
      DrawText(cr, f.left_px + 10, y, s.name + (s.sigma.empty() ? "" : " (band: ± one sigma)"), TextAlign::kLeft, 10);
      y += 14;
    }
  });
  return plot;
}

}  // namespace platemeter::report
