// platemeter calibrate bundle end to end: a simulated block written as the
// observations CSV, the adjustment run by the binary, its outputs read back
// and checked against the simulator's truth; bad input answered in one line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/samples/bundle_block.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

std::string ReadTextOfCalibrate(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The Table 9 block (80 mm) as an observations CSV with no approximations.
std::string WriteLunarObservations(const testing::TempDir& dir, sim::SimulatedBlock* block) {
  sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
  options.seed = 3;
  *block = sim::SimulateLunarBlock(options);
  const std::string path = dir.file("observations.csv");
  WriteObservationsCsv(path, block->input.observations);
  return path;
}

TEST(CliCalibrate, BundleFromAnObservationsCsvWritesEveryOutput) {
  testing::TempDir dir;
  sim::SimulatedBlock block;
  const std::string observations = WriteLunarObservations(dir, &block);
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("calibrate bundle --observations '" + observations +
                                 "' --principal-distance-mm 80.5 --free c,xp,yp,k1,k2,p1,p2 -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  EXPECT_NE(run.out.find("sigma0"), std::string::npos) << run.out;
  for (const char* name : {"calibration.json", "report.md", "residuals.csv", "camera-camera.toml"}) {
    EXPECT_TRUE(std::filesystem::exists(out + "/" + name)) << name;
  }
  const nlohmann::json j = nlohmann::json::parse(ReadTextOfCalibrate(out + "/calibration.json"));
  EXPECT_EQ(j["datum"]["kind"], "inner-constraints");
  EXPECT_GT(j["degrees_of_freedom"].get<double>(), 3000.0);
  EXPECT_NEAR(j["sigma0"].get<double>(), 1.0, 0.1);
  const auto truth = block.truth.camera.Values();
  const auto& parameters = j["cameras"][0]["parameters"];
  for (int i : {0, 1, 2, 3, 4, 6, 7}) {
    const auto& p = parameters[kBundleCameraParamNames[i]];
    ASSERT_TRUE(p["sigma"].is_number()) << kBundleCameraParamNames[i];
    EXPECT_LT(std::abs(p["value"].get<double>() - truth[i]), 4.0 * p["sigma"].get<double>())
        << kBundleCameraParamNames[i];
  }
  EXPECT_EQ(parameters["k3_per_mm6"]["status"], "fixed");
  EXPECT_EQ(j["cameras"][0]["correlation"]["parameters"].size(), 7u);
  EXPECT_EQ(j["frames"].size(), 9u);
  // One residual row per observation, plus the header.
  const std::string residuals = ReadTextOfCalibrate(out + "/residuals.csv");
  EXPECT_EQ(std::count(residuals.begin(), residuals.end(), '\n'), long(block.input.observations.size()) + 1);
  // The calibrated camera loads as a definition.
  const auto show = RunPlatemeter("--definitions '" + out + "/camera-camera.toml' cameras show camera");
  EXPECT_EQ(show.exit_code, 0) << show.err;
  EXPECT_NE(show.out.find("brown-affine"), std::string::npos) << show.out;
}

// One line on stderr naming the subject, exit code 1, no output folder.
void ExpectOneLineError(const testing::CommandResult& result, const std::string& subject,
                        const std::string& reason, const std::string& out) {
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(subject), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(reason), std::string::npos) << result.err;
  EXPECT_FALSE(std::filesystem::exists(out + "/calibration.json"));
}

TEST(CliCalibrate, BadObservationsAreOneLineErrors) {
  testing::TempDir dir;
  const std::string out = dir.file("out");
  const std::string header = "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\n";
  struct Case {
    const char* rows;
    const char* reason;
  };
  for (const Case& c : {Case{"a,P1,1.0,2.0,nan,0.01\n", "line 2"}, Case{"a,P1,1.0,2.0,-0.01,0.01\n", "line 2"},
                        Case{"a,P1,1.0,2.0,0.01,0.01\na,P1,1.5,2.0,0.01,0.01\n", "line 3"}}) {
    const std::string path = dir.file("bad.csv");
    std::ofstream(path) << header << c.rows;
    ExpectOneLineError(RunPlatemeter("calibrate bundle --observations '" + path +
                                     "' --principal-distance-mm 80 -o '" + out + "'"),
                       path, c.reason, out);
  }
}

TEST(CliCalibrate, PointsSeenOnceAndThinFramesAreLeftOutWithWarnings) {
  testing::TempDir dir;
  sim::SimulatedBlock block;
  WriteLunarObservations(dir, &block);
  std::vector<ImageObservation> observations = block.input.observations;
  ImageObservation lone = observations.front();
  lone.point_id = "LONE";
  observations.push_back(lone);
  for (const char* id : {"T1", "T2"}) {  // a frame with two points only
    ImageObservation thin = observations[5];
    thin.frame = "THIN";
    thin.point_id = observations[5 + (id[1] - '1')].point_id;
    observations.push_back(thin);
  }
  const std::string path = dir.file("observations.csv");
  WriteObservationsCsv(path, observations);
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("calibrate bundle --observations '" + path +
                                 "' --principal-distance-mm 80 --free c -o '" + out + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("warning: point LONE"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("warning: frame THIN"), std::string::npos) << run.err;
  const nlohmann::json j = nlohmann::json::parse(ReadTextOfCalibrate(out + "/calibration.json"));
  EXPECT_EQ(j["warnings"].size(), 2u);
  EXPECT_EQ(j["frames"].size(), 9u);
}

TEST(CliCalibrate, NeitherJobNorObservationsIsAnError) {
  testing::TempDir dir;
  const auto run = RunPlatemeter("calibrate bundle -o '" + dir.file("out") + "'");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("job file or --observations"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

// A job with two cameras (orbits 1-2 and orbit 3 of the Table 9 block, the same
// true lens), a-priori stations on orbit 1 (Gyer's sigmas: the datum), a gross
// error found by the robust pass, and exports.
TEST(CliCalibrate, JobWithTwoCamerasStationPriorsAndAGrossError) {
  testing::TempDir dir;
  sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
  options.seed = 5;
  sim::SimulatedBlock block = sim::SimulateLunarBlock(options);
  std::vector<ImageObservation> observations = block.input.observations;
  observations[100].x_mm += 0.5;  // 33 sigma
  const std::string gross = observations[100].frame + " " + observations[100].point_id;
  WriteObservationsCsv(dir.file("observations.csv"), observations);
  std::string job = R"(observations = ["observations.csv"]
[output]
title = "two cameras"
export_pixel_size_um = 10.0
export_image_size_px = [5500, 5500]
[adjustment]
robust_loss_scale = 3.0
)";
  for (const char* name : {"a", "b"}) {
    job += std::string("[[camera]]\nname = \"") + name +
           "\"\nformat_mm = [55.0, 55.0]\nc_mm = { value = 80.3, state = \"free\" }\n"
           "xp_mm = \"free\"\nyp_mm = \"free\"\nk1_per_mm2 = \"free\"\np1_per_mm = \"free\"\np2_per_mm = \"free\"\n";
  }
  for (size_t f = 0; f < block.input.frames.size(); ++f) {
    const sim::StationTruth& s = block.truth.stations[f];
    job += "[[frame]]\nid = \"" + s.id + "\"\ncamera = \"" + (s.id.rfind("R3", 0) == 0 ? "b" : "a") + "\"\n";
    if (s.group == 1) {
      const auto& p = s.position_m;
      const auto& v = s.velocity_direction;
      job += "position_m = [" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " + std::to_string(p.z()) +
             "]\nangles_deg = [" + std::to_string(s.angles.phi_rad * 180 / M_PI) + ", " +
             std::to_string(s.angles.omega_rad * 180 / M_PI) + ", " + std::to_string(s.angles.kappa_rad * 180 / M_PI) +
             "]\nin_track_sigma_m = 50.0\ncross_track_sigma_m = 10.0\nradial_sigma_m = 10.0\nvelocity_m_per_s = [" +
             std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + "]\n";
    }
  }
  std::ofstream(dir.file("job.toml")) << job;
  const std::string out = dir.file("out");
  const auto run = RunPlatemeter("calibrate bundle --quiet '" + dir.file("job.toml") + "' -o '" + out + "'");
  if (getenv("PLATEMETER_KEEP")) std::filesystem::copy(out, "/tmp/pm/job_out", std::filesystem::copy_options::recursive | std::filesystem::copy_options::overwrite_existing);
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  const nlohmann::json j = nlohmann::json::parse(ReadTextOfCalibrate(out + "/calibration.json"));
  EXPECT_EQ(j["datum"]["kind"], "control") << j["datum"];
  EXPECT_EQ(j["rank"]["datum_defect"], 0);
  EXPECT_EQ(j["rejected_observations"], 1);
  EXPECT_EQ(j["worst_observations"][0]["status"], "rejected");
  EXPECT_EQ(j["worst_observations"][0]["frame"].get<std::string>() + " " +
                j["worst_observations"][0]["point_id"].get<std::string>(),
            gross);
  EXPECT_NEAR(j["sigma0"].get<double>(), 1.0, 0.1);
  ASSERT_EQ(j["cameras"].size(), 2u);
  for (const auto& camera : j["cameras"]) {
    const auto& c = camera["parameters"]["c_mm"];
    EXPECT_LT(std::abs(c["value"].get<double>() - 80.0), 4.0 * c["sigma"].get<double>()) << camera["name"];
  }
  for (const char* name : {"camera-a.toml", "camera-b.toml", "camera-a-opencv.yaml", "camera-a-micmac.xml",
                           "camera-a.tsai", "camera-b.tsai"}) {
    EXPECT_TRUE(std::filesystem::exists(out + "/" + name)) << name;
  }
}

}  // namespace
}  // namespace platemeter
