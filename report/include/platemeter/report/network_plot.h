#pragma once
// The network: exposure stations and object points in the plan view (X-Y) or
// the side view (X-Z) of the object frame, at equal scale on both axes, with
// optional rays (point -> station). Beyond `max_points` points only every k-th
// is drawn, beyond `max_rays` rays every k-th ray (k stated in the legend), so
// that a block of 100 000 points stays a readable, small file.
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

enum class NetworkView { kPlan, kSide };  // X-Y, X-Z

struct NetworkPlotOptions {
  std::string title;
  NetworkView view = NetworkView::kPlan;
  bool rays = true;
  int max_points = 5000;
  int max_rays = 3000;
  int width_px = 760;
  int height_px = 640;
};

struct NetworkPlot {
  RenderedPlot files;
  PlotFrame frame;  // x: X (m), y: Y or Z (m)
  int stations_drawn = 0;
  int points_drawn = 0;
  int rays_drawn = 0;
  int point_stride = 1;  // every k-th point drawn
  int ray_stride = 1;    // every k-th ray drawn
};

// stations_m, points_m: object coordinates (X, Y, Z) in metres; rays: (point
// index, station index) pairs.
NetworkPlot DrawNetworkPlot(const std::vector<std::array<double, 3>>& stations_m,
                            const std::vector<std::array<double, 3>>& points_m,
                            const std::vector<std::pair<int, int>>& rays, const NetworkPlotOptions& options);

}  // namespace platemeter::report
