// Pins DESIGN.md's pixel convention: x = column, y = row, the centre of the
// top-left pixel is (0, 0). A synthetic dot whose centre is known in that
// convention is written to a file, read back through core's image access, and
// re-measured with a plain first-moment centroid.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/core/pixel.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

// Integral over [a, b] of a unit-area 1D Gaussian centred at mu.
double GaussianMass(double a, double b, double mu, double sigma) {
  const double s = sigma * std::sqrt(2.0);
  return 0.5 * (std::erf((b - mu) / s) - std::erf((a - mu) / s));
}

// Pixel (col, row) covers [col - 0.5, col + 0.5) x [row - 0.5, row + 0.5) by the convention under test.
std::vector<float> RenderDot(long width, long height, double cx, double cy, double sigma, double flux) {
  std::vector<float> values(static_cast<size_t>(width * height));
  for (long row = 0; row < height; ++row) {
    for (long col = 0; col < width; ++col) {
      values[static_cast<size_t>(row * width + col)] = static_cast<float>(
          100.0 + flux * GaussianMass(col - 0.5, col + 0.5, cx, sigma) * GaussianMass(row - 0.5, row + 0.5, cy, sigma));
    }
  }
  return values;
}

TEST(PixelConvention, DotAtKnownSubPixelCentreIsReadBackThere) {
  testing::TempDir dir;
  const long width = 48, height = 40;
  const double cx = 17.3, cy = 22.85;  // between pixel centres 17/18 and 22/23
  const std::vector<float> dot = RenderDot(width, height, cx, cy, 2.0, 4.0e6);
  ImageWriterOptions options;
  options.width_px = width;
  options.height_px = height;
  options.sample_type = SampleType::kFloat32;
  options.tile_size_px = 16;
  const std::string path = dir.file("dot.tif");
  WriteImage(path, options, dot.data());

  const Image image = Image::Open(path);
  const ImageWindow window = image.ReadWindow({5, 8, 30, 28});  // a window, not the whole image
  double sum = 0, sum_x = 0, sum_y = 0;
  for (long row = window.rect.y0_px; row < window.rect.y_end_px(); ++row) {
    for (long col = window.rect.x0_px; col < window.rect.x_end_px(); ++col) {
      const double signal = window.at(col, row) - 100.0;  // background known exactly
      sum += signal;
      sum_x += signal * col;
      sum_y += signal * row;
    }
  }
  EXPECT_NEAR(sum_x / sum, cx, 1e-4);
  EXPECT_NEAR(sum_y / sum, cy, 1e-4);
  // The brightest pixel is the one whose area holds the centre.
  long best_col = window.rect.x0_px, best_row = window.rect.y0_px;
  for (long row = window.rect.y0_px; row < window.rect.y_end_px(); ++row) {
    for (long col = window.rect.x0_px; col < window.rect.x_end_px(); ++col) {
      if (window.at(col, row) > window.at(best_col, best_row)) {
        best_col = col;
        best_row = row;
      }
    }
  }
  EXPECT_EQ(best_col, PixelIndexOf(cx));
  EXPECT_EQ(best_row, PixelIndexOf(cy));
}

TEST(PixelConvention, ConversionsAtFileBoundaries) {
  // OIIO/OpenCV-resize corner coordinates: the top-left pixel's centre is at 0.5.
  EXPECT_DOUBLE_EQ(PixelFromCornerCoordinate(0.5), 0.0);
  EXPECT_DOUBLE_EQ(CornerCoordinateFromPixel(-0.5), 0.0);
  // FITS / SExtractor: the first pixel's centre is 1.
  EXPECT_DOUBLE_EQ(PixelFromFits(1.0), 0.0);
  EXPECT_DOUBLE_EQ(FitsFromPixel(99.25), 100.25);
  // Pixel 3 covers [2.5, 3.5).
  EXPECT_EQ(PixelIndexOf(2.5), 3);
  EXPECT_EQ(PixelIndexOf(3.4999), 3);
  EXPECT_EQ(PixelIndexOf(-0.5), 0);
  EXPECT_EQ(PixelIndexOf(-0.51), -1);
}

}  // namespace
}  // namespace platemeter
