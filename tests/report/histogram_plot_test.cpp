// The histogram primitive against the numbers it draws: counts from an
// independent count, the values outside the range, bar heights in the PNG.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "platemeter/report/histogram_plot.h"
#include "png_pixels.h"

namespace platemeter::report {
namespace {

std::vector<double> Gaussian(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.3, 1.2);
  std::vector<double> values;
  for (int i = 0; i < n; ++i) values.push_back(normal(rng));
  return values;
}

TEST(HistogramPlot, CountsMatchAnIndependentCountAndSumToTheInputs) {
  std::vector<double> values = Gaussian(5000, 7);
  values.push_back(NAN);
  values.push_back(40.0);  // a gross error, outside the range
  HistogramPlotOptions o;
  o.range = AxisRange{-4.0, 4.0};
  o.bins = 16;
  const HistogramPlot plot = DrawHistogram(values, o);
  ASSERT_EQ(plot.counts.size(), 16u);
  ASSERT_EQ(plot.bin_edges.size(), 17u);
  long sum = 0, outside = 0;
  for (long c : plot.counts) sum += c;
  std::vector<long> expected(16, 0);
  for (double v : values) {
    if (!(v >= -4.0 && v <= 4.0)) {
      ++outside;
      continue;
    }
    // Bin i holds [-4 + 0.5 i, -4 + 0.5 (i + 1)); 4.0 itself in the last.
    int i = 0;
    while (i < 15 && v >= -4.0 + 0.5 * (i + 1)) ++i;
    ++expected[i];
  }
  EXPECT_EQ(plot.outside, outside);
  EXPECT_GE(plot.outside, 2);
  EXPECT_EQ(sum + plot.outside, static_cast<long>(values.size()));
  for (int i = 0; i < 16; ++i) EXPECT_EQ(plot.counts[i], expected[i]) << "bin " << i;
  // The curve drawn is the values' own mean and sigma unless given.
  EXPECT_NEAR(plot.normal_mean, 0.3, 0.06);
}

TEST(HistogramPlot, BarsInThePngAreCountTimesTheAxisScale) {
  const std::vector<double> values = {0.5, 1.5, 1.6, 2.5, 2.6, 2.7, 2.8, 3.5, 3.6};
  HistogramPlotOptions o;
  o.range = AxisRange{0.0, 4.0};
  o.bins = 4;
  const HistogramPlot plot = DrawHistogram(values, o);
  ASSERT_EQ(plot.counts, (std::vector<long>{1, 2, 4, 2}));
  testing::PngPixels png(plot.files.png);
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), plot.files.width_px);
  const int baseline = static_cast<int>(std::floor(plot.frame.PxY(0))) - 1;
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(plot.bar_height_px[i], plot.counts[i] * plot.frame.PxPerY(), 1e-9);
    // Count the bar's pixels up from the baseline at the bin's centre.
    const int x = static_cast<int>(plot.frame.PxX(0.5 + i));
    int height = 0;
    while (baseline - height > 0 && !png.IsWhite(x, baseline - height)) ++height;
    EXPECT_NEAR(height, plot.bar_height_px[i], 2.0) << "bin " << i;
  }
}

TEST(HistogramPlot, WritesAnSvgAndAPngOfTheSameSize) {
  const HistogramPlot plot = DrawHistogram(Gaussian(200, 3), {});
  EXPECT_EQ(plot.files.png.substr(1, 3), "PNG");
  EXPECT_NE(plot.files.svg.find("<svg"), std::string::npos);
  EXPECT_NE(plot.files.svg.find("width=\"640pt\""), std::string::npos) << plot.files.svg.substr(0, 300);
}

}  // namespace
}  // namespace platemeter::report
