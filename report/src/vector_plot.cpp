// DrawVectorPlot (vector_plot.h).
#include "platemeter/report/vector_plot.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "plot_axes.h"
#include "plot_canvas.h"

namespace platemeter::report {
namespace {

constexpr double kMargin = 60.0;   // px; left and bottom labels
constexpr double kTitle = 34.0;    // px; a panel's title above its frame
constexpr double kKeyY = 66.0;     // px; baseline of the colour key (under the scale bar)

// The panel's vectors, or the means of its cells when there are too many.
std::vector<PlotVector> ToDraw(const VectorPanel& panel, const PlotFrame& frame, const VectorPlotOptions& options,
                               VectorPanelDrawn* out, std::vector<int>* members) {
  if (static_cast<int>(panel.vectors.size()) <= options.max_vectors) {
    members->assign(panel.vectors.size(), 1);
    return panel.vectors;
  }
  const double w = frame.x.max - frame.x.min, h = frame.y.max - frame.y.min;
  const double cell = std::max(w, h) / std::max(1, options.cells_across);
  out->aggregated = true;
  out->cell_width_mm = out->cell_height_mm = cell;
  std::map<std::pair<int, int>, std::pair<PlotVector, int>> cells;
  for (const PlotVector& v : panel.vectors) {
    const auto key = std::make_pair(static_cast<int>(std::floor((v.x_mm - frame.x.min) / cell)),
                                    static_cast<int>(std::floor((v.y_mm - frame.y.min) / cell)));
    auto& [sum, count] = cells[key];
    sum.dx_um += v.dx_um;
    sum.dy_um += v.dy_um;
    sum.rgb = kVectorRed;
    ++count;
  }
  std::vector<PlotVector> means;
  for (const auto& [key, entry] : cells) {
    const auto& [sum, count] = entry;
    means.push_back({frame.x.min + (key.first + 0.5) * cell, frame.y.min + (key.second + 0.5) * cell,
                     sum.dx_um / count, sum.dy_um / count, kVectorRed});
    members->push_back(count);
  }
  out->legend = fmt::format("{} {}s; arrows: the mean per {:.3g} mm cell", panel.vectors.size(),
                            options.vector_words, cell);
  return means;
}

AxisRange Extent(const std::vector<VectorPanel>& panels, bool x) {
  double lo = INFINITY, hi = -INFINITY;
  for (const VectorPanel& p : panels) {
    for (const PlotVector& v : p.vectors) {
      lo = std::min(lo, x ? v.x_mm : v.y_mm);
      hi = std::max(hi, x ? v.x_mm : v.y_mm);
    }
    for (const PlotMarker& m : p.markers) {
      lo = std::min(lo, x ? m.x_mm : m.y_mm);
      hi = std::max(hi, x ? m.x_mm : m.y_mm);
    }
  }
  return NiceRange(lo, hi);
}

double AutoScale(const std::vector<std::vector<PlotVector>>& vectors, double panel_px) {
  std::vector<double> lengths;
  for (const auto& panel : vectors) {
    for (const PlotVector& v : panel) lengths.push_back(std::hypot(v.dx_um, v.dy_um));
  }
  if (lengths.empty()) return 1.0;
  const size_t k = std::min(lengths.size() - 1, static_cast<size_t>(0.95 * lengths.size()));
  std::nth_element(lengths.begin(), lengths.begin() + k, lengths.end());
  const double p95 = lengths[k] > 0 ? lengths[k] : 1.0;
  return panel_px / 15.0 / p95;
}

void DrawArrow(cairo_t* cr, const DrawnVector& d, bool head) {
  cairo_move_to(cr, d.x_px, d.y_px);
  cairo_line_to(cr, d.x_px + d.dx_px, d.y_px + d.dy_px);
  const double length = std::hypot(d.dx_px, d.dy_px);
  if (head && length > 3.0) {
    const double a = std::atan2(d.dy_px, d.dx_px), s = std::min(5.0, 0.35 * length);
    const double ex = d.x_px + d.dx_px, ey = d.y_px + d.dy_px;
    cairo_move_to(cr, ex - s * std::cos(a - 0.4), ey - s * std::sin(a - 0.4));
    cairo_line_to(cr, ex, ey);
    cairo_line_to(cr, ex - s * std::cos(a + 0.4), ey - s * std::sin(a + 0.4));
  }
}

void DrawPanel(cairo_t* cr, const VectorPanel& panel, const VectorPanelDrawn& drawn, bool small) {
  const PlotFrame& f = drawn.frame;
  DrawAxes(cr, f, "x (mm)", "y (mm)", small ? 9 : 11);
  DrawText(cr, f.left_px, f.top_px - (drawn.legend.empty() ? 8 : 20), panel.title, TextAlign::kLeft, small ? 10 : 12, true);
  if (!drawn.legend.empty()) DrawText(cr, f.left_px, f.top_px - 6, drawn.legend, TextAlign::kLeft, small ? 7 : 9);
  cairo_save(cr);
  cairo_rectangle(cr, f.left_px, f.top_px, f.width_px, f.height_px);
  cairo_clip(cr);
  const size_t n = drawn.drawn.size();
  const double marker_px = panel.markers.size() > 3000 ? 0.8 : small ? 1.2 : 1.8;
  for (const PlotMarker& m : panel.markers) {
    SetColour(cr, m.rgb);
    cairo_arc(cr, f.PxX(m.x_mm), f.PxY(m.y_mm), marker_px, 0, 2 * M_PI);
    cairo_fill(cr);
  }
  SetColour(cr, 0x1f4e9a);
  for (const DrawnVector& d : drawn.drawn) {
    cairo_rectangle(cr, d.x_px - 0.75, d.y_px - 0.75, 1.5, 1.5);
  }
  cairo_fill(cr);
  cairo_set_line_width(cr, n > 2000 ? 0.4 : n > 300 ? 0.7 : 1.0);
  // One stroke per colour run (vectors come grouped by colour, e.g. by trail).
  for (size_t i = 0; i < n;) {
    const unsigned rgb = drawn.drawn[i].rgb;
    SetColour(cr, rgb);
    for (; i < n && drawn.drawn[i].rgb == rgb; ++i) DrawArrow(cr, drawn.drawn[i], n <= 300);
    cairo_stroke(cr);
  }
  for (const PlotLine& l : panel.lines) {
    SetColour(cr, l.rgb);
    cairo_set_line_width(cr, 1.0);
    const double dash[] = {6.0, 4.0};
    cairo_set_dash(cr, dash, l.dashed ? 2 : 0, 0.0);
    cairo_move_to(cr, f.PxX(l.x0_mm), f.PxY(l.y0_mm));
    cairo_line_to(cr, f.PxX(l.x1_mm), f.PxY(l.y1_mm));
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  SetColour(cr, 0x000000);
  for (const PlotLabel& label : panel.labels) {
    DrawText(cr, f.PxX(label.x_mm), f.PxY(label.y_mm), label.text, TextAlign::kCenter, small ? 8 : 10, true);
  }
  cairo_restore(cr);
}

}  // namespace

double AutoVectorScale(const std::vector<VectorPanel>& panels, const VectorPlotOptions& options, double panel_px) {
  const AxisRange x = options.x_mm.max > options.x_mm.min ? options.x_mm : Extent(panels, true);
  const AxisRange y = options.y_mm.max > options.y_mm.min ? options.y_mm : Extent(panels, false);
  const PlotFrame frame = MakePlotFrame(0, 0, panel_px, panel_px, x, y, true);
  std::vector<std::vector<PlotVector>> vectors;
  for (const VectorPanel& panel : panels) {
    VectorPanelDrawn unused;
    std::vector<int> members;
    vectors.push_back(ToDraw(panel, frame, options, &unused, &members));
  }
  return AutoScale(vectors, panel_px);
}

VectorPlot DrawVectorPlot(const std::vector<VectorPanel>& panels, const VectorPlotOptions& options) {
  VectorPlot plot;
  const int count = std::max<int>(1, panels.size());
  const int columns = options.columns > 0 ? options.columns : static_cast<int>(std::ceil(std::sqrt(double(count))));
  const int rows = (count + columns - 1) / columns;
  const double panel_px = options.panel_px > 0 ? options.panel_px : count == 1 ? 560 : 240;
  const AxisRange x = options.x_mm.max > options.x_mm.min ? options.x_mm : Extent(panels, true);
  const AxisRange y = options.y_mm.max > options.y_mm.min ? options.y_mm : Extent(panels, false);
  const double cell_w = panel_px + kMargin + 20, cell_h = panel_px + kMargin + kTitle;
  const double top = options.colour_key.empty() ? 60.0 : 80.0;  // px; the header (title, scale bar, key)
  std::vector<std::vector<PlotVector>> vectors;
  std::vector<std::vector<int>> members(panels.size());
  for (size_t i = 0; i < panels.size(); ++i) {
    VectorPanelDrawn& d = plot.panels.emplace_back();
    d.frame = MakePlotFrame(kMargin + (i % columns) * cell_w, top + kTitle + (i / columns) * cell_h, panel_px,
                            panel_px, x, y, true);
    vectors.push_back(ToDraw(panels[i], d.frame, options, &d, &members[i]));
  }
  plot.px_per_um = options.px_per_um > 0 ? options.px_per_um : AutoScale(vectors, panel_px);
  plot.scale_bar_um = NiceBelow(panel_px / 6.0 / plot.px_per_um);
  plot.scale_bar_px = plot.scale_bar_um * plot.px_per_um;
  for (size_t i = 0; i < panels.size(); ++i) {
    VectorPanelDrawn& d = plot.panels[i];
    for (size_t k = 0; k < vectors[i].size(); ++k) {
      const PlotVector& v = vectors[i][k];
      // y up in the plate, down in the picture.
      d.drawn.push_back({d.frame.PxX(v.x_mm), d.frame.PxY(v.y_mm), v.dx_um * plot.px_per_um,
                         -v.dy_um * plot.px_per_um, std::hypot(v.dx_um, v.dy_um), members[i][k], v.rgb});
    }
  }
  const int width = static_cast<int>(columns * cell_w + 10), height = static_cast<int>(top + rows * cell_h + 10);
  plot.files = RenderPlot(width, height, [&](cairo_t* cr) {
    SetColour(cr, 0x000000);
    DrawText(cr, kMargin, 22, options.title, TextAlign::kLeft, 13, true);
    // The stated scale: a bar of scale_bar_um drawn at px_per_um.
    const double bar_y = 44;
    SetColour(cr, 0xc0392b);
    cairo_set_line_width(cr, 2.0);
    cairo_move_to(cr, kMargin, bar_y);
    cairo_line_to(cr, kMargin + plot.scale_bar_px, bar_y);
    cairo_stroke(cr);
    SetColour(cr, 0x000000);
    DrawText(cr, kMargin + plot.scale_bar_px + 8, bar_y + 4,
             fmt::format("{:g} µm {} (vectors at {:.3g} px per µm; the axes in mm)", plot.scale_bar_um,
                         options.vector_words, plot.px_per_um),
             TextAlign::kLeft, 11);
    double key_x = kMargin;
    for (const auto& [words, rgb] : options.colour_key) {
      SetColour(cr, rgb);
      cairo_rectangle(cr, key_x, kKeyY - 8, 10, 10);
      cairo_fill(cr);
      SetColour(cr, 0x000000);
      DrawText(cr, key_x + 14, kKeyY, words, TextAlign::kLeft, 11);
      key_x += 24 + 7.0 * words.size();
    }
    for (size_t i = 0; i < panels.size(); ++i) DrawPanel(cr, panels[i], plot.panels[i], panels.size() > 1);
  });
  return plot;
}

}  // namespace platemeter::report
