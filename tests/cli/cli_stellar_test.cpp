// platemeter calibrate stellar end to end: two simulated Orbigon plates (North
// and South, two dates) written as measurement files whose stars carry only
// detector keys, identified, adjusted and combined by the binary; the outputs
// read back and checked against the simulator's truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "platemeter/calib/rotations.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

constexpr const char* kSite = "[site]\nlatitude_deg = 39.03\nlongitude_deg = -76.93\nheight_m = 50\n";

struct TwoPlateJob {
  std::string job;
  std::map<std::string, std::map<std::string, std::string>> truth_of;  // plate -> key -> catalog key
  StellarCamera truth{};
};

TwoPlateJob WriteTwoPlateJob(const testing::TempDir& dir) {
  const DefinitionRegistry registry;
  TwoPlateJob out;
  std::string plates;
  for (const auto& [id, start, roll, seed] : {std::tuple{"N", "1972-05-12T05:30:00Z", 0.0, 21},
                                              std::tuple{"S", "1972-04-09T06:10:00Z", 180.0, 22}}) {
    sim::StellarPlateSimulation s = testing::BeltsvillePlate(id, start, roll);
    s.field.place.pressure_hpa = 1013.25 * std::exp(-50.0 / (29.3 * (273.15 + 10.0)));  // the job's default
    const sim::StellarTruthPlate truth = sim::SimulateStellarTruth(s, registry.Camera("orbigon"));
    out.truth = truth.camera;
    const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = static_cast<uint64_t>(seed)});
    const std::string path = dir.file(std::string(id) + ".csv");
    out.truth_of[id] = sim::WriteStellarMeasurementFile(noisy.plate, path, true);
    // The pointing given 4 deg off the zenith.
    plates += "[[plate]]\nid = \"" + std::string(id) + "\"\nmeasurements = \"" + path +
              "\"\naxis_azimuth_deg = 120\naxis_altitude_deg = 86\n";
  }
  out.job = dir.file("job.toml");
  WriteText(out.job, "title = \"two simulated Orbigon plates\"\ncamera = \"orbigon\"\n" + std::string(kSite) + plates);
  return out;
}

TEST(CliStellar, IdentifiesAdjustsAndCombinesTwoPlates) {
  testing::TempDir dir;
  const TwoPlateJob job = WriteTwoPlateJob(dir);
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("calibrate stellar '" + job.job + "' -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  std::printf("%s", run.out.c_str());
  for (const char* name : {"calibration.json", "report.md", "residuals.csv", "identification.csv",
                           "camera-orbigon-stellar.toml"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + name)) << name;
  // Every identified star is the simulator's.
  std::istringstream identification(testing::ReadTextFile(out + "/identification.csv"));
  std::string line;
  int identified = 0, wrong = 0;
  std::getline(identification, line);
  while (std::getline(identification, line)) {
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string v; std::getline(fields, v, ',');) f.push_back(v);
    if (f.size() < 4 || f[3] != "identified") continue;
    ++identified;
    wrong += job.truth_of.at(f[0]).at(f[1]) == f[2] ? 0 : 1;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(identified, 1000);
  // The combined camera within 3 sigma of the true lens.
  const nlohmann::json j = nlohmann::json::parse(testing::ReadTextFile(out + "/calibration.json"));
  ASSERT_EQ(j["combinations"].size(), 1u);
  const auto& camera = j["combinations"][0]["camera"]["plate_frame"];
  for (int i = 0; i < kStellarCameraParams; ++i) {
    const auto& p = camera[kStellarCameraParamNames[i]];
    double difference = p["value"].get<double>() - job.truth[i];
    if (i == 10) difference = std::remainder(difference, 2 * M_PI);
    EXPECT_LT(std::abs(difference), 3.0 * p["sigma"].get<double>()) << kStellarCameraParamNames[i];
  }
  EXPECT_NEAR(j["combinations"][0]["m_0"].get<double>(), 1.0, 0.1);
  // The calibrated camera is a definition platemeter loads.
  const auto show = RunPlatemeter("--definitions '" + out + "/camera-orbigon-stellar.toml' cameras show orbigon");
  EXPECT_EQ(show.exit_code, 0) << show.err;
}

// Seed 004's SMAC through the job file: two cameras 96 deg apart on one mount
// (camera "orbigon" looking north at 48 deg altitude, a second camera
// "orbigon-b" looking south, defined in the test by its nominal principal
// distance only), two exposures; the interlock within 3 sigma of the truth.
TEST(CliStellar, InterlocksTwoCamerasExposedTogether) {
  testing::TempDir dir;
  const DefinitionRegistry registry;
  const CameraDefinition lens_a = registry.Camera("orbigon");
  CameraDefinition lens_b = lens_a;
  lens_b.lens->principal_distance_mm += 0.6;
  lens_b.lens->principal_point_x_mm += 0.040;
  const std::string definitions = dir.file("b.toml");
  WriteText(definitions, "[[camera]]\nname = \"orbigon-b\"\ndescription = \"a second Orbigon\"\nsource = \"test\"\n"
                         "format_width_mm = 114.0\nformat_height_mm = 114.0\nnominal_principal_distance_mm = 80.8\n");
  std::string plates;
  Eigen::Matrix3d b_from_a;
  for (const auto& [exposure, start] : {std::pair{"1", "1972-05-12T05:30:00Z"}, std::pair{"2", "1972-04-09T06:10:00Z"}}) {
    for (const bool b : {false, true}) {
      const std::string id = std::string(b ? "B" : "A") + exposure;
      sim::StellarPlateSimulation s = testing::BeltsvillePlate(id, start, b ? 30.0 : 0.0);
      s.field.place.pressure_hpa = 1013.25 * std::exp(-50.0 / (29.3 * (273.15 + 10.0)));  // the job's default
      s.field.axis_azimuth_deg = b ? 180.0 : 0.0;
      s.field.axis_altitude_deg = 48.0;
      s.magnitude_limit = 5.5;
      const sim::StellarTruthPlate truth = sim::SimulateStellarTruth(s, b ? lens_b : lens_a);
      if (b) b_from_a = truth.camera_from_enu * b_from_a.transpose();
      else b_from_a = truth.camera_from_enu;
      const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = static_cast<uint64_t>(40 + id[1] + 2 * b)});
      const std::string path = dir.file(id + ".csv");
      sim::WriteStellarMeasurementFile(noisy.plate, path, true);
      plates += "[[plate]]\nid = \"" + id + "\"\nmeasurements = \"" + path + "\"\nexposure = \"" + exposure +
                "\"\naxis_azimuth_deg = " + (b ? "178" : "3") + "\naxis_altitude_deg = 46\n" +
                (b ? "camera = \"orbigon-b\"\n" : "");
    }
  }
  const std::string job = dir.file("job.toml");
  WriteText(job, "camera = \"orbigon\"\nmagnitude_limit = 5.5\norientation_sets = 2\n" + std::string(kSite) + plates);
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("--definitions '" + definitions + "' calibrate stellar '" + job + "' -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  std::printf("%s", run.out.c_str());
  for (const char* name : {"camera-orbigon-stellar.toml", "camera-orbigon-b-stellar.toml"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + name)) << name;
  const nlohmann::json j = nlohmann::json::parse(testing::ReadTextFile(out + "/calibration.json"));
  ASSERT_TRUE(j.contains("interlock"));
  const auto& interlock = j["interlock"]["interlocks"][0];
  EXPECT_EQ(interlock["to"], "orbigon-b");
  const OmegaPhiKappa truth = OmegaPhiKappaFromMatrix(b_from_a);
  const double truth_rad[3] = {truth.omega_rad, truth.phi_rad, truth.kappa_rad};
  const char* names[3] = {"omega", "phi", "kappa"};
  for (int i = 0; i < 3; ++i) {
    const double error_arcsec =
        std::remainder(interlock[std::string(names[i]) + "_rad"].get<double>() - truth_rad[i], 2 * M_PI) * 180 * 3600 / M_PI;
    const double sigma_arcsec = interlock[std::string(names[i]) + "_sigma_arcsec"].get<double>();
    EXPECT_GT(sigma_arcsec, 0.0);
    EXPECT_LT(std::abs(error_arcsec), 3.0 * sigma_arcsec) << names[i];
  }
  EXPECT_NEAR(j["interlock"]["statistics"]["sigma0"].get<double>(), 1.0, 0.1);
  EXPECT_NE(testing::ReadTextFile(out + "/report.md").find("Relative orientation matrix"), std::string::npos);
}

// Seed 004's lens model through the job file: two simulated plates of the
// sn004-terrain camera (its smac-radial-decentering lens, Table A.4, is the
// truth and the starting camera), stars identified from detector keys; the
// combined camera within 3 sigma of the truth, and the camera TOML written
// with the smac lens loads as a definition.
TEST(CliStellar, SmacLensModelWritesALoadableCamera) {
  testing::TempDir dir;
  const DefinitionRegistry registry;
  StellarCamera truth;
  std::string plates;
  for (const auto& [id, start, roll, seed] : {std::tuple{"N", "1972-05-12T05:30:00Z", 0.0, 61},
                                              std::tuple{"S", "1972-04-09T06:10:00Z", 180.0, 62}}) {
    sim::StellarPlateSimulation s = testing::BeltsvillePlate(id, start, roll);
    s.field.place.pressure_hpa = 1013.25 * std::exp(-50.0 / (29.3 * (273.15 + 10.0)));  // the job's default
    s.magnitude_limit = 5.5;
    const sim::StellarTruthPlate t = sim::SimulateStellarTruth(s, registry.Camera("sn004-terrain"));
    truth = t.camera;
    const std::string path = dir.file(std::string(id) + ".csv");
    sim::WriteStellarMeasurementFile(sim::Noisy(t, {.seed = static_cast<uint64_t>(seed)}).plate, path, true);
    plates += "[[plate]]\nid = \"" + std::string(id) + "\"\nmeasurements = \"" + path +
              "\"\naxis_azimuth_deg = 120\naxis_altitude_deg = 87\n";
  }
  const std::string job = dir.file("job.toml");
  WriteText(job, "camera = \"sn004-terrain\"\nlens_model = \"smac-radial-decentering\"\nmagnitude_limit = 5.5\n" +
                     std::string(kSite) + plates);
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("calibrate stellar '" + job + "' -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  std::printf("%s", run.out.c_str());
  const nlohmann::json j = nlohmann::json::parse(testing::ReadTextFile(out + "/calibration.json"));
  EXPECT_EQ(j["lens_model"], "smac-radial-decentering");
  ASSERT_EQ(j["combinations"].size(), 1u);
  const auto& camera = j["combinations"][0]["camera"];
  EXPECT_FALSE(camera.contains("seed001_printed_frame"));
  const std::vector<std::string> names = StellarCameraParamNames(DistortionModelId::kSmacRadialDecentering);
  for (size_t i = 0; i < names.size(); ++i) {
    const auto& p = camera["plate_frame"][names[i]];
    double difference = p["value"].get<double>() - truth[i];
    if (names[i] == "theta0_rad") difference = std::remainder(difference, 2 * M_PI);
    std::printf("%-11s z %6.2f\n", names[i].c_str(), difference / p["sigma"].get<double>());
    EXPECT_LT(std::abs(difference), 3.0 * p["sigma"].get<double>()) << names[i];
  }
  EXPECT_NEAR(j["combinations"][0]["m_0"].get<double>(), 1.0, 0.1);
  const std::string toml = testing::ReadTextFile(out + "/camera-sn004-terrain-stellar.toml");
  EXPECT_NE(toml.find("model = \"smac-radial-decentering\""), std::string::npos) << toml;
  EXPECT_NE(toml.find("theta0_rad = "), std::string::npos) << toml;
  const auto show =
      RunPlatemeter("--definitions '" + out + "/camera-sn004-terrain-stellar.toml' cameras show sn004-terrain");
  EXPECT_EQ(show.exit_code, 0) << show.err;
  EXPECT_NE(show.out.find("smac-radial-decentering"), std::string::npos) << show.out;
}

TEST(CliStellar, BadJobsAreOneLineErrors) {
  testing::TempDir dir;
  const std::string out = dir.file("out");
  const std::string measurements = dir.file("m.csv");
  WriteText(measurements, "x\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"camera = \"orbigon\"\nfoo = 1\n" + std::string(kSite), "unknown key 'foo'"},
      {"camera = \"nosuch\"\n" + std::string(kSite), "unknown camera 'nosuch'"},
      {"camera = \"orbigon\"\n", "[site]"},
      {"camera = \"orbigon\"\norientation_sets = 4\n" + std::string(kSite), "orientation_sets"},
      {"camera = \"orbigon\"\n" + std::string(kSite) + "[[plate]]\nid = \"A\"\n", "needs 'id' and 'measurements'"},
      {"camera = \"orbigon\"\nlens_model = \"brown-balanced\"\n" + std::string(kSite), "lens_model: 'brown-balanced'"},
      {"camera = \"orbigon\"\nlens_model = \"smac-radial-decentering\"\nfixed = [\"xs_mm\"]\n" + std::string(kSite),
       "unknown smac-radial-decentering camera parameter 'xs_mm'"},
      {"camera = \"orbigon\"\n" + std::string(kSite) + "[[plate]]\nid = \"A\"\nmeasurements = \"" + measurements +
           "\"\ncamera = \"nosuch\"\n", "unknown camera 'nosuch'"},
  };
  for (const auto& [text, reason] : cases) {
    const std::string job = dir.file("bad.toml");
    WriteText(job, text);
    const auto run = RunPlatemeter("calibrate stellar '" + job + "' -o '" + out + "'");
    EXPECT_EQ(run.exit_code, 1) << text;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_NE(run.err.find(reason), std::string::npos) << run.err;
    EXPECT_FALSE(std::filesystem::exists(out + "/calibration.json"));
  }
}

}  // namespace
}  // namespace platemeter
