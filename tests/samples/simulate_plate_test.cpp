// The simulated plate: marks and truth where the chain puts them, star
// brightness from magnitudes, and `platemeter simulate` end to end (three
// files, the truth file read back with the measurement-file reader).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/core/sha256.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter::sim {
namespace {

using ::testing::HasSubstr;

SimulatedPlate Build(const std::string& text) {
  return BuildSimulatedPlate(ParseSimulationSpec(text, "t.toml"), DefinitionRegistry());
}

TEST(SimulatePlate, CrossesLandWhereAPlainScannerPutsThem) {
  // Only the scanner: 100 um pixels, orientation 0, no margin surprises. The
  // centre cross X6Y6 (0, 0) sits at the image centre; X7Y6 (+10 mm) 100 px to
  // the right; X6Y7 (+10 mm up) 100 px higher (smaller row).
  const SimulatedPlate plate =
      Build("name = \"t\"\ncamera = \"orbigon\"\n[output]\npixel_size_um = 100\nmargin_mm = 3\n");
  ASSERT_EQ(plate.scene.width_px, 1201);
  std::map<std::string, PixelPoint> at;
  for (const SceneMark& m : plate.scene.marks) at[m.id] = m.centre_px;
  ASSERT_EQ(at.size(), 121u);
  EXPECT_NEAR(at["X6Y6"].x_px, 600.0, 1e-9);
  EXPECT_NEAR(at["X6Y6"].y_px, 600.0, 1e-9);
  EXPECT_NEAR(at["X7Y6"].x_px, 700.0, 1e-9);
  EXPECT_NEAR(at["X6Y7"].y_px, 500.0, 1e-9);
  EXPECT_NEAR(at["X1Y1"].x_px, 100.0, 1e-9);
  EXPECT_NEAR(at["X1Y1"].y_px, 1100.0, 1e-9);
  // The mark frame maps 1 um right to 0.01 px right, 1 um up to 0.01 px up.
  const SceneMark& centre = plate.scene.marks[60];
  EXPECT_NEAR(centre.px_from_um[0], 0.01, 1e-15);
  EXPECT_NEAR(centre.px_from_um[3], -0.01, 1e-15);
  EXPECT_NEAR(centre.px_from_um[1], 0.0, 1e-15);
}

TEST(SimulatePlate, TruthAndMarksFollowTheFullChain) {
  const SimulatedPlate plate = Build(R"(
name = "t"
camera = "orbigon"
[output]
pixel_size_um = 50
[thermal]
temperature_degC = 25
[emulsion]
depth_um = 21
[film]
affine_ppm = [100, 20, -10, 50]
[[film.wave]]
amplitude_um = [3, -2]
wavelength_mm = 40
[scanner]
rotation_deg = 2
orientation_deg = 90
mirrored = true
non_orthogonality_arcsec = 30
)");
  ASSERT_EQ(plate.truth.size(), plate.truth_mark.size());
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& t = plate.truth[i];
    const SceneMark& m = plate.scene.marks[static_cast<size_t>(plate.truth_mark[i])];
    EXPECT_EQ(t.id, m.id);
    EXPECT_EQ(*t.x_px, m.centre_px.x_px);
    // The true plate position is what the inverse chain recovers from the true pixel.
    const PlatePoint back = plate.chain.PlateFromPixel({*t.x_px, *t.y_px});
    EXPECT_NEAR(back.x_mm, *t.x_mm, 1e-9);
    EXPECT_NEAR(back.y_mm, *t.y_mm, 1e-9);
    // The mark's local map is the chain's derivative (finite differences over 1 um).
    const double h_mm = 1e-3;
    const PixelPoint right = plate.chain.PixelFromPlate({*t.x_mm + h_mm, *t.y_mm});
    const PixelPoint left = plate.chain.PixelFromPlate({*t.x_mm - h_mm, *t.y_mm});
    EXPECT_NEAR(m.px_from_um[0], (right.x_px - left.x_px) / 2.0, 1e-9);
    EXPECT_NEAR(m.px_from_um[2], (right.y_px - left.y_px) / 2.0, 1e-9);
  }
  // Thermal at 25 degC vs the grid's 20 degC, expansion 8.1e-6 (the camera's): recorded in the chain.
  EXPECT_DOUBLE_EQ(plate.chain.thermal.calibration_temperature_degC, 20.0);
  EXPECT_NEAR(plate.chain.thermal.Scale(), 1.0 + 5 * 8.1e-6, 1e-15);
  // The emulsion principal distance is the calibrated one (80.17103 mm, seed 001 Table 3).
  EXPECT_NEAR(plate.chain.emulsion.principal_distance_mm, 80.17103, 1e-9);
}

TEST(SimulatePlate, StarBrightnessFollowsMagnitude) {
  // 10 um pixels, FWHM 30 um: sigma = 30 / 2.35482 / 10 px; a reference star (mag 6) has a
  // peak of 8000 DN, so flux = 8000 * 2 pi sigma^2; 2.5 magnitudes fainter is 10 times less.
  const SimulatedPlate plate = Build(R"(
name = "t"
camera = "orbigon"
[output]
pixel_size_um = 10
[stars]
reference_magnitude = 6.0
reference_peak_dn = 8000
fwhm_um = 30
polarity = "bright"
[[stars.star]]
id = "a"
x_mm = 12.5
y_mm = -30.25
magnitude = 6.0
[[stars.star]]
id = "b"
x_mm = -20
y_mm = 5
magnitude = 8.5
)");
  const double sigma_px = 30.0 / (2 * std::sqrt(2 * std::log(2.0))) / 10.0;
  std::map<std::string, const SceneMark*> star;
  for (const SceneMark& m : plate.scene.marks) {
    if (m.kind == MarkKind::kStar) star[m.id] = &m;
  }
  ASSERT_EQ(star.size(), 2u);
  EXPECT_NEAR(star["a"]->amplitude_dn, 8000 * 2 * std::numbers::pi * sigma_px * sigma_px, 1e-6);
  EXPECT_NEAR(star["b"]->amplitude_dn, star["a"]->amplitude_dn / 10.0, 1e-6);
  EXPECT_NEAR(star["a"]->centre_px.x_px - plate.chain.scanner.origin_px.x_px, 1250.0, 1e-9);
  EXPECT_NEAR(star["a"]->centre_px.y_px - plate.chain.scanner.origin_px.y_px, 3025.0, 1e-9);
}

TEST(SimulatePlate, SeedChangesRandomContentOnly) {
  const std::string text = "name = \"t\"\ncamera = \"orbigon\"\n[stars]\ncount = 5\n";
  const SimulationSpec spec = ParseSimulationSpec(text, "t.toml");
  SimulateOptions a, b;
  a.seed = 1;
  b.seed = 2;
  const SimulatedPlate p1 = BuildSimulatedPlate(spec, DefinitionRegistry(), a);
  const SimulatedPlate p1_again = BuildSimulatedPlate(spec, DefinitionRegistry(), a);
  const SimulatedPlate p2 = BuildSimulatedPlate(spec, DefinitionRegistry(), b);
  ASSERT_EQ(p1.scene.marks.size(), 126u);
  EXPECT_EQ(p1.scene.marks[125].centre_px.x_px, p1_again.scene.marks[125].centre_px.x_px);
  EXPECT_NE(p1.scene.marks[125].centre_px.x_px, p2.scene.marks[125].centre_px.x_px);
  EXPECT_EQ(p1.scene.marks[0].centre_px.x_px, p2.scene.marks[0].centre_px.x_px);  // crosses stay
}

TEST(SimulatePlate, RenderedMarksAreCentredOnTheirTruth) {
  // Noise-free, unquantized render with a rotated, mirrored, non-orthogonal scanner: the
  // intensity centroid of each (point-symmetric) cross and star around its truth position
  // is that position. Catches any disagreement between the chain and the renderer's frames.
  const SimulatedPlate plate = Build(R"(
name = "t"
camera = "orbigon"
[output]
pixel_size_um = 200
[scanner]
orientation_deg = 90
mirrored = true
rotation_deg = 7
non_orthogonality_arcsec = 600
[marks.reseau]
line_width_um = 300
size_um = 1600
contrast_dn = 10000
[stars]
fwhm_um = 500
reference_peak_dn = 10000
polarity = "bright"
[[stars.star]]
id = "s"
x_mm = 23.37
y_mm = -14.81
magnitude = 6
[noise]
blur_sigma_um = 60
quantize = false
)");
  const SceneRenderer renderer(plate.scene);
  const long width = plate.scene.width_px;
  std::vector<float> band(static_cast<size_t>(width) * 21);
  int checked = 0;
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& t = plate.truth[i];
    if (t.id != "X6Y6" && t.id != "X2Y9" && t.id != "X10Y3" && t.id != "s") continue;
    const long col = PixelIndexOf(*t.x_px), row = PixelIndexOf(*t.y_px);
    renderer.RenderBand(row - 10, 21, band.data());
    double sum = 0, sx = 0, sy = 0;
    for (long r = 0; r < 21; ++r) {
      for (long c = col - 10; c <= col + 10; ++c) {
        const double v = std::abs(band[static_cast<size_t>(r * width + c)] - 30000.0);
        sum += v;
        sx += v * c;
        sy += v * (row - 10 + r);
      }
    }
    EXPECT_NEAR(sx / sum, *t.x_px, 0.02) << t.id;
    EXPECT_NEAR(sy / sum, *t.y_px, 0.02) << t.id;
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

std::string ReadTextOfPlate(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SimulateCommand, WritesScanTruthAndChain) {
  testing::TempDir dir;
  const std::string spec = dir.file("tiny.toml");
  std::ofstream(spec) << R"(
name = "tiny"
camera = "orbigon"
seed = 3
[output]
pixel_size_um = 200
full_size_pixel_size_um = 100
bits = 16
tile_size_px = 64
[thermal]
temperature_degC = 22
[emulsion]
depth_um = 21
[scanner]
orientation_deg = 270
rotation_deg = 0.5
[marks.reseau]
polarity = "dark"
contrast_dn = 15000
line_width_um = 300
size_um = 2000
[stars]
count = 4
[noise]
sensor_sigma_dn = 20
[defects]
missing_crosses = ["X2Y3"]
)";
  const std::string out = dir.file("out");
  const testing::CommandResult run = testing::RunPlatemeter("simulate '" + spec + "' -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("scan: " + out + "/tiny.tif"));
  EXPECT_THAT(run.out, HasSubstr("truth: " + out + "/tiny.truth.csv"));
  EXPECT_THAT(run.out, HasSubstr("chain: " + out + "/tiny.chain.json"));

  // The truth file: every cross of the 11 x 11 grid once, with its id and position.
  const MeasurementFile truth = ReadMeasurementFile(out + "/tiny.truth.csv");
  EXPECT_TRUE(truth.truth_columns);
  EXPECT_EQ(truth.header.camera, "orbigon");
  EXPECT_EQ(truth.header.pixel_size_um, 200.0);
  EXPECT_EQ(truth.header.scan_file, "tiny.tif");
  EXPECT_EQ(truth.header.scan_sha256, Sha256HexOfFile(out + "/tiny.tif"));
  std::map<std::string, int> seen;
  int stars = 0;
  for (const MeasuredPoint& p : truth.points) {
    EXPECT_EQ(p.status, PointStatus::kTruth);
    if (p.kind == PointKind::kStar) ++stars;
    if (p.kind != PointKind::kReseau) continue;
    ++seen[p.id];
    int i = 0, j = 0;
    ASSERT_EQ(std::sscanf(p.id.c_str(), "X%dY%d", &i, &j), 2) << p.id;
    EXPECT_DOUBLE_EQ(*p.x_mm, 10.0 * (i - 6));  // the nominal Orbigon lattice
    EXPECT_DOUBLE_EQ(*p.y_mm, 10.0 * (j - 6));
    if (p.id == "X2Y3") {
      EXPECT_EQ(p.flags, std::vector<std::string>{"absent"});
      EXPECT_FALSE(p.crb_x_px.has_value());
    } else {
      ASSERT_TRUE(p.crb_x_px.has_value()) << p.id;
      EXPECT_GT(*p.crb_x_px, 0.0);
      EXPECT_LT(*p.crb_x_px, 0.5);
    }
  }
  EXPECT_EQ(seen.size(), 121u);
  for (const auto& [id, n] : seen) EXPECT_EQ(n, 1) << id;
  EXPECT_EQ(stars, 4);

  // The chain file: the parameters used, and it reproduces the truth pixels.
  const auto chain_json = nlohmann::json::parse(ReadTextOfPlate(out + "/tiny.chain.json"));
  EXPECT_EQ(chain_json["chain"]["scanner"]["orientation_deg"], 270);
  EXPECT_EQ(chain_json["chain"]["emulsion_depth"]["depth_um"], 21.0);
  const GeometryChain chain = GeometryChain::FromJson(chain_json["chain"].dump(), "tiny.chain.json");
  for (const MeasuredPoint& p : truth.points) {
    const PixelPoint q = chain.PixelFromPlate({*p.x_mm, *p.y_mm});
    EXPECT_NEAR(q.x_px, *p.x_px, 1e-9);
    EXPECT_NEAR(q.y_px, *p.y_px, 1e-9);
  }

  // The scan: the size in the chain file, 16-bit, dark crosses where the truth says.
  const Image scan = Image::Open(out + "/tiny.tif");
  EXPECT_EQ(scan.info().width_px, chain_json["image"]["width_px"].get<long>());
  EXPECT_EQ(scan.info().sample_type, SampleType::kUint16);
  for (const MeasuredPoint& p : truth.points) {
    if (p.kind != PointKind::kReseau || p.id == "X2Y3") continue;
    const long col = PixelIndexOf(*p.x_px), row = PixelIndexOf(*p.y_px);
    const ImageWindow w = scan.ReadWindow({col - 1, row - 1, 3, 3});
    EXPECT_LT(w.at(col, row), 30000 - 4000) << p.id;  // background 30000, cross -15000 (blurred by pixels)
  }
  // Where the missing cross would be, only background.
  for (const MeasuredPoint& p : truth.points) {
    if (p.id != "X2Y3") continue;
    const long col = PixelIndexOf(*p.x_px), row = PixelIndexOf(*p.y_px);
    EXPECT_NEAR(scan.ReadWindow({col, row, 1, 1}).values_dn[0], 30000, 150);
  }
  // Nothing else left in the folder (no temporaries).
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(out)) ++files;
  EXPECT_EQ(files, 3);
}

TEST(SimulateCommand, FullSizeAndSeedSwitches) {
  testing::TempDir dir;
  const std::string spec = dir.file("tiny.toml");
  std::ofstream(spec) << "name = \"tiny\"\ncamera = \"sn004-stellar\"\n[output]\npixel_size_um = 100\n"
                         "full_size_pixel_size_um = 50\nmargin_mm = 1\n";
  const testing::CommandResult run =
      testing::RunPlatemeter("simulate '" + spec + "' -o '" + dir.file("out") + "' --full-size --seed 9");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto chain_json = nlohmann::json::parse(ReadTextOfPlate(dir.file("out") + "/tiny.chain.json"));
  EXPECT_EQ(chain_json["image"]["pixel_size_um"], 50.0);
  EXPECT_EQ(chain_json["seed"], 9);
  EXPECT_EQ(chain_json["full_size"], true);
  // 24 mm format + 2 x 1 mm margin at 50 um: 520 steps, 521 px.
  EXPECT_EQ(chain_json["image"]["width_px"], 521);
}

TEST(SimulateCommand, BadSpecsFailOnOneLineAndWriteNothing) {
  testing::TempDir dir;
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {"name = \"bad\"\ncamera = \"leica\"\n", "unknown camera 'leica'"},
      {"name = \"bad\"\ncamera = \"orbigon\"\n[scanner]\norientation_deg = 33\n", "line 4: scanner: key 'orientation_deg'"},
      {"name = \"bad\"\ncamera = \"orbigon\n", "line 2"},
  };
  for (const Case& c : cases) {
    const std::string spec = dir.file("bad.toml");
    std::ofstream(spec) << c.text;
    const std::string out = dir.file("out");
    const testing::CommandResult run = testing::RunPlatemeter("simulate '" + spec + "' -o '" + out + "'");
    EXPECT_NE(run.exit_code, 0);
    EXPECT_THAT(run.err, HasSubstr("platemeter: error: " + spec + ": "));
    EXPECT_THAT(run.err, HasSubstr(c.expected));
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_FALSE(std::filesystem::exists(out + "/bad.tif"));
    EXPECT_FALSE(std::filesystem::exists(out + "/bad.truth.csv"));
  }
  const testing::CommandResult missing = testing::RunPlatemeter("simulate '" + dir.file("none.toml") + "' -o '" + dir.file("o") + "'");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_THAT(missing.err, HasSubstr("none.toml: cannot open the spec file"));
}

}  // namespace
}  // namespace platemeter::sim
