// The simulator's spec: the bundled specs read and build; every kind of
// mistake is an Error naming the file, the line where there is one, and the key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace platemeter::sim {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& text) {
  try {
    ParseSimulationSpec(text, "plate.toml");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string BuildErrorOf(const std::string& text, bool full_size = false) {
  try {
    SimulateOptions options;
    options.full_size = full_size;
    BuildSimulatedPlate(ParseSimulationSpec(text, "plate.toml"), DefinitionRegistry(), options);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

const char* kMinimal = "name = \"tiny\"\ncamera = \"orbigon\"\n";

TEST(SpecParse, MinimalSpecTakesTheDocumentedDefaults) {
  const SimulationSpec spec = ParseSimulationSpec(kMinimal, "plate.toml");
  EXPECT_EQ(spec.name, "tiny");
  EXPECT_EQ(spec.camera, "orbigon");
  EXPECT_EQ(spec.output.pixel_size_um, 25.0);
  EXPECT_EQ(spec.output.bits, 16);
  EXPECT_EQ(spec.emulsion.depth_um, 0.0);
  EXPECT_FALSE(spec.thermal.temperature_degC.has_value());
}

TEST(SpecParse, EveryBundledSpecReadsAndBuilds) {
  const std::filesystem::path folder = std::filesystem::path(PLATEMETER_SOURCE_DIR) / "samples" / "specs";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    ++count;
    const SimulationSpec spec = ReadSimulationSpec(entry.path().string());
    EXPECT_EQ(spec.name + ".toml", entry.path().filename().string());
    ASSERT_TRUE(spec.output.full_size_pixel_size_um.has_value());
    const SimulatedPlate plate = BuildSimulatedPlate(spec, DefinitionRegistry());
    // CI-sized: a few Mpx at most.
    EXPECT_LT(double(plate.scene.width_px) * plate.scene.height_px, 1.2e7);
    // Full size: about 5 um pixels, e.g. the 114 mm plates become more than 22800 px wide.
    SimulateOptions full;
    full.full_size = true;
    const SimulatedPlate big = BuildSimulatedPlate(spec, DefinitionRegistry(), full);
    EXPECT_NEAR(double(big.scene.width_px) / plate.scene.width_px,
                spec.output.pixel_size_um / *spec.output.full_size_pixel_size_um, 0.01);
  }
  EXPECT_EQ(count, 4);
}

TEST(SpecParse, SizeIsDerivedFromFormatGridAndMargin) {
  // Orbigon: 114 mm format (the grid, +-50.3 mm, lies inside), 3 mm margins, 40 um pixels:
  // (114 + 6) / 0.040 = 3000 pixel steps, so 3001 pixels; no rotation.
  const SimulatedPlate plate = BuildSimulatedPlate(
      ParseSimulationSpec("name = \"t\"\ncamera = \"orbigon\"\n[output]\npixel_size_um = 40\nmargin_mm = 3\n", "t.toml"),
      DefinitionRegistry());
  EXPECT_EQ(plate.scene.width_px, 3001);
  EXPECT_EQ(plate.scene.height_px, 3001);
  // The plate origin (centre cross) at the image centre.
  EXPECT_NEAR(plate.chain.scanner.origin_px.x_px, 1500.0, 1e-9);
  EXPECT_NEAR(plate.chain.scanner.origin_px.y_px, 1500.0, 1e-9);
}

TEST(SpecParse, MistakesNameTheFileLineAndKey) {
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[scanner]\nrotation = 0.3\n"),
              HasSubstr("plate.toml: line 4: scanner: unknown key 'rotation'"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[scanner]\norientation_deg = 45\n"),
              HasSubstr("line 4: scanner: key 'orientation_deg' must be 0, 90, 180 or 270"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[output]\nbits = 12\n"),
              HasSubstr("line 4: output: key 'bits' must be 8 or 16"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[emulsion]\nrefractive_index = 0.5\n"),
              HasSubstr("line 4: emulsion: key 'refractive_index' = 0.5 must lie in 1..3"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[film]\naffine_ppm = [1, 2]\n"),
              HasSubstr("film: key 'affine_ppm' must be an array of 4 numbers"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[marks.reseau]\npolarity = \"grey\"\n"),
              HasSubstr("marks.reseau: key 'polarity' must be \"dark\" or \"bright\""));
  EXPECT_THAT(ErrorOf("name = \"t\"\n"), HasSubstr("plate.toml: line 1: missing required key 'camera'"));
  EXPECT_THAT(ErrorOf("name = \"../escape\"\ncamera = \"orbigon\"\n"), HasSubstr("must be a plain file name"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[noise\n"), HasSubstr("plate.toml: line 3: "));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\ncolour = 1\n"), HasSubstr("line 3: unknown key 'colour'"));
  EXPECT_THAT(ErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[[stars.star]]\nid = \"a\"\nx_mm = 1\ny_mm = 2\n"),
              HasSubstr("star 'a' needs a magnitude"));
}

TEST(SpecParse, BuildErrorsNameTheSpecFile) {
  EXPECT_THAT(BuildErrorOf("name = \"t\"\ncamera = \"leica\"\n"),
              HasSubstr("plate.toml: unknown camera 'leica' (known: "));
  EXPECT_THAT(BuildErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[defects]\nmissing_crosses = [\"X12Y1\"]\n"),
              HasSubstr("plate.toml: defects.missing_crosses: grid 'orbigon-reseau' has no cross 'X12Y1'"));
  EXPECT_THAT(BuildErrorOf("name = \"t\"\ncamera = \"orbigon\"\n", true),
              HasSubstr("--full-size needs full_size_pixel_size_um"));
  EXPECT_THAT(BuildErrorOf("name = \"t\"\ncamera = \"orbigon\"\n[output]\nbits = 8\n"),
              HasSubstr("background.level_dn = 30000 DN exceeds the 8-bit full scale 255"));
  EXPECT_THAT(BuildErrorOf("name = \"t\"\ncamera = \"hasselblad-500\"\n[defects]\ndamaged_crosses = [\"X1Y1\"]\n"),
              HasSubstr("camera 'hasselblad-500' has no reseau"));
}

}  // namespace
}  // namespace platemeter::sim
