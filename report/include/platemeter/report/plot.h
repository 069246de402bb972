#pragma once
// What every plot primitive returns besides its drawing: the files (SVG and
// PNG of the same drawing) and the axis ranges, so that a test can check the
// picture against the numbers it shows. Coordinates of a drawing are in
// pixels of the PNG (1 px = 1 pt of the SVG), x right, y DOWN (the image's
// convention, not the plot's).
#include <string>

namespace platemeter::report {

struct RenderedPlot {
  std::string svg;  // the SVG file's bytes
  std::string png;  // the PNG file's bytes (RGB, white background)
  int width_px = 0;
  int height_px = 0;
};

struct AxisRange {
  double min = 0.0;  // data units at the axis' start (left, or bottom)
  double max = 0.0;
};

// Where a plot's data area lies in the picture and its scale (px per data unit).
struct PlotFrame {
  double left_px = 0.0, top_px = 0.0, width_px = 0.0, height_px = 0.0;
  AxisRange x, y;
  double PxX(double x_value) const { return left_px + (x_value - x.min) / (x.max - x.min) * width_px; }
  // y up in the data, down in the picture.
  double PxY(double y_value) const { return top_px + (y.max - y_value) / (y.max - y.min) * height_px; }
  double PxPerX() const { return width_px / (x.max - x.min); }
  double PxPerY() const { return height_px / (y.max - y.min); }
};

}  // namespace platemeter::report
