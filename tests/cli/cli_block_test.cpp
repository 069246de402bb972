// The rendered block end to end, as scripts/demo runs it: `platemeter simulate`
// on the bundled block spec (samples/blocks/hasselblad-block.toml: 9 Hasselblad
// frames of seed 000's lunar geometry at CI size), `platemeter batch` on the
// manifest it writes (every frame measured with its approximate passpoint
// list), `platemeter calibrate bundle` on the job it writes; the outcome
// against the block's truth file (the simulator's true camera): every free
// inner-cone parameter within 3 of its sigma, sigma0 within the band its
// degrees of freedom allow, every passpoint measured under its own id in every
// frame. And a bad block spec refused in one line naming file and key.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;
using testing::TempDir;

std::string BlockSpecPath() { return std::string(PLATEMETER_SOURCE_DIR) + "/samples/blocks/hasselblad-block.toml"; }

nlohmann::json ReadJson(const std::string& path) { return nlohmann::json::parse(testing::ReadTextFile(path)); }

struct Timed {
  testing::CommandResult result;
  double seconds = 0.0;
};
Timed RunTimed(const std::string& arguments) {
  const auto start = std::chrono::steady_clock::now();
  Timed t;
  t.result = RunPlatemeter(arguments);
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return t;
}

// Wilson-Hilferty: the p quantile of chi-square with f degrees of freedom.
double ChiSquareQuantile(double f, double z_p) {
  const double a = 2.0 / (9.0 * f);
  return f * std::pow(1.0 - a + z_p * std::sqrt(a), 3);
}

// Per frame: the passpoint ids measured, and the share of each passpoint's
// variance that is its own (the detector's sigma in pixels times the pixel
// size) rather than the frame's common interior-orientation error, which
// measure adds to every point (docs/measure.md) and the bundle's exterior
// orientation largely absorbs.
struct MeasuredFrame {
  std::set<std::string> measured_ids;
  double own_variance_share_sum = 0.0;
  int components = 0;
  std::vector<ImageObservation> own_sigma_observations;  // the plate mm with the per-point sigmas only
};
MeasuredFrame ReadMeasuredFrame(const std::string& path, const std::string& frame_id) {
  const MeasurementFile file = ReadMeasurementFile(path);
  MeasuredFrame frame;
  const double pixel_mm = file.header.pixel_size_um.value_or(0.0) * 1e-3;
  for (const MeasuredPoint& p : file.points) {
    if (p.kind != PointKind::kPasspoint || p.status != PointStatus::kMeasured) continue;
    frame.measured_ids.insert(p.id);
    const double own_x = *p.sigma_x_px * pixel_mm, own_y = *p.sigma_y_px * pixel_mm;
    frame.own_variance_share_sum += own_x * own_x / (*p.sigma_x_mm * *p.sigma_x_mm);
    frame.own_variance_share_sum += own_y * own_y / (*p.sigma_y_mm * *p.sigma_y_mm);
    frame.components += 2;
    ImageObservation o;
    o.frame = frame_id;
    o.point_id = p.id;
    o.x_mm = *p.x_mm;
    o.y_mm = *p.y_mm;
    o.sigma_x_mm = own_x;
    o.sigma_y_mm = own_y;
    frame.own_sigma_observations.push_back(o);
  }
  return frame;
}

// The written job with its frames' measurement files replaced by an
// observations CSV (same frames, approximations, ground points, camera).
std::string JobWithObservations(const std::string& job_text, const std::string& observations_file) {
  std::stringstream in(job_text);
  std::string out = "observations = \"" + observations_file + "\"\n", line;
  while (std::getline(in, line)) {
    if (line.rfind("measurements = ", 0) != 0) out += line + "\n";
  }
  return out;
}

struct InnerCone {
  double sigma0 = 0.0, dof = 0.0;
  int free_parameters = 0;
  std::string z_report;
};
// The free parameters of calibration.json against the block's true camera:
// each within 3 of its sigma.
InnerCone CheckInnerCone(const nlohmann::json& calibration, const nlohmann::json& truth, const std::string& what) {
  InnerCone cone;
  EXPECT_TRUE(calibration["converged"].get<bool>()) << what;
  cone.sigma0 = calibration["sigma0"];
  cone.dof = calibration["degrees_of_freedom"];
  const auto& parameters = calibration["cameras"][0]["parameters"];
  std::ostringstream report;
  for (const char* name : kBundleCameraParamNames) {
    const auto& p = parameters[name];
    if (p["status"] != "free") continue;
    ++cone.free_parameters;
    EXPECT_TRUE(p["sigma"].is_number()) << what << ": " << name;
    if (!p["sigma"].is_number()) continue;
    const double value = p["value"], sigma = p["sigma"], true_value = truth["camera"][name];
    const double z = (value - true_value) / sigma;
    char line[200];
    std::snprintf(line, sizeof line, "  %-11s true %-12.6g adjusted %-14.8g sigma %-10.3g z %+.2f\n", name,
                  true_value, value, sigma, z);
    report << line;
    EXPECT_LT(std::abs(z), 3.0) << what << ": " << name << " = " << value << " +- " << sigma << ", true "
                                << true_value;
  }
  cone.z_report = report.str();
  return cone;
}

TEST(CliBlock, RenderedHasselbladBlockSelfCalibratesToItsTruth) {
  TempDir dir;
  const std::string out = dir.file("block");
  const Timed simulate = RunTimed("simulate '" + BlockSpecPath() + "' -o '" + out + "'");
  ASSERT_EQ(simulate.result.exit_code, 0) << simulate.result.err;
  const nlohmann::json truth = ReadJson(out + "/hasselblad-block.truth.json");
  ASSERT_EQ(truth["frames"].size(), 9u);
  ASSERT_EQ(truth["files"]["measured_dir"], "measured");

  const Timed batch = RunTimed("batch '" + out + "/hasselblad-block.manifest.csv' -o '" + out + "/measured'");
  ASSERT_EQ(batch.result.exit_code, 0) << batch.result.err << batch.result.out;

  // Every frame: each of its passpoints measured, under the ground point's id.
  double share_sum = 0.0;
  int components = 0;
  std::vector<ImageObservation> own_sigma_observations;
  for (const auto& frame : truth["frames"]) {
    const std::string id = frame["id"];
    std::set<std::string> expected;
    for (const auto& p : frame["image_points"]) expected.insert(p["id"].get<std::string>());
    const MeasuredFrame measured = ReadMeasuredFrame(out + "/measured/" + id + "/" + id + ".measurements.csv", id);
    EXPECT_EQ(measured.measured_ids, expected) << "frame " << id;
    share_sum += measured.own_variance_share_sum;
    components += measured.components;
    own_sigma_observations.insert(own_sigma_observations.end(), measured.own_sigma_observations.begin(),
                                  measured.own_sigma_observations.end());
  }
  ASSERT_GT(components, 0);
  const double own_share = share_sum / components;

  const Timed bundle = RunTimed("calibrate bundle '" + out + "/hasselblad-block.bundle.toml' -o '" + out + "/bundle'");
  ASSERT_EQ(bundle.result.exit_code, 0) << bundle.result.err << bundle.result.out;
  EXPECT_TRUE(std::filesystem::exists(out + "/bundle/report.html"));
  const nlohmann::json calibration = ReadJson(out + "/bundle/calibration.json");
  ASSERT_EQ(calibration["cameras"].size(), 1u);
  const InnerCone cone = CheckInnerCone(calibration, truth, "the job as written");
  EXPECT_EQ(cone.free_parameters, 7);  // c, xp, yp, k1, k2, p1, p2

  // sigma0 against the two-sided 99.9 % chi-square band of its degrees of
  // freedom. measure's sigma of a passpoint includes its frame's interior
  // orientation error (the four corners' fit, common to the frame's points:
  // docs/measure.md); the bundle takes the observations as independent, and
  // its exterior orientation absorbs most of that common part, which lowers
  // sigma0 by at most sqrt(own share): the lower end of the accepted band.
  const double chi_lower = std::sqrt(ChiSquareQuantile(cone.dof, -3.2905) / cone.dof);
  const double chi_upper = std::sqrt(ChiSquareQuantile(cone.dof, 3.2905) / cone.dof);
  const double lower = chi_lower * std::sqrt(own_share);
  EXPECT_GT(cone.sigma0, lower);
  EXPECT_LT(cone.sigma0, chi_upper);

  // The same observations weighted by their own (per-point) sigmas alone: the
  // model then matches the errors, and sigma0 must lie in the chi-square band itself.
  WriteObservationsCsv(out + "/own-sigmas.csv", own_sigma_observations);
  std::ofstream(out + "/own-sigmas.bundle.toml")
      << JobWithObservations(testing::ReadTextFile(out + "/hasselblad-block.bundle.toml"), "own-sigmas.csv");
  const auto own = RunPlatemeter("calibrate bundle '" + out + "/own-sigmas.bundle.toml' -o '" + out + "/own'");
  ASSERT_EQ(own.exit_code, 0) << own.err << own.out;
  const InnerCone own_cone = CheckInnerCone(ReadJson(out + "/own/calibration.json"), truth, "per-point sigmas");
  EXPECT_EQ(own_cone.dof, cone.dof);
  EXPECT_GT(own_cone.sigma0, chi_lower);
  EXPECT_LT(own_cone.sigma0, chi_upper);

  std::printf("rendered block: simulate %.1f s, batch (measure) %.1f s, calibrate bundle %.1f s\n", simulate.seconds,
              batch.seconds, bundle.seconds);
  std::printf("inner cone against the truth, the job as written (sigmas as calibration.json gives them):\n%s",
              cone.z_report.c_str());
  std::printf("sigma0 %.4f with %.0f degrees of freedom; chi-square 99.9 %% band %.4f..%.4f; the observations' own "
              "variance share %.3f: accepted %.4f..%.4f\n",
              cone.sigma0, cone.dof, chi_lower, chi_upper, own_share, lower, chi_upper);
  std::printf("with the per-point sigmas only:\n%ssigma0 %.4f with %.0f degrees of freedom (band %.4f..%.4f)\n",
              own_cone.z_report.c_str(), own_cone.sigma0, own_cone.dof, chi_lower, chi_upper);
}

TEST(CliBlock, BadBlockSpecIsOneLineNamingFileAndKey) {
  TempDir dir;
  std::ifstream in(BlockSpecPath());
  std::stringstream text;
  text << in.rdbuf();
  std::string spec = text.str();
  const std::string from = "convergence_deg = 80.0";
  ASSERT_NE(spec.find(from), std::string::npos);
  spec.replace(spec.find(from), from.size(), "convergence_deg = 200.0");
  const std::string frame_spec = "frame_spec = \"hasselblad-80-frame.toml\"";
  spec.replace(spec.find(frame_spec), frame_spec.size(),
               "frame_spec = \"" + std::string(PLATEMETER_SOURCE_DIR) + "/samples/blocks/hasselblad-80-frame.toml\"");
  const std::string path = dir.file("bad-block.toml");
  std::ofstream(path) << spec;
  const auto result = RunPlatemeter("simulate '" + path + "' -o '" + dir.file("out") + "'");
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find("platemeter: error: " + path + ": line "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("orbits: key 'convergence_deg' = 200 must lie in 1..170"), std::string::npos)
      << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

}  // namespace
}  // namespace platemeter
