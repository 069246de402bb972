// The profile primitive against the numbers it draws: the band's half height
// is the sigma at every sampled radius, in the returned numbers and in the PNG.
#include <gtest/gtest.h>

#include <cmath>

#include "platemeter/core/error.h"
#include "platemeter/report/profile_plot.h"
#include "png_pixels.h"

namespace platemeter::report {
namespace {

ProfileSeries Series() {
  ProfileSeries s{"radial", {}, {}, {}, 0x1f4e9a};
  for (int i = 0; i <= 40; ++i) {
    const double r = i;
    s.x.push_back(r);
    s.value.push_back(60.0 + 0.5 * r);
    s.sigma.push_back(2.0 + 0.25 * r);
  }
  return s;
}

TEST(ProfilePlot, BandHalfHeightIsTheSigmaAtEverySample) {
  const ProfileSeries s = Series();
  const ProfilePlot plot = DrawProfilePlot({s}, {});
  ASSERT_EQ(plot.band_half_height_px.size(), 1u);
  ASSERT_EQ(plot.band_half_height_px[0].size(), s.x.size());
  for (size_t i = 0; i < s.x.size(); ++i) {
    EXPECT_NEAR(plot.band_half_height_px[0][i], s.sigma[i] * plot.frame.PxPerY(), 1e-9);
  }
  // The axis shows zero and the whole band.
  EXPECT_LE(plot.frame.y.min, 0.0);
  EXPECT_GE(plot.frame.y.max, 60.0 + 20.0 + 12.0);
}

TEST(ProfilePlot, TheBandInThePngSpansTwoSigmas) {
  const ProfileSeries s = Series();
  const ProfilePlot plot = DrawProfilePlot({s}, {});
  testing::PngPixels png(plot.files.png);
  ASSERT_TRUE(png.ok());
  const PlotFrame& f = plot.frame;
  for (int i : {20, 30, 38}) {  // right of the legend
    const int x = static_cast<int>(std::lround(f.PxX(s.x[i])));
    const int zero = static_cast<int>(f.PxY(0));
    int first = -1, last = -1;
    for (int y = static_cast<int>(f.top_px) + 2; y < zero - 3; ++y) {
      if (png.IsWhite(x, y)) continue;
      if (first < 0) first = y;
      last = y;
    }
    ASSERT_GE(first, 0) << "no band at r = " << s.x[i];
    EXPECT_NEAR(last - first + 1, 2 * plot.band_half_height_px[0][i], 2.5) << "r = " << s.x[i];
    EXPECT_NEAR(0.5 * (first + last), f.PxY(s.value[i]), 2.0) << "r = " << s.x[i];
  }
}

TEST(ProfilePlot, RefusesSeriesOfUnequalLength) {
  ProfileSeries s = Series();
  s.sigma.pop_back();
  EXPECT_THROW(DrawProfilePlot({s}, {}), Error);
}

}  // namespace
}  // namespace platemeter::report
