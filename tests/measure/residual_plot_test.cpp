// The residual vector plot: a PNG of the asked size whose arrows point along
// the residuals (read back through core's image access).
#include <gtest/gtest.h>

#include "platemeter/core/image.h"
#include "platemeter/measure/residual_plot.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

TEST(ResidualPlot, ArrowPointsAlongTheResidual) {
  // 3 x 3 crosses at 10 mm; only the centre one has a residual: +10 um in x.
  std::vector<ReseauObservation> obs;
  ReseauFit fit;
  for (int j = -1; j <= 1; ++j) {
    for (int i = -1; i <= 1; ++i) {
      obs.push_back({"X" + std::to_string(i + 2) + "Y" + std::to_string(j + 2), 10.0 * i, 10.0 * j, {}});
      fit.is_rejected.push_back(false);
      fit.residual_x_mm.push_back(i == 0 && j == 0 ? 0.010 : 0.0);
      fit.residual_y_mm.push_back(0.0);
    }
  }
  testing::TempDir dir;
  const std::string path = dir.file("residuals.png");
  ResidualPlotOptions options;
  options.size_px = 400;
  options.scale_bar_um = 10.0;  // 10 um = a tenth of the plot = 40 px
  WriteResidualPlotPng(path, obs, fit, options);
  const Image image = Image::Open(path);
  ASSERT_EQ(image.info().width_px, 400);
  ASSERT_EQ(image.info().height_px, 400);
  // The centre cross sits at the image centre; its arrow runs 40 px to the right.
  const std::vector<float> row = image.ReadWindow(PixelRect{0, 200, 400, 1}).values_dn;
  const float white = row[5];
  EXPECT_LT(row[200 + 20], 0.8f * white);  // on the arrow
  EXPECT_LT(row[200 + 35], 0.8f * white);  // near its head
  EXPECT_GT(row[200 - 20], 0.95f * white);  // nothing to the left
  EXPECT_GT(row[200 + 60], 0.95f * white);  // nothing beyond the tip (the next cross is 140 px away)
}

}  // namespace
}  // namespace platemeter
