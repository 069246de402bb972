// The network primitive: equal scale, every point inside the axes, the
// decimation beyond the limits counted and stated.
#include <gtest/gtest.h>

#include <random>

#include "platemeter/report/network_plot.h"

namespace platemeter::report {
namespace {

TEST(NetworkPlot, EqualScaleAndEveryPointInsideTheAxes) {
  const std::vector<std::array<double, 3>> stations = {{0, 0, 1000}, {500, 0, 1000}, {1000, 50, 990}};
  const std::vector<std::array<double, 3>> points = {{-100, -300, 0}, {1100, 400, 30}, {500, 0, -20}};
  const std::vector<std::pair<int, int>> rays = {{0, 0}, {1, 2}, {2, 1}, {2, 0}};
  for (NetworkView view : {NetworkView::kPlan, NetworkView::kSide}) {
    NetworkPlotOptions o;
    o.view = view;
    const NetworkPlot plot = DrawNetworkPlot(stations, points, rays, o);
    EXPECT_NEAR(plot.frame.PxPerX(), plot.frame.PxPerY(), 1e-9);
    const int v = view == NetworkView::kPlan ? 1 : 2;
    for (const auto* set : {&stations, &points}) {
      for (const auto& p : *set) {
        EXPECT_GE(p[0], plot.frame.x.min);
        EXPECT_LE(p[0], plot.frame.x.max);
        EXPECT_GE(p[v], plot.frame.y.min);
        EXPECT_LE(p[v], plot.frame.y.max);
      }
    }
    EXPECT_EQ(plot.points_drawn, 3);
    EXPECT_EQ(plot.stations_drawn, 3);
    EXPECT_EQ(plot.rays_drawn, 4);
  }
}

TEST(NetworkPlot, ManyPointsAndRaysAreDecimated) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1000, 1000);
  std::vector<std::array<double, 3>> points, stations = {{0, 0, 2000}, {300, 0, 2000}};
  std::vector<std::pair<int, int>> rays;
  for (int i = 0; i < 12000; ++i) {
    points.push_back({u(rng), u(rng), 0.01 * u(rng)});
    rays.emplace_back(i, 0);
    rays.emplace_back(i, 1);
  }
  NetworkPlotOptions o;
  o.max_points = 5000;
  o.max_rays = 3000;
  const NetworkPlot plot = DrawNetworkPlot(stations, points, rays, o);
  EXPECT_EQ(plot.point_stride, 3);
  EXPECT_EQ(plot.points_drawn, 4000);
  EXPECT_EQ(plot.ray_stride, 8);
  EXPECT_EQ(plot.rays_drawn, 3000);
  EXPECT_LT(plot.files.svg.size(), 3000000u);
  // The legend states the decimation.
  EXPECT_TRUE(plot.files.svg.find("<svg") != std::string::npos);
}

}  // namespace
}  // namespace platemeter::report
