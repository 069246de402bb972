// Masked pixels (core/image.h): a float scan's NaN, infinite and |value| > 1e10
// samples are missing data. On a simulated SN-004 terrain plate written as a
// float scan, 100 of them (NaN, +-Inf, +-3e38, 1e20; 40 on cross arms, one on a
// fiducial) are counted exactly, cost no cross or fiducial, and move no centre
// by more than its sigma; a cross whose fit region is mostly masked is missing
// with reason masked_pixels, the others unaffected.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/detect/fiducial_detector.h"
#include "platemeter/detect/overview.h"
#include "platemeter/detect/reseau_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

constexpr double kPixelUm = 40.0;  // the CI size: 3200 x 3200 px

std::string SpecNonFinite() {
  return "name = \"plate\"\ncamera = \"sn004-terrain\"\nseed = 5\n"
         "[output]\npixel_size_um = 40.0\nmargin_mm = 1.0\n"
         "[film]\naffine_ppm = [40.0, 5.0, -3.0, -25.0]\n"
         "[scanner]\nrotation_deg = 0.4\nnon_orthogonality_arcsec = 10.0\n"
         "[marks.reseau]\npolarity = \"dark\"\ncontrast_dn = 14000.0\n"
         "[background]\nlevel_dn = 20000.0\nterrain_amplitude_dn = 3000.0\nterrain_scale_mm = 15.0\n"
         "[noise]\nblur_sigma_um = 8.0\nsensor_sigma_dn = 100.0\ngrain_sigma_dn = 150.0\n";
}

// The plate rendered once, its 16-bit DN scaled to [0, 1] as a float scanner writes them.
struct FloatPlateOfPixels {
  sim::SimulatedPlate plate;
  long width_px = 0, height_px = 0;
  std::vector<float> values;  // row-major, [0, 1]
};

const FloatPlateOfPixels& PlateOfPixels() {
  static const FloatPlateOfPixels plate = [] {
    testing::TempDir dir;
    const DefinitionRegistry registry;
    FloatPlateOfPixels p;
    p.plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(SpecNonFinite(), "test spec"), registry);
    const Image image = Image::Open(sim::WriteSimulatedPlate(p.plate, dir.path().string()).image_path);
    p.width_px = image.info().width_px;
    p.height_px = image.info().height_px;
    p.values = image.ReadWindow(image.Bounds()).values_dn;
    for (float& v : p.values) v /= 65535.0f;
    return p;
  }();
  return plate;
}

std::string WriteFloat(const std::string& path, const std::vector<float>& values) {
  ImageWriterOptions options;
  options.width_px = PlateOfPixels().width_px;
  options.height_px = PlateOfPixels().height_px;
  options.sample_type = SampleType::kFloat32;
  options.pixel_size_um = kPixelUm;
  options.compression = "none";  // quick to write; compression plays no part here
  WriteImage(path, options, values.data());
  return path;
}

PixelPoint TruthOf(const std::string& id, PointKind kind) {
  for (const MeasuredPoint& t : PlateOfPixels().plate.truth)
    if (t.kind == kind && t.id == id && t.x_px) return {*t.x_px, *t.y_px};
  ADD_FAILURE() << "no truth for " << id;
  return {};
}

// 100 distinct bad pixels: 40 on the arms of the first 40 crosses (3 to 8 px from the centre), one on the
// first fiducial's mark, the rest scattered; the values cycle through NaN, +Inf, -Inf, 3e38, -3e38, 1e20.
std::vector<float> WithBadPixels(std::set<std::pair<long, long>>* bad) {
  const FloatPlateOfPixels& p = PlateOfPixels();
  std::vector<float> values = p.values;
  const float kinds[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                         -std::numeric_limits<float>::infinity(), 3e38f, -3e38f, 1e20f};
  auto add = [&](long x, long y) {
    if (x < 0 || y < 0 || x >= p.width_px || y >= p.height_px || !bad->insert({x, y}).second) return;
    values[static_cast<size_t>(y * p.width_px + x)] = kinds[bad->size() % 6];
  };
  int on_arms = 0;
  for (const MeasuredPoint& t : p.plate.truth) {
    if (t.kind != PointKind::kReseau || !t.x_px || on_arms == 40) continue;
    const long k = 3 + on_arms % 6, cx = std::lround(*t.x_px), cy = std::lround(*t.y_px);
    const long dx[] = {k, -k, 0, 0}, dy[] = {0, 0, k, -k};
    add(cx + dx[on_arms % 4], cy + dy[on_arms % 4]);
    ++on_arms;
  }
  for (const MeasuredPoint& t : p.plate.truth)
    if (t.kind == PointKind::kFiducial && t.x_px) {
      add(std::lround(*t.x_px) + 1, std::lround(*t.y_px));
      break;
    }
  std::mt19937 rng(28);
  while (bad->size() < 100) add(static_cast<long>(rng() % p.width_px), static_cast<long>(rng() % p.height_px));
  return values;
}

ReseauDetection Detect(const Image& image) {
  const DefinitionRegistry registry;
  ReseauDetectorOptions options;
  options.pixel_size_um = kPixelUm;
  return DetectReseau(image, registry.Grid("ikogon-b"), options);
}

TEST(NonFinitePixels, ReadAsMaskedAndCountedExactly) {
  testing::TempDir dir;
  std::set<std::pair<long, long>> bad;
  const Image image = Image::Open(WriteFloat(dir.file("masked.tif"), WithBadPixels(&bad)));
  ASSERT_EQ(bad.size(), 100u);
  const ImageWindow all = image.ReadWindow(image.Bounds());
  EXPECT_EQ(CountMaskedPixels(all.values_dn.data(), all.values_dn.size()), 100u);
  for (const auto& [x, y] : bad) EXPECT_TRUE(IsMaskedPixel(all.at(x, y))) << x << "," << y;
  // The overview counts them all (also below its last whole block row) and holds no NaN.
  const Overview overview = BuildOverview(image, 7);
  ASSERT_NE(image.info().height_px % 7, 0);  // there are rows below the last block
  EXPECT_EQ(overview.masked_px, 100);
  EXPECT_EQ(CountMaskedPixels(overview.values_dn.data(), overview.values_dn.size()), 0u);
}

TEST(NonFinitePixels, CostNoCrossAndMoveNoCentreBeyondItsSigma) {
  testing::TempDir dir;
  std::set<std::pair<long, long>> bad;
  const ReseauDetection clean = Detect(Image::Open(WriteFloat(dir.file("clean.tif"), PlateOfPixels().values)));
  const ReseauDetection masked = Detect(Image::Open(WriteFloat(dir.file("masked.tif"), WithBadPixels(&bad))));
  ASSERT_TRUE(clean.found) << clean.summary;
  ASSERT_TRUE(masked.found) << masked.summary;
  EXPECT_EQ(clean.masked_px, 0);
  EXPECT_EQ(masked.masked_px, 100);
  EXPECT_EQ(masked.orientation.Name(), clean.orientation.Name());
  EXPECT_FALSE(masked.orientation_ambiguous) << masked.orientation_evidence;
  EXPECT_EQ(masked.measured, clean.measured) << masked.summary;
  EXPECT_GE(masked.measured, 120) << masked.summary;

  int with_masked = 0;
  double sum_z2 = 0;
  for (size_t g = 0; g < masked.points.size(); ++g) {
    const DetectedPoint& m = masked.points[g];
    const DetectedPoint& c = clean.points[g];
    ASSERT_EQ(m.id, c.id);
    if (m.status != PointStatus::kMeasured || c.status != PointStatus::kMeasured) continue;
    if (masked.fits[g].pixels_masked > 0) {
      ++with_masked;
      EXPECT_NE(masked.fits[g].summary.find("masked left out"), std::string::npos) << masked.fits[g].summary;
    }
    EXPECT_LT(std::abs(m.position_px.x_px - c.position_px.x_px), c.sigma_x_px) << m.id;
    EXPECT_LT(std::abs(m.position_px.y_px - c.position_px.y_px), c.sigma_y_px) << m.id;
    const PixelPoint t = TruthOf(m.id, PointKind::kReseau);
    sum_z2 += std::pow((m.position_px.x_px - t.x_px) / m.sigma_x_px, 2) +
              std::pow((m.position_px.y_px - t.y_px) / m.sigma_y_px, 2);
  }
  EXPECT_GE(with_masked, 38);  // the 40 on arms, less any a cross dropped as an outlier anyway
  const double z_rms = std::sqrt(sum_z2 / (2.0 * masked.measured));
  EXPECT_GT(z_rms, 0.7);
  EXPECT_LT(z_rms, 1.5);
}

TEST(NonFinitePixels, AMostlyMaskedCrossIsMissingTheOthersMeasured) {
  testing::TempDir dir;
  std::vector<float> values = PlateOfPixels().values;
  const PixelPoint centre = TruthOf("X6Y6", PointKind::kReseau);
  // A 16 x 16 px hole over the cross (15 px arms tip to tip): most of its fit region.
  for (long y = std::lround(centre.y_px) - 8; y < std::lround(centre.y_px) + 8; ++y)
    for (long x = std::lround(centre.x_px) - 8; x < std::lround(centre.x_px) + 8; ++x)
      values[static_cast<size_t>(y * PlateOfPixels().width_px + x)] = std::numeric_limits<float>::quiet_NaN();
  const ReseauDetection d = Detect(Image::Open(WriteFloat(dir.file("hole.tif"), values)));
  ASSERT_TRUE(d.found) << d.summary;
  EXPECT_EQ(d.masked_px, 16 * 16);
  for (size_t g = 0; g < d.points.size(); ++g) {
    const DetectedPoint& p = d.points[g];
    if (p.id == "X6Y6") {
      EXPECT_EQ(p.status, PointStatus::kMissing);
      EXPECT_EQ(p.reason, "masked_pixels");
      EXPECT_TRUE(d.fits[g].too_many_masked);
      EXPECT_NE(d.fits[g].summary.find("masked"), std::string::npos) << d.fits[g].summary;
    }
  }
  EXPECT_GE(d.measured, 119) << d.summary;
  EXPECT_EQ(d.missing, 1) << d.summary;
}

TEST(NonFinitePixels, FiducialWithAMaskedPixelIsMeasured) {
  testing::TempDir dir;
  std::set<std::pair<long, long>> bad;
  const Image clean_image = Image::Open(WriteFloat(dir.file("clean.tif"), PlateOfPixels().values));
  const Image masked_image = Image::Open(WriteFloat(dir.file("masked.tif"), WithBadPixels(&bad)));
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("sn004-terrain");
  const FiducialSet* set = &registry.Fiducials(camera.fiducial_set);
  FiducialDetectorOptions options;
  options.pixel_size_um = kPixelUm;
  const ReseauDetection reseau = Detect(clean_image);
  ASSERT_TRUE(reseau.found);
  const FiducialDetection clean = DetectFiducialMarks(clean_image, camera, set, &reseau.plate_to_pixel, options);
  const FiducialDetection masked = DetectFiducialMarks(masked_image, camera, set, &reseau.plate_to_pixel, options);
  ASSERT_EQ(masked.points.size(), clean.points.size());
  EXPECT_EQ(masked.measured, clean.measured) << masked.summary;
  EXPECT_GE(masked.measured, 8) << masked.summary;
  int with_masked = 0;
  for (size_t k = 0; k < masked.points.size(); ++k) {
    if (masked.points[k].status != PointStatus::kMeasured) continue;
    with_masked += masked.fits[k].pixels_masked > 0;
    EXPECT_LT(std::abs(masked.points[k].position_px.x_px - clean.points[k].position_px.x_px),
              clean.points[k].sigma_x_px);
    EXPECT_LT(std::abs(masked.points[k].position_px.y_px - clean.points[k].position_px.y_px),
              clean.points[k].sigma_y_px);
  }
  EXPECT_EQ(with_masked, 1);
}

}  // namespace
}  // namespace platemeter
