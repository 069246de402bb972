// platemeter detect end to end: the files it writes, and its refusals (an
// undecidable orientation, an unknown camera or orientation, a missing scan) as one line,
// exit code 1 and nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

std::string RenderOrbigon(const testing::TempDir& dir) {
  const std::string spec =
      "name = \"orbigon\"\ncamera = \"orbigon\"\nseed = 2\n[output]\npixel_size_um = 30.0\nmargin_mm = 1.0\n"
      "[noise]\nblur_sigma_um = 8.0\nsensor_sigma_dn = 100.0\n";
  const DefinitionRegistry registry;
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "spec"), registry);
  return sim::WriteSimulatedPlate(plate, dir.path().string()).image_path;
}

TEST(CliDetect, WritesMeasurementsAndSummaryWhenTheOrientationIsGiven) {
  testing::TempDir dir;
  const std::string scan = RenderOrbigon(dir);
  const std::string out = dir.file("out");
  const auto result = RunPlatemeter("detect '" + scan + "' --camera orbigon --orientation 0 -o '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const MeasurementFile file = ReadMeasurementFile(out + "/orbigon.measurements.csv");
  EXPECT_EQ(file.points.size(), 121u);
  EXPECT_EQ(file.header.camera, "orbigon");
  EXPECT_EQ(file.header.scan_sha256.size(), 64u);
  int measured = 0;
  for (const MeasuredPoint& p : file.points) measured += p.status == PointStatus::kMeasured;
  EXPECT_GE(measured, 119);
  EXPECT_TRUE(std::filesystem::exists(out + "/orbigon.detect.json"));
}

TEST(CliDetect, RefusesToGuessAnOrientation) {
  testing::TempDir dir;
  const std::string scan = RenderOrbigon(dir);
  const std::string out = dir.file("out");
  const auto result = RunPlatemeter("detect '" + scan + "' --camera orbigon -o '" + out + "'");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("give --orientation"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(std::filesystem::exists(out + "/orbigon.measurements.csv"));
}

TEST(CliDetect, StarsAreMeasuredAndCrossesAreNotStars) {
  testing::TempDir dir;
  const std::string spec =
      "name = \"stellar\"\ncamera = \"sn004-stellar\"\nseed = 3\n[output]\npixel_size_um = 10.0\n"
      "[marks.reseau]\npolarity = \"bright\"\ncontrast_dn = 12000.0\n"
      "[background]\nlevel_dn = 40000.0\n"
      "[stars]\ncount = 60\nmagnitude_min = 4.0\nmagnitude_max = 7.0\nfwhm_um = 18.0\npolarity = \"dark\"\n"
      "[noise]\nblur_sigma_um = 4.0\nsensor_sigma_dn = 150.0\n";
  const DefinitionRegistry registry;
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "spec"), registry);
  const std::vector<MeasuredPoint> truth = plate.truth;
  const std::string scan = sim::WriteSimulatedPlate(plate, dir.path().string()).image_path;
  const std::string out = dir.file("out");
  const auto result = RunPlatemeter("detect '" + scan + "' --camera sn004-stellar --stars --star-fwhm-px 1.8 -o '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const MeasurementFile file = ReadMeasurementFile(out + "/stellar.measurements.csv");
  int truth_stars = 0, found = 0, stars = 0, false_stars = 0;
  for (const MeasuredPoint& p : file.points) {
    if (p.kind != PointKind::kStar || p.status != PointStatus::kMeasured) continue;
    ++stars;
    bool matched = false;
    for (const MeasuredPoint& t : truth)
      if (t.kind == PointKind::kStar && t.x_px && std::hypot(*p.x_px - *t.x_px, *p.y_px - *t.y_px) < 1.0) matched = true;
    false_stars += !matched;
  }
  for (const MeasuredPoint& t : truth) {
    if (t.kind != PointKind::kStar || !t.x_px) continue;
    ++truth_stars;
    for (const MeasuredPoint& p : file.points)
      if (p.kind == PointKind::kStar && p.status == PointStatus::kMeasured &&
          std::hypot(*p.x_px - *t.x_px, *p.y_px - *t.y_px) < 1.0) {
        ++found;
        break;
      }
  }
  EXPECT_GT(truth_stars, 40);
  EXPECT_GE(found, 0.9 * truth_stars);
  EXPECT_EQ(false_stars, 0) << stars << " stars reported";  // the 25 reseau crosses are not stars
}

TEST(CliDetect, BadInputIsOneLineAndWritesNothing) {
  testing::TempDir dir;
  const std::string scan = RenderOrbigon(dir);
  const std::string out = dir.file("out");
  const auto unknown_camera = RunPlatemeter("detect '" + scan + "' --camera no-such-camera -o '" + out + "'");
  EXPECT_EQ(unknown_camera.exit_code, 1);
  EXPECT_NE(unknown_camera.err.find("no-such-camera"), std::string::npos) << unknown_camera.err;
  const auto bad_orientation = RunPlatemeter("detect '" + scan + "' --camera orbigon --orientation 45 -o '" + out + "'");
  EXPECT_EQ(bad_orientation.exit_code, 1);
  EXPECT_NE(bad_orientation.err.find("--orientation"), std::string::npos) << bad_orientation.err;
  const auto missing = RunPlatemeter("detect '" + dir.file("absent.tif") + "' --camera orbigon -o '" + out + "'");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no such file"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace platemeter
