#pragma once
// Axes for the plot primitives: "nice" ranges and ticks (1, 2, 5 x 10^k), a
// frame with ticks, tick labels and axis titles, and text placement with
// cairo's toy text API.
#include <string>
#include <vector>

#include <cairo.h>

#include "platemeter/report/plot.h"

namespace platemeter::report {

// The range widened to whole multiples of a nice step, about `target` ticks.
// A degenerate range (min == max) is widened by one unit around it.
AxisRange NiceRange(double min, double max, int target = 6);
// Tick values inside the range, at the nice step.
std::vector<double> NiceTicks(const AxisRange& range, int target = 6);
// The largest 1, 2 or 5 x 10^k not above `value` (> 0).
double NiceBelow(double value);

// The data area of a box (px) with room for the labels; with `equal_scale` the
// ranges are widened so that one data unit is as long on both axes.
PlotFrame MakePlotFrame(double left_px, double top_px, double width_px, double height_px, AxisRange x, AxisRange y,
                        bool equal_scale);

// The frame's border, ticks, tick labels and the axis titles (with units).
void DrawAxes(cairo_t* cr, const PlotFrame& frame, const std::string& x_title, const std::string& y_title,
              double font_px = 11);

enum class TextAlign { kLeft, kCenter, kRight };
// Text with its baseline's reference point at (x, y).
void DrawText(cairo_t* cr, double x_px, double y_px, const std::string& text, TextAlign align, double font_px,
              bool bold = false);
// Short tick label: "0", "0.5", "1e-05", "-200".
std::string TickLabel(double value, double step);

}  // namespace platemeter::report
