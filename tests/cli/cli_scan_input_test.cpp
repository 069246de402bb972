// Scan input end to end (issue #28): `measure` refuses a truncated JPEG with one
// line and exit code 1 (it used to measure it, part of it blank); a float scan
// with 100 NaN, infinite, 3e38 and 1e20 pixels is measured in full, the masked pixels
// counted on the console, in <scan>.detect.json and in the measurement file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

// The SN-004 terrain sample at its CI size (40 um), written as `extension` after `edit` changes the pixels
// (DN of the 16-bit rendering; a float scan gets them scaled to [0, 1]).
template <typename Edit>
std::string RenderTerrain(const testing::TempDir& dir, const std::string& name, SampleType type, const Edit& edit) {
  const DefinitionRegistry registry;
  const std::string spec_path = std::string(PLATEMETER_SOURCE_DIR) + "/samples/specs/sn004-terrain.toml";
  const sim::SimulatedPlate plate =
      sim::BuildSimulatedPlate(sim::ParseSimulationSpec(testing::ReadTextFile(spec_path), spec_path), registry);
  const Image rendered = Image::Open(sim::WriteSimulatedPlate(plate, dir.file("render")).image_path);
  std::vector<float> values = rendered.ReadWindow(rendered.Bounds()).values_dn;
  const double scale = type == SampleType::kFloat32 ? 1.0 / 65535.0 : type == SampleType::kUint8 ? 255.0 / 65535.0 : 1.0;
  for (float& v : values) v = static_cast<float>(v * scale);
  edit(&values, rendered.info().width_px);
  ImageWriterOptions options;
  options.width_px = rendered.info().width_px;
  options.height_px = rendered.info().height_px;
  options.sample_type = type;
  options.tile_size_px = name.ends_with(".tif") ? 256 : 0;
  options.pixel_size_um = plate.pixel_size_um;
  WriteImage(dir.file(name), options, values.data());
  return dir.file(name);
}

TEST(CliScanInput, MeasureRefusesATruncatedJpeg) {
  testing::TempDir dir;
  const std::string whole = RenderTerrain(dir, "terrain.jpg", SampleType::kUint8, [](std::vector<float>*, long) {});
  const std::string cut = dir.file("cut.jpg");
  std::filesystem::copy_file(whole, cut);
  std::filesystem::resize_file(cut, std::filesystem::file_size(whole) * 6 / 10);
  const auto result = RunPlatemeter("measure '" + cut + "' --camera sn004-terrain --pixel-size-um 40 -o '" +
                                    dir.file("out") + "'");
  EXPECT_EQ(result.exit_code, 1) << result.out;
  EXPECT_EQ(result.err.rfind("platemeter: error: " + cut + ": ", 0), 0u) << result.err;
  EXPECT_NE(result.err.find("end-of-image marker (FF D9)"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("the file is truncated"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out") + "/cut.measurements.csv"));
}

TEST(CliScanInput, FloatScanWithNonFinitePixelsIsMeasuredAndTheyAreCounted) {
  testing::TempDir dir;
  const std::string scan = RenderTerrain(dir, "terrain.tif", SampleType::kFloat32, [](std::vector<float>* v, long) {
    const float kinds[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), 3e38f, 1e20f};
    std::mt19937 rng(100);
    std::set<size_t> at;
    while (at.size() < 100) at.insert(rng() % v->size());
    int k = 0;
    for (size_t i : at) (*v)[i] = kinds[k++ % 4];
  });
  const auto detect = RunPlatemeter("detect '" + scan + "' --camera sn004-terrain -o '" + dir.file("d") + "'");
  ASSERT_EQ(detect.exit_code, 0) << detect.err;
  EXPECT_NE(detect.out.find("scan: 100 pixels masked"), std::string::npos) << detect.out;
  EXPECT_NE(detect.out.find("reseau: 121 of 121 crosses measured"), std::string::npos) << detect.out;
  const nlohmann::json summary = nlohmann::json::parse(testing::ReadTextFile(dir.file("d") + "/terrain.detect.json"));
  EXPECT_EQ(summary.at("masked_pixels").get<long>(), 100);

  const auto measure = RunPlatemeter("measure '" + scan + "' --camera sn004-terrain -o '" + dir.file("m") + "'");
  ASSERT_EQ(measure.exit_code, 0) << measure.err;
  EXPECT_NE(measure.out.find("scan: 100 pixels masked"), std::string::npos) << measure.out;
  EXPECT_NE(measure.out.find("fiducials: 8 of 8 fiducials measured"), std::string::npos) << measure.out;
  EXPECT_NE(testing::ReadTextFile(dir.file("m") + "/terrain.measurements.csv").find("# masked_pixels: 100\n"),
            std::string::npos);
  const nlohmann::json report = nlohmann::json::parse(testing::ReadTextFile(dir.file("m") + "/terrain.measure.json"));
  EXPECT_EQ(report.at("masked_pixels").get<long>(), 100);
}

}  // namespace
}  // namespace platemeter
