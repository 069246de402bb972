#pragma once
// A heat map of a square matrix (a correlation matrix) with its rows and
// columns labelled, the values printed in the cells while they fit, and a
// colour scale: blue (min) through white (the middle) to red (max), so a
// colour's red minus blue grows with the value.
#include <array>
#include <string>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

struct HeatmapPlotOptions {
  std::string title;
  AxisRange value_range = {-1.0, 1.0};  // the colour scale's ends; values beyond take the end colours
  int cell_px = 0;                      // 0: 64 up to 10 rows, smaller beyond (at least 4)
  int max_annotated = 16;               // print the values in the cells up to this many rows
};

struct HeatmapPlot {
  RenderedPlot files;
  double cell_px = 0.0;
  double left_px = 0.0, top_px = 0.0;  // the matrix' top-left corner in the picture
  // Colour of cell (row, column) as drawn, RGB in [0, 1].
  std::vector<std::vector<std::array<double, 3>>> cell_rgb;
};

// The colour of a value on the scale (clamped to its range).
std::array<double, 3> HeatmapColour(double value, const AxisRange& range);

HeatmapPlot DrawHeatmap(const std::vector<std::vector<double>>& matrix, const std::vector<std::string>& labels,
                        const HeatmapPlotOptions& options);

}  // namespace platemeter::report
