// Job files from the command line (docs/job.md): detect's and measure's flags laid over
// a job's request (cli/detect_options.h), `measure --job` / `detect --job` against the
// equivalent flags, and explicit flags over the job. The job file itself is tested in
// tests/pipeline/job_file_test.cpp.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <regex>

#include "detect_options.h"
#include "platemeter/core/error.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/pipeline/job_file.h"
#include "platemeter/pipeline/measure_run.h"
#include "support/job_plates.h"
#include "support/test_support.h"

namespace platemeter::cli {
namespace {

using pipeline::CanonicalOptionsText;
using pipeline::LoadJobFile;
using pipeline::MeasureRequest;
using testing::JobDocsExample;
using testing::OrbigonJobScan;
using testing::OrbigonTruthMeasurementFile;
using testing::ReadTextFile;
using testing::RunPlatemeter;
using testing::TempDir;

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// `detect`'s and `measure`'s detection flags parsed over a job's request.
DetectRequest Resolve(const DetectRequest& base, const std::string& arguments) {
  CLI::App app;
  OptionOverlay<DetectRequest> overlay(&app);
  AddScanOptions(overlay);
  AddFeatureOptions(overlay);
  app.parse(arguments, false);
  return overlay.Resolve(base);
}

TEST(CliJob, DetectionFlagsGivenOverrideTheJobAndOnlyThose) {
  TempDir dir;
  WriteText(dir.file("job.toml"), JobDocsExample());
  const DetectRequest job = LoadJobFile(dir.file("job.toml")).measure.detect;

  // Nothing given: the job as it is.
  MeasureRequest given, expected;
  given.detect = Resolve(job, "");
  expected.detect = job;
  EXPECT_EQ(CanonicalOptionsText(given), CanonicalOptionsText(expected));

  const DetectRequest a = Resolve(job, "--pixel-size-um 12.5 --orientation 90m --star-fwhm-px 3 --trail-dashes 3,5 "
                                       "--passpoint-polarity dark --passpoint-diameter-um 300");
  EXPECT_EQ(a.pixel_size_um, 12.5);
  EXPECT_EQ(a.orientation, "90m");
  EXPECT_EQ(a.star_fwhm_px, 3.0);
  EXPECT_TRUE(a.stars);
  ASSERT_TRUE(a.trails && a.passpoints);
  EXPECT_EQ(a.trails->start_utc, "1972-05-12T05:30:00Z");  // the job's
  EXPECT_EQ(a.trails->leading_dashes, (std::vector<int>{3, 5}));
  EXPECT_EQ(a.trails->break_s, 540.0);  // the job's
  EXPECT_EQ(a.passpoints->diameter_um, 300.0);
  EXPECT_EQ(a.passpoints->polarity, "dark");
  EXPECT_EQ(a.passpoints->shape, "ring");  // the job's
  EXPECT_EQ(a.passpoints->line_width_um, 30.0);
  EXPECT_EQ(a.passpoints->list_file, dir.file("passpoints.csv"));

  // Without a job: a trail or passpoint detail alone is refused (it would be silently ignored); the start
  // time and the diameter switch them on, with the details given and the defaults.
  EXPECT_THROW(Resolve({}, "--trail-dashes 3,5"), Error);
  EXPECT_THROW(Resolve({}, "--trail-break-s 500"), Error);
  EXPECT_THROW(Resolve({}, "--trails-require-joined"), Error);
  EXPECT_THROW(Resolve({}, "--passpoint-shape ring"), Error);
  EXPECT_THROW(Resolve({}, "--passpoints list.csv"), Error);
  const DetectRequest b = Resolve({}, "--trail-break-s 500 --trails-start-utc 1972-05-12T05:30:00Z --passpoint-diameter-um 200 "
                                      "--passpoints list.csv");
  ASSERT_TRUE(b.trails && b.passpoints);
  EXPECT_EQ(b.trails->start_utc, "1972-05-12T05:30:00Z");
  EXPECT_EQ(b.trails->leading_dashes, (std::vector<int>{2, 3, 4, 5}));
  EXPECT_EQ(b.trails->break_s, 500.0);
  EXPECT_FALSE(b.trails->require_joined);
  EXPECT_EQ(b.passpoints->diameter_um, 200.0);
  EXPECT_EQ(b.passpoints->shape, "dot");
  EXPECT_EQ(b.passpoints->polarity, "dark");
  EXPECT_EQ(b.passpoints->list_file, "list.csv");
}

std::string CorrectionParameter(const MeasurementFile& file, const std::string& correction, const std::string& key) {
  for (const AppliedCorrection& c : file.header.corrections)
    for (const auto& [k, v] : c.parameters)
      if (c.name == correction && k == key) return v;
  return "";
}

TEST(CliJobMeasure, WithAJobItWritesWhatTheEquivalentFlagsWrite) {
  TempDir dir;
  const std::string scan = OrbigonTruthMeasurementFile(dir);
  WriteText(dir.file("job.toml"),
            "camera = \"orbigon\"\norientation = \"0\"\n[measure]\ntemperature_degC = 22.0\nemulsion_depth_um = 21.0\n"
            "model = \"affine\"\nlocal_reseau = false\ntolerance_um = 3.0\n");
  const auto flags = RunPlatemeter("measure '" + scan + "' --camera orbigon --orientation 0 --temperature-degC 22 "
                                   "--emulsion-depth-um 21 --model affine --no-local-reseau --tolerance-um 3 -o '" +
                                   dir.file("flags") + "'");
  ASSERT_EQ(flags.exit_code, 0) << flags.err;
  const auto job = RunPlatemeter("measure '" + scan + "' --job '" + dir.file("job.toml") + "' -o '" + dir.file("job") + "'");
  ASSERT_EQ(job.exit_code, 0) << job.err;
  const std::string a = ReadTextFile(dir.file("flags/orbigon.measurements.csv"));
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(ReadTextFile(dir.file("job/orbigon.measurements.csv")), a);
  EXPECT_EQ(ReadTextFile(dir.file("job/orbigon.measure.json")), ReadTextFile(dir.file("flags/orbigon.measure.json")));
  // And they are what the job asked for: thermal, emulsion, an affine fit, no local step.
  const MeasurementFile file = ReadMeasurementFile(dir.file("job/orbigon.measurements.csv"));
  std::vector<std::string> names;
  for (const AppliedCorrection& c : file.header.corrections) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"comparator", "thermal", "emulsion_depth", "reseau_fit"}));
  EXPECT_EQ(CorrectionParameter(file, "reseau_fit", "model"), "affine");
  const nlohmann::json report = nlohmann::json::parse(ReadTextFile(dir.file("job/orbigon.measure.json")));
  EXPECT_EQ(report["reseau"]["tolerance_um"], 3.0);
  // The console text differs only by the output folder.
  EXPECT_EQ(std::regex_replace(job.out, std::regex(dir.file("job")), "OUT"),
            std::regex_replace(flags.out, std::regex(dir.file("flags")), "OUT"));
}

TEST(CliJobMeasure, ExplicitFlagsOverrideTheJob) {
  TempDir dir;
  const std::string scan = OrbigonTruthMeasurementFile(dir);
  WriteText(dir.file("job.toml"), "camera = \"orbigon\"\norientation = \"90\"\n[measure]\ntemperature_degC = 22.0\n"
                                  "model = \"affine\"\nlocal_reseau = false\n");
  const auto result = RunPlatemeter("measure '" + scan + "' --job '" + dir.file("job.toml") +
                                    "' --orientation 0 --model similarity --temperature-degC 21 -o '" + dir.file("out") + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const MeasurementFile file = ReadMeasurementFile(dir.file("out/orbigon.measurements.csv"));
  EXPECT_EQ(CorrectionParameter(file, "comparator", "orientation_deg"), "0");
  EXPECT_EQ(CorrectionParameter(file, "reseau_fit", "model"), "similarity");
  EXPECT_EQ(std::stod(CorrectionParameter(file, "thermal", "temperature_degC")), 21.0);
  std::vector<std::string> names;
  for (const AppliedCorrection& c : file.header.corrections) names.push_back(c.name);
  EXPECT_EQ(names.back(), "reseau_fit");  // the job's local_reseau = false, where no flag was given

  // Without a camera anywhere: one line.
  WriteText(dir.file("nocamera.toml"), "orientation = \"0\"\n");
  const auto none = RunPlatemeter("measure '" + scan + "' --job '" + dir.file("nocamera.toml") + "' -o '" + dir.file("none") + "'");
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_EQ(none.err, "platemeter: error: measure: give --camera NAME (or camera in the --job file)\n");
}

TEST(CliJob, DetectTakesTheJobAndTheFlagsOverIt) {
  const std::string& scan = OrbigonJobScan();
  TempDir dir;
  // The job's camera, its wrong orientation corrected on the command line.
  WriteText(dir.file("job.toml"), "camera = \"orbigon\"\norientation = \"90m\"\n");
  const auto result = RunPlatemeter("detect '" + scan + "' --job '" + dir.file("job.toml") + "' --orientation 0 -o '" +
                                    dir.file("out") + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const MeasurementFile file = ReadMeasurementFile(dir.file("out/orbigon.measurements.csv"));
  EXPECT_EQ(file.header.camera, "orbigon");
  EXPECT_EQ(file.points.size(), 121u);
  int measured = 0;
  for (const MeasuredPoint& p : file.points) measured += p.status == PointStatus::kMeasured;
  EXPECT_GE(measured, 119);
  const nlohmann::json summary = nlohmann::json::parse(ReadTextFile(dir.file("out/orbigon.detect.json")));
  EXPECT_EQ(summary["orientation"], "0");
  // A bad job is one line naming it, and nothing is written.
  WriteText(dir.file("bad.toml"), "camera = \"orbigon\"\norientaton = \"0\"\n");
  const auto bad = RunPlatemeter("detect '" + scan + "' --job '" + dir.file("bad.toml") + "' -o '" + dir.file("bad") + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err, "platemeter: error: " + dir.file("bad.toml") + ": line 2: unknown key 'orientaton' (docs/job.md lists the keys)\n");
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad")));
}

}  // namespace
}  // namespace platemeter::cli
