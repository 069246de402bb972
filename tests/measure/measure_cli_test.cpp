// platemeter measure / validate end to end on a rendered simulator plate:
// the detector, the corrections, the files.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::CommandResult;
using testing::RunPlatemeter;
using testing::TempDir;

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return nlohmann::json::parse(s.str());
}

TEST(MeasureCli, RenderedOrbigonPlate) {
  // Seed 001's 22 degC and 21 um; 10 arcsec scanner non-orthogonality; a
  // trace-free film affine, so the mean scale is the emulsion's.
  TempDir dir;
  {
    std::ofstream spec(dir.file("plate.toml"));
    spec << R"(name = "plate"
camera = "orbigon"
seed = 3
[output]
pixel_size_um = 40.0
[thermal]
temperature_degC = 22.0
[emulsion]
depth_um = 21.0
[film]
affine_ppm = [10.0, 0.0, 0.0, -10.0]
[scanner]
rotation_deg = 0.2
non_orthogonality_arcsec = 10.0
[noise]
blur_sigma_um = 10.0
sensor_sigma_dn = 100.0
)";
  }
  ASSERT_EQ(RunPlatemeter("simulate " + dir.file("plate.toml") + " -o " + dir.file("sim")).exit_code, 0);
  const std::string scan = dir.file("sim/plate.tif");

  const CommandResult v = RunPlatemeter("validate " + scan + " --camera orbigon --orientation 0 --temperature-degC 22 -o " + dir.file("out"));
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const nlohmann::json j = ReadJson(dir.file("out/plate.validate.json"));
  // The discrepancy reads as the simulated 21 um (the detector's own scale
  // error is a fraction of a ppm-level um here).
  EXPECT_NEAR(j["emulsion_depth_reading_um"]["value"].get<double>(), 21.0, 1.0);
  EXPECT_NEAR(j["non_orthogonality_arcsec"]["value"].get<double>(), 10.0, 2.0);
  EXPECT_EQ(j["residuals"].size(), 121u);
  EXPECT_LT(j["rms_um"].get<double>(), 2.0);
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/plate.residuals.png")));

  const CommandResult m = RunPlatemeter("measure " + scan +
                                        " --camera orbigon --orientation 0 --temperature-degC 22 --emulsion-depth-um 21 -o " +
                                        dir.file("out"));
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const MeasurementFile file = ReadMeasurementFile(dir.file("out/plate.measurements.csv"));
  ASSERT_EQ(file.header.corrections.size(), 5u);  // comparator, thermal, emulsion_depth, reseau_fit, local_reseau
  int with_mm = 0;
  for (const MeasuredPoint& p : file.points) with_mm += p.x_mm && p.sigma_x_mm && *p.sigma_x_mm > 0;
  EXPECT_EQ(with_mm, 121);
  const nlohmann::json r = ReadJson(dir.file("out/plate.measure.json"));
  // The emulsion correction applied: what remains of the scale is near zero.
  EXPECT_NEAR(r["reseau"]["emulsion_depth_reading_um"]["value"].get<double>(), 0.0, 1.0);
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/plate.micmac.xml")));
}

}  // namespace
}  // namespace platemeter
