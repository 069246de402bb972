// Band rendering: independence of the band split, noise statistics, background
// (vignetting, terrain) against hand-derived values, clipping and quantization.
#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/samples/render.h"
#include "support/test_support.h"

namespace platemeter::sim {
namespace {

SceneMark Mark(MarkKind kind, MarkShapeKind shape, double x, double y, double amplitude) {
  SceneMark mark;
  mark.id = MarkKindName(kind);
  mark.kind = kind;
  mark.shape = shape;
  mark.centre_px = {x, y};
  mark.size_um = 150.0;
  mark.line_width_um = 15.0;
  mark.amplitude_dn = amplitude;
  const double a = 0.01;
  mark.px_from_um[0] = 0.2 * std::cos(a), mark.px_from_um[1] = 0.2 * std::sin(a);
  mark.px_from_um[2] = 0.2 * std::sin(a), mark.px_from_um[3] = -0.2 * std::cos(a);
  return mark;
}

Scene BusyScene() {
  Scene scene;
  scene.width_px = 201;
  scene.height_px = 300;
  scene.background.level_dn = 20000.0;
  scene.background.terrain_amplitude_dn = 300.0;
  scene.background.terrain_scale_px = 80.0;
  scene.background.vignetting_fraction = 0.1;
  scene.background.optical_centre_px = {100, 150};
  scene.background.vignetting_radius_px = 180.0;
  scene.noise.scanner_blur_sigma_px = 0.6;
  scene.noise.sensor_sigma_dn = 3.0;
  scene.noise.grain_sigma_dn = 2.0;
  scene.noise.seed = 7;
  scene.marks.push_back(Mark(MarkKind::kReseauCross, MarkShapeKind::kCross, 40.2, 62.7, -3000));  // across 64
  SceneMark damaged = Mark(MarkKind::kReseauCross, MarkShapeKind::kCross, 150.6, 127.9, -3000);
  damaged.damage_fraction = 0.4;
  damaged.seed = 3;
  scene.marks.push_back(damaged);
  scene.marks.push_back(Mark(MarkKind::kFiducial, MarkShapeKind::kDot, 100.1, 30.3, 2000));
  scene.marks.push_back(Mark(MarkKind::kFiducial, MarkShapeKind::kRing, 60.5, 200.5, -2500));
  scene.marks.push_back(Mark(MarkKind::kFiducial, MarkShapeKind::kCorner, 5.0, 295.0, -2500));  // clipped by the edges
  SceneMark star = Mark(MarkKind::kStar, MarkShapeKind::kPsf, 120.3, 191.2, 80000);
  scene.marks.push_back(star);
  SceneMark dash = Mark(MarkKind::kTrailDash, MarkShapeKind::kSegment, 150.0, 250.0, 90000);
  dash.segment_u_um = 150.0, dash.segment_v_um = 40.0;
  scene.marks.push_back(dash);
  scene.marks.push_back(Mark(MarkKind::kDust, MarkShapeKind::kDot, 30.0, 130.0, -4000));
  SceneMark scratch = Mark(MarkKind::kScratch, MarkShapeKind::kSegment, 100.0, 150.0, 1500);
  scratch.size_um = 800.0;
  scratch.line_width_um = 5.0;
  scratch.corner_angle_rad = 1.0;
  scene.marks.push_back(scratch);
  scene.marks.push_back(Mark(MarkKind::kFalseMark, MarkShapeKind::kCross, 190.0, 10.0, -2000));
  return scene;
}

TEST(RenderBand, BandSplitDoesNotChangeAnyPixel) {
  const Scene scene = BusyScene();
  const SceneRenderer renderer(scene);
  std::vector<float> whole(scene.width_px * scene.height_px), banded(whole.size(), -1.0f);
  renderer.RenderBand(0, scene.height_px, whole.data());
  for (long y0 = 0; y0 < scene.height_px; y0 += 64)
    renderer.RenderBand(y0, std::min(64L, scene.height_px - y0), banded.data() + y0 * scene.width_px);
  EXPECT_EQ(0, std::memcmp(whole.data(), banded.data(), whole.size() * sizeof(float)));
  // An odd band through the free function, too.
  std::vector<float> odd(37 * scene.width_px);
  RenderBand(scene, 101, 37, odd.data());
  EXPECT_EQ(0, std::memcmp(whole.data() + 101 * scene.width_px, odd.data(), odd.size() * sizeof(float)));
  // Marks are really there: the dust's centre is dark by ~ its amplitude.
  const double dust_centre = whole[130 * scene.width_px + 30];
  EXPECT_LT(dust_centre, renderer.BackgroundAt(30, 130) - 3500.0);
  // Quantized output is integral.
  for (float v : whole) ASSERT_EQ(v, std::nearbyint(v));
}

// Band by band through core's tiled TIFF writer, read back: the same DN.
TEST(RenderBand, TiledTiffWrittenBandByBandReadsBackExactly) {
  const Scene scene = BusyScene();
  const SceneRenderer renderer(scene);
  platemeter::testing::TempDir dir;
  const std::string path = dir.file("plate.tif");
  ImageWriterOptions options;
  options.width_px = scene.width_px;
  options.height_px = scene.height_px;
  options.tile_size_px = 64;
  platemeter::ImageWriter writer(path, options);
  const long band = writer.band_height_px();
  std::vector<float> values(band * scene.width_px);
  for (long y0 = 0; y0 < scene.height_px; y0 += band) {
    const long rows = std::min(band, scene.height_px - y0);
    renderer.RenderBand(y0, rows, values.data());
    writer.WriteBand(y0, rows, values.data());
  }
  writer.Finish();
  std::vector<float> whole(scene.width_px * scene.height_px);
  renderer.RenderBand(0, scene.height_px, whole.data());
  const Image image = Image::Open(path);
  const ImageWindow read = image.ReadWindow(image.Bounds());
  ASSERT_EQ(read.values_dn.size(), whole.size());
  EXPECT_EQ(0, std::memcmp(read.values_dn.data(), whole.data(), whole.size() * sizeof(float)));
}

TEST(RenderBand, NoiseIsWhiteGaussianWithTheCombinedSigma) {
  Scene scene;
  scene.width_px = 512;
  scene.height_px = 512;
  scene.background.level_dn = 1000.0;
  scene.noise.sensor_sigma_dn = 3.0;
  scene.noise.grain_sigma_dn = 4.0;  // combined: 5
  scene.noise.quantize = false;
  std::vector<float> image(scene.width_px * scene.height_px);
  RenderBand(scene, 0, scene.height_px, image.data());
  const long n = image.size();
  double s = 0, s2 = 0, lag_x = 0, lag_y = 0;
  long tails = 0;
  for (long i = 0; i < n; ++i) {
    const double z = image[i] - 1000.0;
    s += z, s2 += z * z;
    if (std::abs(z) > 15.0) ++tails;
    if (i % scene.width_px + 1 < scene.width_px) lag_x += z * (image[i + 1] - 1000.0);
    if (i + scene.width_px < n) lag_y += z * (image[i + scene.width_px] - 1000.0);
  }
  const double mean = s / n, variance = s2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 0.05);                    // 5 / 512 = 0.01 standard error
  EXPECT_NEAR(std::sqrt(variance), 5.0, 0.05);     // 0.14 % standard error
  EXPECT_NEAR(lag_x / n / variance, 0.0, 0.01);    // 0.002 standard error
  EXPECT_NEAR(lag_y / n / variance, 0.0, 0.01);
  EXPECT_NEAR(static_cast<double>(tails) / n, 0.0026998, 0.0005);  // P(|z| > 3 sigma)
  // Another seed gives another image.
  scene.noise.seed = 2;
  std::vector<float> other(image.size());
  RenderBand(scene, 0, scene.height_px, other.data());
  EXPECT_NE(0, std::memcmp(image.data(), other.data(), 4096));
  EXPECT_EQ(StandardNormalAt(1, 10, 20), StandardNormalAt(1, 10, 20));
}

TEST(RenderBand, VignettingAndTerrain) {
  Scene scene;
  scene.width_px = 1024;
  scene.height_px = 1024;
  scene.background.level_dn = 1000.0;
  scene.background.vignetting_fraction = 0.2;
  scene.background.optical_centre_px = {50, 60};
  scene.background.vignetting_radius_px = 100.0;
  scene.noise.quantize = false;
  {
    const SceneRenderer renderer(scene);
    EXPECT_DOUBLE_EQ(renderer.BackgroundAt(50, 60), 1000.0);
    EXPECT_DOUBLE_EQ(renderer.BackgroundAt(150, 60), 800.0);   // at the radius: the given fall-off
    EXPECT_DOUBLE_EQ(renderer.BackgroundAt(110, 140), 800.0);  // 60^2 + 80^2 = 100^2
    EXPECT_DOUBLE_EQ(renderer.BackgroundAt(100, 60), 950.0);   // half the radius: a quarter of it
    std::vector<float> row(scene.width_px);
    renderer.RenderBand(60, 1, row.data());
    EXPECT_FLOAT_EQ(row[150], 800.0f);
  }
  scene.background.vignetting_fraction = 0.0;
  scene.background.terrain_amplitude_dn = 200.0;
  scene.background.terrain_scale_px = 100.0;
  const SceneRenderer renderer(scene);
  double s = 0, s2 = 0, steepest = 0;
  for (long y = 0; y < scene.height_px; ++y)
    for (long x = 0; x < scene.width_px; ++x) {
      const double v = renderer.BackgroundAt(x, y) - 1000.0;
      s += v, s2 += v * v;
      if (x > 0) steepest = std::max(steepest, std::abs(v + 1000.0 - renderer.BackgroundAt(x - 1, y)));
    }
  const double n = scene.width_px * scene.height_px;
  EXPECT_NEAR(std::sqrt(s2 / n), 200.0, 30.0);  // RMS = terrain_amplitude_dn over many wavelengths
  EXPECT_NEAR(s / n, 0.0, 30.0);
  // Smooth: 8 waves of total RMS A and wavelength >= 0.6 scale change by at most
  // 4 A * 2 pi / (0.6 scale) per pixel.
  EXPECT_LT(steepest, 4 * 200.0 * 2 * M_PI / 60.0);
  EXPECT_GT(steepest, 1.0);
}

TEST(RenderBand, ClipsAtSaturationAndZero) {
  Scene scene;
  scene.width_px = 64;
  scene.height_px = 64;
  scene.background.level_dn = 1000.0;
  scene.noise.saturation_dn = 4095.0;
  scene.marks.push_back(Mark(MarkKind::kFiducial, MarkShapeKind::kDot, 20, 20, 10000));
  scene.marks.push_back(Mark(MarkKind::kFiducial, MarkShapeKind::kDot, 45, 45, -5000));
  std::vector<float> image(64 * 64);
  RenderBand(scene, 0, 64, image.data());
  EXPECT_EQ(image[20 * 64 + 20], 4095.0f);
  EXPECT_EQ(image[45 * 64 + 45], 0.0f);
  EXPECT_EQ(image[0], 1000.0f);
  EXPECT_THROW(RenderBand(scene, 60, 10, image.data()), Error);
}

}  // namespace
}  // namespace platemeter::sim
