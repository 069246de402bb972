// The heat map against the numbers it draws: colours monotone in the value,
// each cell's colour in the PNG at its centre, bad matrices refused.
#include <gtest/gtest.h>

#include <cmath>

#include "platemeter/core/error.h"
#include "platemeter/report/heatmap_plot.h"
#include "png_pixels.h"

namespace platemeter::report {
namespace {

TEST(HeatmapPlot, ColourIsMonotoneInTheValue) {
  const AxisRange range{-1.0, 1.0};
  // Red minus blue strictly rises with the value over the whole scale.
  double last_difference = -INFINITY;
  for (int i = 0; i <= 200; ++i) {
    const double v = -1.0 + 2.0 * i / 200;
    const auto c = HeatmapColour(v, range);
    EXPECT_GT(c[0] - c[2], last_difference) << v;
    last_difference = c[0] - c[2];
  }
  // Clamped beyond the range; the ends are blue and red.
  EXPECT_EQ(HeatmapColour(-3.0, range), HeatmapColour(-1.0, range));
  EXPECT_LT(HeatmapColour(-1.0, range)[0], HeatmapColour(-1.0, range)[2]);
  EXPECT_GT(HeatmapColour(1.0, range)[0], HeatmapColour(1.0, range)[2]);
  const auto white = HeatmapColour(0.0, range);
  EXPECT_NEAR(white[0] + white[1] + white[2], 3.0, 1e-12);
}

TEST(HeatmapPlot, EachCellInThePngHasItsValuesColour) {
  const std::vector<std::vector<double>> r = {
      {1.0, -0.95, 0.3}, {-0.95, 1.0, 0.0}, {0.3, 0.0, 1.0}};
  HeatmapPlotOptions o;
  o.max_annotated = 0;  // no text over the cells' centres
  const HeatmapPlot plot = DrawHeatmap(r, {"c_mm", "k1_per_mm2", "p1_per_mm"}, o);
  testing::PngPixels png(plot.files.png);
  ASSERT_TRUE(png.ok());
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      const auto expected = HeatmapColour(r[i][k], o.value_range);
      EXPECT_EQ(plot.cell_rgb[i][k], expected);
      const auto c = png.At(static_cast<int>(plot.left_px + (k + 0.5) * plot.cell_px),
                            static_cast<int>(plot.top_px + (i + 0.5) * plot.cell_px));
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], 255 * expected[ch], 1.5) << i << "," << k << " channel " << ch;
    }
  }
  // The labels are in the SVG as text (glyphs): at least the picture is not empty there.
  EXPECT_FALSE(png.IsWhite(static_cast<int>(plot.left_px) - 1, static_cast<int>(plot.top_px) + 5) &&
               png.IsWhite(static_cast<int>(plot.left_px) - 20, static_cast<int>(plot.top_px + 0.5 * plot.cell_px)));
}

TEST(HeatmapPlot, RefusesANonSquareMatrixOrMissingLabels) {
  EXPECT_THROW(DrawHeatmap({{1.0, 0.0}}, {"a"}, {}), Error);
  EXPECT_THROW(DrawHeatmap({{1.0, 0.0}, {0.0, 1.0}}, {"a"}, {}), Error);
}

}  // namespace
}  // namespace platemeter::report
