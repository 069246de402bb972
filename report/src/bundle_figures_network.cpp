// The network figures of the bundle's HTML report: plan and side views with
// the rays, and the histogram of rays per point.
#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "bundle_figures.h"
#include "platemeter/report/histogram_plot.h"
#include "platemeter/report/network_plot.h"

namespace platemeter::report {

FigureSection NetworkFigures(const BundleResult& result, const BundleInput& input) {
  FigureSection section{"network", "The network", {}, {}};
  std::map<std::string, int> station_of, point_of;
  std::vector<std::array<double, 3>> stations, points;
  for (const BundleFrameResult& f : result.frames) {
    station_of[f.id] = static_cast<int>(stations.size());
    stations.push_back({f.position_m.x(), f.position_m.y(), f.position_m.z()});
  }
  for (const BundlePointResult& p : result.points) {
    point_of[p.id] = static_cast<int>(points.size());
    points.push_back({p.position_m.x(), p.position_m.y(), p.position_m.z()});
  }
  std::vector<std::pair<int, int>> rays;
  for (const ImageObservation& o : input.observations) {
    const auto s = station_of.find(o.frame), p = point_of.find(o.point_id);
    if (s != station_of.end() && p != point_of.end()) rays.emplace_back(p->second, s->second);
  }
  for (NetworkView view : {NetworkView::kPlan, NetworkView::kSide}) {
    NetworkPlotOptions o;
    const bool plan = view == NetworkView::kPlan;
    o.view = view;
    o.title = plan ? "The network, plan view (X-Y of the object frame)" : "The network, side view (X-Z of the object frame)";
    const NetworkPlot plot = DrawNetworkPlot(stations, points, rays, o);
    std::string caption = fmt::format("Adjusted exposure stations (triangles) and points (squares), equal scale on "
                                      "both axes, with the rays point to station ({} drawn of {}).",
                                      plot.rays_drawn, rays.size());
    if (plot.point_stride > 1) caption += fmt::format(" One point in {} drawn.", plot.point_stride);
    section.figures.push_back({plan ? "network-plan" : "network-side", caption, plot.files});
  }
  if (!result.points.empty()) {
    std::vector<double> rays_per_point;
    int most = 1;
    for (const BundlePointResult& p : result.points) {
      rays_per_point.push_back(p.rays);
      most = std::max(most, p.rays);
    }
    HistogramPlotOptions o;
    o.title = "Rays per point";
    o.x_label = "rays (frames observing the point)";
    // One bin per whole number of rays.
    o.range = AxisRange{0.5, most + 0.5};
    o.bins = most;
    const HistogramPlot plot = DrawHistogram(rays_per_point, o);
    section.figures.push_back({"rays-per-point",
                               fmt::format("How many frames observe each of the {} points (one bar per number of "
                                           "rays).",
                                           result.points.size()),
                               plot.files});
  }
  return section;
}

}  // namespace platemeter::report
