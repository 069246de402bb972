// Fiducial detection on simulator plates: the SN-004 terrain fiducials (crosses)
// with a reseau-derived prior, the Hasselblad format corners without any prior,
// and marks that are not on the scan reported missing.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>

#include "platemeter/detect/fiducial_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::TempDir;

struct Rendered {
  sim::SimulatedPlate plate;
  std::string image_path;
};

Rendered RenderPlate(const std::string& toml, const TempDir& dir) {
  const DefinitionRegistry registry;
  const sim::SimulationSpec spec = sim::ParseSimulationSpec(toml, "test spec");
  Rendered r;
  r.plate = sim::BuildSimulatedPlate(spec, registry);
  r.image_path = sim::WriteSimulatedPlate(r.plate, dir.path().string()).image_path;
  return r;
}

const MeasuredPoint* Truth(const sim::SimulatedPlate& plate, const std::string& id, PointKind kind) {
  for (const MeasuredPoint& p : plate.truth)
    if (p.id == id && p.kind == kind) return &p;
  return nullptr;
}

// What a reseau detection hands over: the least-squares similarity of the
// crosses' plate positions onto their scan positions (here from the truth).
PlateToPixel ReseauSimilarity(const sim::SimulatedPlate& plate) {
  std::vector<std::array<double, 4>> pairs;
  for (const MeasuredPoint& p : plate.truth)
    if (p.kind == PointKind::kReseau && p.x_px && p.x_mm) pairs.push_back({*p.x_mm, *p.y_mm, *p.x_px, *p.y_px});
  // pixel = [[a, b], [b, -a]] plate + t: a similarity with the y flip of pixel rows.
  Eigen::MatrixXd m(2 * pairs.size(), 4);
  Eigen::VectorXd rhs(2 * pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    const auto& q = pairs[i];
    m.row(2 * i) << q[0], q[1], 1, 0;
    m.row(2 * i + 1) << -q[1], q[0], 0, 1;
    rhs(2 * i) = q[2];
    rhs(2 * i + 1) = q[3];
  }
  const Eigen::Vector4d p = m.colPivHouseholderQr().solve(rhs);
  PlateToPixel map;
  map.a[0] = p(0), map.a[1] = p(1), map.a[2] = p(1), map.a[3] = -p(0);
  map.t[0] = p(2), map.t[1] = p(3);
  return map;
}

const char* kTerrainSpec = R"(
name = "fid-terrain"
camera = "sn004-terrain"
seed = 9
[output]
pixel_size_um = 40.0
margin_mm = 2.0
bits = 16
[film]
affine_ppm = [45.0, 6.0, -4.0, -30.0]
[scanner]
rotation_deg = 0.25
offset_px = [3.3, -2.7]
[marks.reseau]
polarity = "dark"
contrast_dn = 14000.0
[marks.fiducials]
polarity = "bright"
contrast_dn = 16000.0
[background]
level_dn = 26000.0
terrain_amplitude_dn = 3000.0
terrain_scale_mm = 15.0
[noise]
blur_sigma_um = 12.0
sensor_sigma_dn = 150.0
grain_sigma_dn = 250.0
)";

TEST(FiducialDetector, TerrainFiducialsWithReseauPrior) {
  TempDir dir;
  const Rendered r = RenderPlate(kTerrainSpec, dir);
  const Image image = Image::Open(r.image_path);
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("sn004-terrain");
  FiducialSet set = registry.Fiducials(camera.fiducial_set);
  // Two marks that are not on this scan: one inside the format between the
  // reseau crosses (nothing drawn there), one beyond the scan's edge.
  set.marks.push_back({"E", 5.0, -25.0, set.marks[0].mark});
  set.marks.push_back({"F", 80.0, 0.0, set.marks[0].mark});
  const PlateToPixel prior = ReseauSimilarity(r.plate);
  FiducialDetectorOptions options;
  options.blur_sigma_px = 0.3;
  const FiducialDetection found = DetectFiducialMarks(image, camera, &set, &prior, options);
  ASSERT_EQ(found.points.size(), 10u);
  int measured = 0;
  for (size_t i = 0; i < 8; ++i) {
    const DetectedPoint& p = found.points[i];
    EXPECT_EQ(p.id, set.marks[i].id);
    EXPECT_EQ(p.kind, PointKind::kFiducial);
    ASSERT_EQ(p.status, PointStatus::kMeasured) << p.id << " " << p.reason << " " << found.fits[i].summary;
    ++measured;
    const MeasuredPoint* truth = Truth(r.plate, p.id, PointKind::kFiducial);
    ASSERT_NE(truth, nullptr);
    const double ex = p.position_px.x_px - *truth->x_px, ey = p.position_px.y_px - *truth->y_px;
    std::printf("%s: error (%+.4f, %+.4f) px, formal (%.4f, %.4f) px\n", p.id.c_str(), ex, ey, p.sigma_x_px, p.sigma_y_px);
    EXPECT_LT(std::abs(ex), 3.0 * p.sigma_x_px) << p.id;
    EXPECT_LT(std::abs(ey), 3.0 * p.sigma_y_px) << p.id;
  }
  EXPECT_EQ(measured, 8);
  EXPECT_EQ(found.points[8].id, "E");
  EXPECT_EQ(found.points[8].status, PointStatus::kMissing);
  EXPECT_EQ(found.points[8].reason, "not_found");
  EXPECT_EQ(found.points[9].status, PointStatus::kMissing);
  EXPECT_EQ(found.points[9].reason, "outside_scan");
  // A missing mark carries its prediction, never sigmas of a measurement.
  EXPECT_EQ(found.points[8].sigma_x_px, 0.0);
  EXPECT_EQ(found.measured, 8);
  EXPECT_EQ(found.missing, 2);
}

const char* kHasselbladSpec = R"(
name = "fid-hasselblad"
camera = "hasselblad-500"
seed = 21
[output]
pixel_size_um = 25.0
margin_mm = 1.5
bits = 8
[scanner]
rotation_deg = 0.6
offset_px = [7.2, -4.1]
[marks.fiducials]
polarity = "bright"
contrast_dn = 60.0
line_width_um = 100.0
size_um = 3000.0
[background]
level_dn = 120.0
terrain_amplitude_dn = 15.0
terrain_scale_mm = 8.0
[noise]
blur_sigma_um = 15.0
sensor_sigma_dn = 1.5
grain_sigma_dn = 2.0
)";

TEST(FiducialDetector, FormatCornersWithoutPrior) {
  TempDir dir;
  const Rendered r = RenderPlate(kHasselbladSpec, dir);
  const Image image = Image::Open(r.image_path);
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("hasselblad-500");
  FiducialDetectorOptions options;
  options.pixel_size_um = 25.0;
  options.blur_sigma_px = 0.6;
  const FiducialDetection found = DetectFiducialMarks(image, camera, nullptr, nullptr, options);
  std::printf("%s\n%s\n", found.summary.c_str(), found.orientation_evidence.c_str());
  ASSERT_TRUE(found.found);
  // A square format's corners look the same in all 8 orientations: the result must say so.
  EXPECT_TRUE(found.orientation_ambiguous);
  // Ambiguous layouts take the first orientation (0), the one this scan has.
  EXPECT_EQ(found.orientation.Name(), "0");
  ASSERT_EQ(found.points.size(), 4u);
  const char* ids[4] = {"UL", "UR", "LL", "LR"};
  for (size_t i = 0; i < 4; ++i) {
    const DetectedPoint& p = found.points[i];
    EXPECT_EQ(p.id, ids[i]);
    ASSERT_EQ(p.status, PointStatus::kMeasured) << p.id << " " << p.reason << " " << found.fits[i].summary;
    const MeasuredPoint* truth = Truth(r.plate, p.id, PointKind::kFiducial);
    ASSERT_NE(truth, nullptr);
    const double ex = p.position_px.x_px - *truth->x_px, ey = p.position_px.y_px - *truth->y_px;
    std::printf("%s: error (%+.4f, %+.4f) px, formal (%.4f, %.4f) px\n", p.id.c_str(), ex, ey, p.sigma_x_px, p.sigma_y_px);
    EXPECT_LT(std::abs(ex), 3.0 * p.sigma_x_px) << p.id;
    EXPECT_LT(std::abs(ey), 3.0 * p.sigma_y_px) << p.id;
  }
}

TEST(FiducialDetector, OptionsAndCameraChecked) {
  FiducialDetectorOptions options;
  std::string why;
  EXPECT_TRUE(options.Check(&why));
  options.corner_arm_length_um = 50.0;
  EXPECT_FALSE(options.Check(&why));
  EXPECT_NE(why.find("corner_arm_length_um"), std::string::npos);
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

// The SN-004 set without a prior: the marks' layout alone (nearly symmetric
// under 180 deg, broken by ~0.1 mm) decides the orientation of a scan turned by 180.
TEST(FiducialDetector, TerrainFiducialsWithoutPrior) {
  testing::TempDir dir;
  std::string spec = kTerrainSpec;
  spec.replace(spec.find("rotation_deg = 0.25"), 19, "rotation_deg = 0.25\norientation_deg = 180");
  const Rendered r = RenderPlate(spec, dir);
  const Image image = Image::Open(r.image_path);
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("sn004-terrain");
  const FiducialSet& set = registry.Fiducials(camera.fiducial_set);
  FiducialDetectorOptions options;
  options.pixel_size_um = 40.0;
  options.blur_sigma_px = 0.3;
  const FiducialDetection found = DetectFiducialMarks(image, camera, &set, nullptr, options);
  std::printf("%s\n%s\n", found.summary.c_str(), found.orientation_evidence.c_str());
  ASSERT_TRUE(found.found);
  EXPECT_FALSE(found.orientation_ambiguous);
  EXPECT_EQ(found.orientation.Name(), "180");
  for (size_t i = 0; i < found.points.size(); ++i) {
    const DetectedPoint& p = found.points[i];
    EXPECT_EQ(p.id, set.marks[i].id);
    ASSERT_EQ(p.status, PointStatus::kMeasured) << p.id << " " << p.reason;
    const MeasuredPoint* truth = Truth(r.plate, p.id, PointKind::kFiducial);
    ASSERT_NE(truth, nullptr);
    EXPECT_LT(std::abs(p.position_px.x_px - *truth->x_px), 3.0 * p.sigma_x_px) << p.id;
    EXPECT_LT(std::abs(p.position_px.y_px - *truth->y_px), 3.0 * p.sigma_y_px) << p.id;
  }
}

}  // namespace
}  // namespace platemeter
