// The vector primitive against the numbers it draws: each drawn length is the
// vector times the stated scale (also measured in the PNG), the scale bar,
// the cell means of an aggregated panel, and 100 000 residuals in a small file.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <random>

#include "platemeter/report/vector_plot.h"
#include "png_pixels.h"

namespace platemeter::report {
namespace {

VectorPanel RandomPanel(int n, unsigned seed, double systematic_um) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> position(-27.0, 27.0);
  std::normal_distribution<double> noise(0.0, 3.0);
  VectorPanel panel;
  panel.title = "frame";
  for (int i = 0; i < n; ++i) {
    const double x = position(rng), y = position(rng);
    // A radial pattern (the systematic part) plus noise.
    panel.vectors.push_back({x, y, systematic_um * x / 27.0 + noise(rng), systematic_um * y / 27.0 + noise(rng)});
  }
  return panel;
}

TEST(VectorPlot, DrawnLengthIsTheVectorTimesTheStatedScale) {
  VectorPlotOptions o;
  o.x_mm = {-27.5, 27.5};
  o.y_mm = {-27.5, 27.5};
  const VectorPanel panel = RandomPanel(200, 1, 4.0);
  const VectorPlot plot = DrawVectorPlot({panel}, o);
  ASSERT_EQ(plot.panels.size(), 1u);
  ASSERT_FALSE(plot.panels[0].aggregated);
  ASSERT_EQ(plot.panels[0].drawn.size(), panel.vectors.size());
  EXPECT_GT(plot.px_per_um, 0.0);
  EXPECT_NEAR(plot.scale_bar_px, plot.scale_bar_um * plot.px_per_um, 1e-9);
  for (size_t i = 0; i < panel.vectors.size(); ++i) {
    const PlotVector& v = panel.vectors[i];
    const DrawnVector& d = plot.panels[0].drawn[i];
    EXPECT_NEAR(std::hypot(d.dx_px, d.dy_px), std::hypot(v.dx_um, v.dy_um) * plot.px_per_um, 1e-9);
    EXPECT_NEAR(d.dy_px, -v.dy_um * plot.px_per_um, 1e-9);  // y up on the plate, down in the picture
    EXPECT_NEAR(d.x_px, plot.panels[0].frame.PxX(v.x_mm), 1e-9);
  }
  // Equal scale: a mm is as long across as up.
  EXPECT_NEAR(plot.panels[0].frame.PxPerX(), plot.panels[0].frame.PxPerY(), 1e-9);
}

TEST(VectorPlot, AVectorInThePngIsAsLongAsStated) {
  VectorPlotOptions o;
  o.x_mm = {-10, 10};
  o.y_mm = {-10, 10};
  o.px_per_um = 20.0;  // 10 um -> 200 px
  VectorPanel panel;
  panel.title = "one";
  panel.vectors = {{-5.0, 0.0, 10.0, 0.0}};
  const VectorPlot plot = DrawVectorPlot({panel}, o);
  testing::PngPixels png(plot.files.png);
  ASSERT_TRUE(png.ok());
  const DrawnVector& d = plot.panels[0].drawn[0];
  EXPECT_NEAR(d.dx_px, 200.0, 1e-9);
  // The red run along the vector's row, from its start.
  const int y = static_cast<int>(std::lround(d.y_px));
  int x = static_cast<int>(std::lround(d.x_px)) + 2, end = x;
  while (x < png.width()) {
    const auto c = png.At(x, y);
    if (c[0] > 150 && c[1] < 120) end = x;  // reddish
    if (png.IsWhite(x, y) && x > end + 3) break;
    ++x;
  }
  EXPECT_NEAR(end - d.x_px, 200.0, 2.0);
  // The bar: the largest 1-2-5 value under a sixth of the panel (560 px / 6 / 20 px per um = 4.7 um).
  EXPECT_EQ(plot.scale_bar_um, 2.0);
}

TEST(VectorPlot, ManyVectorsAreAggregatedIntoCellMeans) {
  VectorPlotOptions o;
  o.x_mm = {-27.5, 27.5};
  o.y_mm = {-27.5, 27.5};
  o.max_vectors = 3000;
  o.cells_across = 10;
  const VectorPanel panel = RandomPanel(10000, 2, 6.0);
  const VectorPlot plot = DrawVectorPlot({panel}, o);
  const VectorPanelDrawn& p = plot.panels[0];
  ASSERT_TRUE(p.aggregated);
  EXPECT_NEAR(p.cell_width_mm, 5.5, 1e-12);
  EXPECT_LE(p.drawn.size(), 100u);
  EXPECT_NE(p.legend.find("mean"), std::string::npos);
  // Independent cell means.
  std::map<std::pair<int, int>, std::array<double, 3>> sums;
  for (const PlotVector& v : panel.vectors) {
    auto& s = sums[{static_cast<int>((v.x_mm + 27.5) / 5.5), static_cast<int>((v.y_mm + 27.5) / 5.5)}];
    s[0] += v.dx_um;
    s[1] += v.dy_um;
    s[2] += 1;
  }
  ASSERT_EQ(sums.size(), p.drawn.size());
  int members = 0;
  for (const DrawnVector& d : p.drawn) {
    members += d.members;
    // The cell whose centre the vector starts from.
    const int i = static_cast<int>((d.x_px - p.frame.PxX(-27.5)) / (5.5 * p.frame.PxPerX()));
    const int j = static_cast<int>((p.frame.PxY(-27.5) - d.y_px) / (5.5 * p.frame.PxPerY()));
    const auto& s = sums.at({i, j});
    EXPECT_EQ(d.members, s[2]);
    EXPECT_NEAR(d.length_um, std::hypot(s[0] / s[2], s[1] / s[2]), 1e-9);
    EXPECT_NEAR(std::hypot(d.dx_px, d.dy_px), d.length_um * plot.px_per_um, 1e-9);
  }
  EXPECT_EQ(members, 10000);
}

TEST(VectorPlot, HundredThousandResidualsMakeASmallQuickPlot) {
  const auto start = std::chrono::steady_clock::now();
  VectorPlotOptions o;
  const VectorPlot plot = DrawVectorPlot({RandomPanel(100000, 3, 2.0)}, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(plot.panels[0].aggregated);
  EXPECT_LT(plot.files.svg.size(), 1000000u);
  EXPECT_LT(plot.files.png.size(), 1000000u);
  EXPECT_LT(seconds, 5.0);
}

TEST(VectorPlot, SmallMultiplesShareOneScale) {
  VectorPlotOptions o;
  const VectorPlot plot = DrawVectorPlot({RandomPanel(50, 4, 1.0), RandomPanel(50, 5, 8.0), RandomPanel(50, 6, 2.0)}, o);
  ASSERT_EQ(plot.panels.size(), 3u);
  for (const VectorPanelDrawn& p : plot.panels) {
    for (const DrawnVector& d : p.drawn) EXPECT_NEAR(std::hypot(d.dx_px, d.dy_px), d.length_um * plot.px_per_um, 1e-9);
  }
  // Side by side: the second panel right of the first.
  EXPECT_GT(plot.panels[1].frame.left_px, plot.panels[0].frame.left_px + plot.panels[0].frame.width_px);
}

}  // namespace
}  // namespace platemeter::report
