#pragma once
// Vectors over a plane (residual vectors over a frame's format, a distortion
// field): each vector from its point, drawn at a stated scale (px per um) with
// a scale bar, in one panel or a grid of small multiples that share the scale.
//
// Readability with many vectors: lines get thinner past a few hundred and lose
// their arrowheads; a panel with more than `max_vectors` is aggregated into a
// grid of cells and each cell draws the MEAN vector of its members from the
// cell's centre (the systematic part; random noise averages out), which the
// panel's legend says with the cell size and the count.
#include <string>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

inline constexpr unsigned kVectorRed = 0xc0392b;

struct PlotVector {
  double x_mm = 0.0, y_mm = 0.0;    // where it starts (plate frame: x right, y up)
  double dx_um = 0.0, dy_um = 0.0;  // the vector (residual or correction)
  unsigned rgb = kVectorRed;        // its colour (e.g. one per star trail); cell means are red
};

// A dot at a point (e.g. a measured star image), in its colour.
struct PlotMarker {
  double x_mm = 0.0, y_mm = 0.0;
  unsigned rgb = 0x1f4e9a;
};

// A line over the panel (e.g. the axis of maximum tangential distortion), dashed or solid.
struct PlotLine {
  double x0_mm = 0.0, y0_mm = 0.0, x1_mm = 0.0, y1_mm = 0.0;
  bool dashed = true;
  unsigned rgb = 0x000000;
};

// A text at a point (e.g. a corner reseau number keying the plot to the focal plane).
struct PlotLabel {
  double x_mm = 0.0, y_mm = 0.0;
  std::string text;
};

struct VectorPanel {
  std::string title;  // e.g. the frame id
  std::vector<PlotVector> vectors;
  std::vector<PlotMarker> markers;  // drawn under the vectors; count in the extent
  std::vector<PlotLine> lines;      // clipped to the panel
  std::vector<PlotLabel> labels;
};

struct VectorPlotOptions {
  std::string title;
  std::string vector_words = "residual";  // legend: "residual", "distortion correction"
  AxisRange x_mm, y_mm;       // the area shown (the format); empty (min == max): the points' extent
  double px_per_um = 0.0;     // 0: the 95th percentile length drawn as 1/15 of a panel's width
  int max_vectors = 3000;     // per panel; beyond: aggregated into cells
  int cells_across = 24;      // the aggregation grid along the longer side
  int panel_px = 0;           // a panel's data area; 0: 560 for one panel, 240 for several
  int columns = 0;            // 0: ceil(sqrt(panels))
  // A key of the colours under the title, e.g. {"trail 1", 0x1f77b4}; empty: none.
  std::vector<std::pair<std::string, unsigned>> colour_key;
};

struct DrawnVector {
  double x_px = 0.0, y_px = 0.0;    // start in the PNG (y down)
  double dx_px = 0.0, dy_px = 0.0;  // the drawn vector (y down)
  double length_um = 0.0;           // the vector's length (the cell mean's, when aggregated)
  int members = 1;                  // vectors it stands for (1, or a cell's count)
  unsigned rgb = kVectorRed;        // its colour
};

struct VectorPanelDrawn {
  PlotFrame frame;  // x_mm, y_mm
  bool aggregated = false;
  double cell_width_mm = 0.0, cell_height_mm = 0.0;  // when aggregated
  std::vector<DrawnVector> drawn;
  std::string legend;
};

struct VectorPlot {
  RenderedPlot files;
  double px_per_um = 0.0;      // the stated scale, shared by every panel
  double scale_bar_um = 0.0;   // the bar's length in um
  double scale_bar_px = 0.0;   // and in px (= scale_bar_um x px_per_um)
  std::vector<VectorPanelDrawn> panels;
};

// The scale DrawVectorPlot picks with px_per_um = 0: the 95th percentile of the
// lengths of the vectors it draws (cell means where it aggregates) as 1/15 of
// `panel_px`. Pass it to several plots so that they share one scale.
double AutoVectorScale(const std::vector<VectorPanel>& panels, const VectorPlotOptions& options, double panel_px);

VectorPlot DrawVectorPlot(const std::vector<VectorPanel>& panels, const VectorPlotOptions& options);

}  // namespace platemeter::report
