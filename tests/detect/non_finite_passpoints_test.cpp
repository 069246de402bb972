// Masked pixels (core/image.h) in the passpoint detector, on the bundled
// Hasselblad plate (41 rings) written as a float scan: a masked pixel on each of
// ten rings, and 200 scattered, cost no ring and move none by more than its
// sigma; a ring whose fit region is mostly masked is missing with reason
// masked_pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/detect/passpoint_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

struct FloatPlate {
  std::vector<PixelPoint> rings;  // truth centres
  long width_px = 0, height_px = 0;
  double pixel_size_um = 0.0;
  std::vector<float> values;  // the 8-bit DN scaled to [0, 1]
};

const FloatPlate& Plate() {
  static const FloatPlate plate = [] {
    testing::TempDir dir;
    const DefinitionRegistry registry;
    const std::string path = std::string(PLATEMETER_SOURCE_DIR) + "/samples/specs/hasselblad-passpoints.toml";
    sim::SimulatedPlate sim_plate =
        sim::BuildSimulatedPlate(sim::ParseSimulationSpec(testing::ReadTextFile(path), path), registry);
    FloatPlate p;
    p.pixel_size_um = sim_plate.pixel_size_um;
    for (const MeasuredPoint& t : sim_plate.truth)
      if (t.kind == PointKind::kPasspoint && t.x_px) p.rings.push_back({*t.x_px, *t.y_px});
    const Image image = Image::Open(sim::WriteSimulatedPlate(sim_plate, dir.path().string()).image_path);
    p.width_px = image.info().width_px;
    p.height_px = image.info().height_px;
    p.values = image.ReadWindow(image.Bounds()).values_dn;
    for (float& v : p.values) v /= 255.0f;
    return p;
  }();
  return plate;
}

Image WriteFloat(const testing::TempDir& dir, const std::string& name, const std::vector<float>& values) {
  ImageWriterOptions options;
  options.width_px = Plate().width_px;
  options.height_px = Plate().height_px;
  options.sample_type = SampleType::kFloat32;
  options.compression = "none";
  WriteImage(dir.file(name), options, values.data());
  return Image::Open(dir.file(name));
}

PasspointDetectorOptions RingOptions() {
  PasspointDetectorOptions o;
  o.shape = MarkType::kRing;
  o.diameter_px = 250.0 / Plate().pixel_size_um;
  o.line_width_px = 50.0 / Plate().pixel_size_um;
  o.dark = true;
  return o;
}

const PasspointPoint* Near(const PasspointDetection& d, const PixelPoint& p) {
  for (const PasspointPoint& q : d.points)
    if (std::hypot(q.point.position_px.x_px - p.x_px, q.point.position_px.y_px - p.y_px) < 2.0) return &q;
  return nullptr;
}

TEST(NonFinitePasspoints, RingsWithMaskedPixelsAreMeasuredAMostlyMaskedOneIsMissing) {
  testing::TempDir dir;
  const FloatPlate& p = Plate();
  ASSERT_EQ(p.rings.size(), 41u);
  std::vector<float> values = p.values;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto set_nan = [&](long x, long y) { values[static_cast<size_t>(y * p.width_px + x)] = nan; };
  const double ring_radius_px = 0.5 * (RingOptions().diameter_px - RingOptions().line_width_px);
  for (size_t k = 0; k < 10; ++k) {  // one pixel on the ring's line
    const double a = 0.6 * static_cast<double>(k);
    set_nan(std::lround(p.rings[k].x_px + ring_radius_px * std::cos(a)),
            std::lround(p.rings[k].y_px + ring_radius_px * std::sin(a)));
  }
  std::mt19937 rng(28);
  for (int k = 0; k < 200; ++k) set_nan(static_cast<long>(rng() % p.width_px), static_cast<long>(rng() % p.height_px));
  // Ring 20: its lower half (and the background below it) masked.
  const PixelPoint half = p.rings[20];
  for (long y = std::lround(half.y_px) + 1; y <= std::lround(half.y_px) + 14; ++y)
    for (long x = std::lround(half.x_px) - 14; x <= std::lround(half.x_px) + 14; ++x) set_nan(x, y);

  const PasspointDetection clean = DetectPasspoints(WriteFloat(dir, "clean.tif", p.values), RingOptions());
  const Image masked_image = WriteFloat(dir, "masked.tif", values);
  const PasspointDetection masked = DetectPasspoints(masked_image, RingOptions());
  EXPECT_EQ(clean.measured, 41) << clean.summary;
  for (size_t k = 0; k < p.rings.size(); ++k) {
    const PasspointPoint* c = Near(clean, p.rings[k]);
    ASSERT_TRUE(c && c->point.status == PointStatus::kMeasured) << "ring " << k;
    if (k == 20) continue;
    const PasspointPoint* m = Near(masked, p.rings[k]);
    ASSERT_TRUE(m) << "ring " << k << " lost";
    EXPECT_EQ(m->point.status, PointStatus::kMeasured) << "ring " << k << ": " << m->point.reason;
    EXPECT_LT(std::abs(m->point.position_px.x_px - c->point.position_px.x_px), c->point.sigma_x_px) << "ring " << k;
    EXPECT_LT(std::abs(m->point.position_px.y_px - c->point.position_px.y_px), c->point.sigma_y_px) << "ring " << k;
    if (k < 10) EXPECT_GE(m->fit.pixels_masked, 1) << "ring " << k;
  }
  EXPECT_GE(masked.measured, 40) << masked.summary;

  // Ring 20 asked for by a list: found there, but with most of its fit region masked.
  const std::vector<ApproximatePasspoint> list = {{"HALF", half}};
  const PasspointDetection listed = DetectPasspoints(masked_image, RingOptions(), &list);
  ASSERT_EQ(listed.points.size(), 1u);
  EXPECT_EQ(listed.points[0].point.status, PointStatus::kMissing);
  EXPECT_EQ(listed.points[0].point.reason, "masked_pixels");
}

}  // namespace
}  // namespace platemeter
