// Axes and text (plot_axes.h).
#include "plot_axes.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "plot_canvas.h"

namespace platemeter::report {
namespace {

double NiceStep(double span, int target) {
  const double raw = span / std::max(1, target);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

}  // namespace

double NiceBelow(double value) {
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * power <= value) return m * power;
  }
  return power;
}

AxisRange NiceRange(double min, double max, int target) {
  if (!std::isfinite(min) || !std::isfinite(max)) return {0.0, 1.0};
  if (max < min) std::swap(min, max);
  if (max - min <= 1e-12 * std::max(1.0, std::abs(max))) {
    const double pad = std::max(1.0, std::abs(max) * 0.1);
    min -= pad;
    max += pad;
  }
  const double step = NiceStep(max - min, target);
  return {std::floor(min / step + 1e-9) * step, std::ceil(max / step - 1e-9) * step};
}

std::vector<double> NiceTicks(const AxisRange& range, int target) {
  const double step = NiceStep(range.max - range.min, target);
  std::vector<double> ticks;
  for (double t = std::ceil(range.min / step - 1e-9) * step; t <= range.max + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::string TickLabel(double value, double step) {
  if (value == 0.0) return "0";
  const double magnitude = std::max(std::abs(value), step);
  if (magnitude >= 1e5 || magnitude < 1e-3) return fmt::format("{:.3g}", value);
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  return fmt::format("{:.{}f}", value, decimals);
}

PlotFrame MakePlotFrame(double left_px, double top_px, double width_px, double height_px, AxisRange x, AxisRange y,
                        bool equal_scale) {
  PlotFrame f{left_px, top_px, width_px, height_px, x, y};
  if (!equal_scale) return f;
  // Widen the axis with more px per unit around its centre.
  const double px_per_unit = std::min(f.PxPerX(), f.PxPerY());
  auto widen = [&](AxisRange* r, double px) {
    const double half = 0.5 * px / px_per_unit, centre = 0.5 * (r->min + r->max);
    *r = {centre - half, centre + half};
  };
  widen(&f.x, width_px);
  widen(&f.y, height_px);
  return f;
}

void DrawText(cairo_t* cr, double x_px, double y_px, const std::string& text, TextAlign align, double font_px,
              bool bold) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, font_px);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  double x = x_px;
  if (align == TextAlign::kCenter) x -= extents.x_advance / 2;
  if (align == TextAlign::kRight) x -= extents.x_advance;
  cairo_move_to(cr, x, y_px);
  cairo_show_text(cr, text.c_str());
}

void DrawAxes(cairo_t* cr, const PlotFrame& frame, const std::string& x_title, const std::string& y_title,
              double font_px) {
  SetColour(cr, 0x000000);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, frame.left_px, frame.top_px, frame.width_px, frame.height_px);
  cairo_stroke(cr);
  const double bottom = frame.top_px + frame.height_px;
  const std::vector<double> x_ticks = NiceTicks(frame.x), y_ticks = NiceTicks(frame.y);
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  for (double t : x_ticks) {
    const double x = frame.PxX(t);
    cairo_move_to(cr, x, bottom);
    cairo_line_to(cr, x, bottom + 4);
    cairo_stroke(cr);
    DrawText(cr, x, bottom + 6 + font_px, TickLabel(t, x_step), TextAlign::kCenter, font_px);
  }
  for (double t : y_ticks) {
    const double y = frame.PxY(t);
    cairo_move_to(cr, frame.left_px - 4, y);
    cairo_line_to(cr, frame.left_px, y);
    cairo_stroke(cr);
    DrawText(cr, frame.left_px - 6, y + 0.35 * font_px, TickLabel(t, y_step), TextAlign::kRight, font_px);
  }
  DrawText(cr, frame.left_px + frame.width_px / 2, bottom + 2 * font_px + 12, x_title, TextAlign::kCenter, font_px);
  cairo_save(cr);
  cairo_translate(cr, frame.left_px - 4.8 * font_px, frame.top_px + frame.height_px / 2);
  cairo_rotate(cr, -M_PI / 2);
  DrawText(cr, 0, 0, y_title, TextAlign::kCenter, font_px);
  cairo_restore(cr);
}

}  // namespace platemeter::report
