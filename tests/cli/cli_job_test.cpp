// Job definition files (cli/job.h, docs/job.md): the documented example loads and
// every key reaches the request; bad files name the file and the line; per-scan
// overrides; the options fingerprint; `measure --job` / `detect --job` against the
// equivalent flags, and explicit flags over the job.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "detect_options.h"
#include "job.h"
#include "measure_run.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter::cli {
namespace {

using testing::RunPlatemeter;
using testing::TempDir;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// The ```toml block of docs/job.md.
std::string DocsExample() {
  const std::string doc = ReadText(std::string(PLATEMETER_SOURCE_DIR) + "/docs/job.md");
  const size_t begin = doc.find("```toml\n");
  const size_t end = doc.find("```", begin + 8);
  if (begin == std::string::npos || end == std::string::npos) return "";
  return doc.substr(begin + 8, end - begin - 8);
}

// The keys the docs' tables document: `key` in the first column, prefixed by the table the
// paragraph before the table names ("`[stars]`: ...").
std::set<std::string> DocumentedKeys() {
  std::istringstream doc(ReadText(std::string(PLATEMETER_SOURCE_DIR) + "/docs/job.md"));
  std::set<std::string> keys;
  std::string table, line;
  static const std::regex kTableIntro(R"(^`\[(\w+)\]`:.*)"), kRow(R"(^\| `(\w+)` \|.*)");
  bool in_keys = false;
  for (std::smatch m; std::getline(doc, line);) {
    if (line.rfind("## ", 0) == 0) in_keys = line == "## Keys";
    if (!in_keys) continue;
    if (std::regex_match(line, m, kTableIntro)) table = m[1].str() + ".";
    if (std::regex_match(line, m, kRow)) keys.insert(table + m[1].str());
  }
  return keys;
}

// The keys the example sets (simple TOML: "[table]" lines and "key = value" lines).
std::set<std::string> ExampleKeys(const std::string& example) {
  std::istringstream in(example);
  std::set<std::string> keys;
  std::string table, line;
  static const std::regex kTable(R"(^\[(\w+)\]\s*$)"), kKey(R"(^(\w+) = .*)");
  for (std::smatch m; std::getline(in, line);) {
    if (std::regex_match(line, m, kTable)) table = m[1].str() + ".";
    if (std::regex_match(line, m, kKey)) keys.insert(table + m[1].str());
  }
  return keys;
}

TEST(CliJob, DocsExampleLoadsAndEveryDocumentedKeyReachesTheRequest) {
  TempDir dir;
  const std::string example = DocsExample();
  ASSERT_FALSE(example.empty());
  WriteText(dir.file("job.toml"), example);
  const JobDefinition job = LoadJobFile(dir.file("job.toml"));
  EXPECT_EQ(job.source, dir.file("job.toml"));

  // The docs document exactly the keys the example sets, and the overrides accept them all.
  const std::set<std::string> documented = DocumentedKeys();
  EXPECT_EQ(documented.size(), 28u);
  std::set<std::string> all_but_grid = documented;  // grid excludes camera: loaded on its own below
  all_but_grid.erase("grid");
  EXPECT_EQ(ExampleKeys(example), all_but_grid);
  std::set<std::string> overridable;
  for (const std::string& k : JobOverrideKeys()) overridable.insert(k.find('.') == std::string::npos && documented.count("measure." + k) ? "measure." + k : k);
  EXPECT_EQ(overridable, documented);

  // Every value of the example, none of them the default (so each key had to do something).
  const MeasureRequest defaults;
  const MeasureRequest& r = job.measure;
  const DetectRequest& d = r.detect;
  EXPECT_EQ(d.camera, "sn004-stellar");
  EXPECT_EQ(d.grid, "");
  EXPECT_EQ(d.pixel_size_um, 10.0);
  EXPECT_EQ(d.orientation, "0");
  EXPECT_FALSE(d.allow_ambiguous);
  EXPECT_TRUE(d.stars);
  EXPECT_FALSE(d.stars_bright);
  EXPECT_EQ(d.star_fwhm_px, 1.8);
  ASSERT_TRUE(d.trails);
  EXPECT_EQ(d.trails->start_utc, "1972-05-12T05:30:00Z");
  EXPECT_EQ(d.trails->leading_dashes, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(d.trails->break_s, 540.0);
  EXPECT_TRUE(d.trails->require_joined);
  EXPECT_FALSE(d.trails->forced_dots);
  ASSERT_TRUE(d.passpoints);
  EXPECT_EQ(d.passpoints->list_file, dir.file("passpoints.csv"));  // relative to the job file
  EXPECT_EQ(d.passpoints->shape, "ring");
  EXPECT_EQ(d.passpoints->diameter_um, 250.0);
  EXPECT_EQ(d.passpoints->line_width_um, 30.0);
  EXPECT_EQ(d.passpoints->polarity, "bright");
  EXPECT_EQ(r.temperature_degC, 22.0);
  EXPECT_EQ(r.emulsion_depth_um, 21.0);
  EXPECT_EQ(r.refractive_index, 1.6);
  EXPECT_EQ(r.model, "affine");
  EXPECT_EQ(r.rejection_threshold, 3.5);
  EXPECT_EQ(r.tolerance_um, 4.0);
  EXPECT_TRUE(r.no_local);
  EXPECT_TRUE(r.fiducial_orientation);
  EXPECT_EQ(r.fiducial_model, "similarity");
  EXPECT_EQ(r.min_cross_fraction, 0.6);
  EXPECT_NE(r.refractive_index, defaults.refractive_index);
  EXPECT_NE(r.model, defaults.model);
  EXPECT_NE(r.fiducial_model, defaults.fiducial_model);
  EXPECT_TRUE(r.detect.scan.empty());
  EXPECT_TRUE(r.out_dir.empty());

  WriteText(dir.file("grid.toml"), "grid = \"orbigon-reseau\"\n");
  EXPECT_EQ(LoadJobFile(dir.file("grid.toml")).measure.detect.grid, "orbigon-reseau");
}

// LoadJobFile's error for `text`, or "" when it loads.
std::string LoadError(const TempDir& dir, const std::string& text) {
  WriteText(dir.file("job.toml"), text);
  try {
    LoadJobFile(dir.file("job.toml"));
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), dir.file("job.toml"));
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.what();
  }
  return "";
}

TEST(CliJob, BadFilesNameTheFileAndTheLine) {
  TempDir dir;
  const std::string head = "camera = \"orbigon\"\n";
  auto expect = [&](const std::string& text, const std::string& line_and_part) {
    const std::string error = LoadError(dir, text);
    EXPECT_NE(error.find(dir.file("job.toml") + ": " + line_and_part), std::string::npos) << text << "\n-> " << error;
  };
  expect(head + "camra = \"x\"\n", "line 2: unknown key 'camra'");
  expect(head + "[measure]\nmodel = \"affine\"\ntemperature = 22\n", "line 4: unknown key 'measure.temperature'");
  expect(head + "[stars]\nfwhm = 2\n", "line 3: unknown key 'stars.fwhm'");
  expect(head + "[camera_settings]\nx = 1\n", "line 2: unknown key 'camera_settings'");
  expect(head + "pixel_size_um = \"ten\"\n", "line 2: key 'pixel_size_um' must be a number");
  expect(head + "[measure]\nlocal_reseau = \"no\"\n", "line 3: key 'measure.local_reseau' must be true or false");
  expect(head + "\norientation = \"45\"\n", "line 3: key 'orientation' = '45' is not one of 0 90 180 270");
  expect(head + "orientation = 90\n", "line 2: key 'orientation' must be a string");
  expect(head + "[measure]\nmodel = \"scale\"\n", "line 3: key 'measure.model' = 'scale' must be one of");
  expect(head + "[measure]\ntemperature_degC = 500\n", "line 3: key 'measure.temperature_degC' = 500 must lie in");
  expect(head + "[trails]\nstart_utc = \"12 May 1972\"\n", "line 3: key 'trails.start_utc'");
  expect(head + "[trails]\nstart_utc = \"1972-05-12T05:30:00Z\"\nleading_dashes = [2, 2]\n",
         "line 4: key 'trails.leading_dashes' gives an invalid trail program");
  expect(head + "\n[trails]\nbreak_s = 500\n", "line 3: [trails] needs start_utc");
  expect(head + "[passpoints]\nshape = \"ring\"\ndiameter_um = 250\n", "line 2: [passpoints] shape \"ring\" needs line_width_um");
  expect(head + "grid = \"orbigon-reseau\"\n", "line 2: give camera or grid, not both");
  expect(head + "stars = 1\n", "line 2: 'stars' must be a table");
  expect(head + "pixel_size_um = \n", "line 2: ");  // TOML syntax
  EXPECT_EQ(LoadError(dir, head + "[measure]\nmodel = \"affine\"\n"), "");

  try {
    LoadJobFile(dir.file("absent.toml"));
    ADD_FAILURE() << "a missing job file loaded";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), dir.file("absent.toml") + ": no such job file");
  }
  try {
    LoadJobFile(dir.path().string());
    ADD_FAILURE() << "a folder loaded as a job file";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), dir.path().string());
  }
}

TEST(CliJob, OverridesSetOneKeyFromText) {
  JobDefinition job;
  ApplyJobOverride(job, "orientation", "90m");
  ApplyJobOverride(job, "temperature_degC", "21.5");
  ApplyJobOverride(job, "trails.start_utc", "1972-05-12T05:30:00Z");
  ApplyJobOverride(job, "trails.leading_dashes", "3,5");
  ApplyJobOverride(job, "pixel_size_um", "12.5");
  ApplyJobOverride(job, "local_reseau", "false");
  ApplyJobOverride(job, "passpoints.list_file", "lists/p.csv");
  EXPECT_EQ(job.measure.detect.orientation, "90m");
  EXPECT_EQ(job.measure.temperature_degC, 21.5);
  ASSERT_TRUE(job.measure.detect.trails);
  EXPECT_EQ(job.measure.detect.trails->start_utc, "1972-05-12T05:30:00Z");
  EXPECT_EQ(job.measure.detect.trails->leading_dashes, (std::vector<int>{3, 5}));
  EXPECT_EQ(job.measure.detect.pixel_size_um, 12.5);
  EXPECT_TRUE(job.measure.no_local);
  EXPECT_EQ(job.measure.detect.passpoints->list_file, "lists/p.csv");  // as given

  // An empty cell clears an optional key.
  ApplyJobOverride(job, "temperature_degC", "");
  ApplyJobOverride(job, "orientation", "");
  EXPECT_FALSE(job.measure.temperature_degC);
  EXPECT_EQ(job.measure.detect.orientation, "");

  auto error = [&job](const std::string& key, const std::string& value) -> std::string {
    try {
      ApplyJobOverride(job, key, value);
    } catch (const Error& e) {
      EXPECT_EQ(e.subject(), "manifest");
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("orientation", "45"), "manifest: key 'orientation' = '45' is not one of 0 90 180 270 0m 90m 180m 270m");
  EXPECT_EQ(error("temperature_degC", "warm"), "manifest: key 'temperature_degC' = 'warm' must be a number");
  EXPECT_EQ(error("temperature_degC", "21.5C"), "manifest: key 'temperature_degC' = '21.5C' must be a number");
  EXPECT_EQ(error("pixel_size_um", "-3"), "manifest: key 'pixel_size_um' = -3 must lie in 0.01..10000");
  EXPECT_EQ(error("stars.enabled", "yes"), "manifest: key 'stars.enabled' = 'yes' must be true or false");
  EXPECT_NE(error("trails.leading_dashes", "2,x").find("must be integers"), std::string::npos);
  EXPECT_NE(error("trails.start_utc", "yesterday").find("key 'trails.start_utc'"), std::string::npos);
  EXPECT_NE(error("temperature", "20").find("manifest: unknown column 'temperature' (job keys: camera, grid,"), std::string::npos);
  EXPECT_NE(error("measure.temperature_degC", "20").find("unknown column"), std::string::npos);
  JobDefinition plain;
  EXPECT_THROW(ApplyJobOverride(plain, "trails.leading_dashes", "2,2"), Error);
  EXPECT_FALSE(plain.measure.detect.trails);
  EXPECT_EQ(job.measure.detect.orientation, "");  // a failed override changes nothing
  EXPECT_EQ(job.measure.detect.trails->leading_dashes, (std::vector<int>{3, 5}));
}

TEST(CliJob, TheFingerprintHasEveryOutputChangingOption) {
  TempDir dir;
  WriteText(dir.file("job.toml"), DocsExample());
  WriteText(dir.file("passpoints.csv"), "id,x_px,y_px\nP1,100,200\n");
  JobDefinition job = LoadJobFile(dir.file("job.toml"));
  const std::string text = CanonicalOptionsText(job.measure);
  EXPECT_EQ(text, CanonicalOptionsText(LoadJobFile(dir.file("job.toml")).measure));  // deterministic
  EXPECT_EQ(text.rfind("software = \"platemeter ", 0), 0u) << text;

  // Not the scan or the output folder.
  MeasureRequest moved = job.measure;
  moved.detect.scan = "other.tif";
  moved.out_dir = "elsewhere";
  EXPECT_EQ(CanonicalOptionsText(moved), text);

  // Each key changed alone changes the text.
  const std::vector<std::pair<std::string, std::string>> changes = {
      {"camera", "orbigon"}, {"grid", "orbigon-reseau"}, {"pixel_size_um", "10.000001"}, {"orientation", "0m"},
      {"allow_ambiguous_orientation", "true"}, {"stars.enabled", "false"}, {"stars.bright", "true"},
      {"stars.fwhm_px", "1.9"}, {"trails.start_utc", "1972-05-12T05:30:01Z"}, {"trails.leading_dashes", "2,3,5"},
      {"trails.break_s", "541"}, {"trails.require_joined", "false"}, {"trails.forced_dots", "true"}, {"passpoints.list_file", dir.file("other.csv")},
      {"passpoints.shape", "dot"},
      {"passpoints.diameter_um", "251"}, {"passpoints.line_width_um", "31"}, {"passpoints.polarity", "dark"},
      {"temperature_degC", "22.5"}, {"emulsion_depth_um", "20"}, {"refractive_index", "1.65"}, {"model", "scales"},
      {"rejection_threshold", "4"}, {"tolerance_um", "5"}, {"local_reseau", "true"}, {"fiducial_orientation", "false"},
      {"fiducial_model", "affine"}, {"min_cross_fraction", "0.5"}};
  std::set<std::string> changed_keys;
  for (const auto& [key, value] : changes) {
    JobDefinition changed = job;
    ApplyJobOverride(changed, key, value);
    EXPECT_NE(CanonicalOptionsText(changed.measure), text) << key;
    changed_keys.insert(key);
  }
  EXPECT_EQ(changed_keys, std::set<std::string>(JobOverrideKeys().begin(), JobOverrideKeys().end()));

  // The passpoint list's content, not just its name.
  WriteText(dir.file("passpoints.csv"), "id,x_px,y_px\nP1,100,201\n");
  EXPECT_NE(CanonicalOptionsText(job.measure), text);
  // Optional values: absent differs from any value.
  MeasureRequest plain = job.measure;
  plain.temperature_degC.reset();
  EXPECT_NE(CanonicalOptionsText(plain), text);
  plain.detect.trails.reset();
  plain.detect.passpoints.reset();
  EXPECT_NE(CanonicalOptionsText(plain).find("trails = none\n"), std::string::npos);
}

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
  WriteText(dir.file("job.toml"), DocsExample());
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

// The simulator's Orbigon plate (121 crosses; seed 001's 22 degC and 21 um emulsion) at 40 um pixels.
sim::SimulatedPlate OrbigonPlate(const std::string& extra_spec = "") {
  const std::string spec =
      "name = \"orbigon\"\ncamera = \"orbigon\"\nseed = 5\n[output]\npixel_size_um = 40.0\nmargin_mm = 1.0\n"
      "[thermal]\ntemperature_degC = 22.0\n[emulsion]\ndepth_um = 21.0\n"
      "[noise]\nblur_sigma_um = 8.0\nsensor_sigma_dn = 100.0\n" + extra_spec;
  const DefinitionRegistry registry;
  return sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "spec"), registry);
}

// Detect's measurement file made from the simulator's truth (no render, no detection: fast); `measured`
// crosses measured at 0.05 px, the others missing.
std::string TruthMeasurementFile(const TempDir& dir, int measured = 121) {
  const sim::SimulatedPlate plate = OrbigonPlate();
  MeasurementFile file;
  file.header.plate_id = "orbigon";
  file.header.camera = "orbigon";
  file.header.pixel_size_um = 40.0;
  for (MeasuredPoint p : plate.truth) {
    if (p.kind != PointKind::kReseau) continue;
    const bool keep = measured-- > 0;
    p.status = keep ? PointStatus::kMeasured : PointStatus::kMissing;
    p.sigma_x_px = p.sigma_y_px = keep ? std::optional<double>(0.05) : std::nullopt;
    if (!keep) p.x_px = p.y_px = std::nullopt;
    p.x_mm = p.y_mm = p.sigma_x_mm = p.sigma_y_mm = std::nullopt;
    p.crb_x_px = p.crb_y_px = p.crb_xy_corr = std::nullopt;
    p.flags.clear();
    file.points.push_back(p);
  }
  const std::string path = dir.file("orbigon.measurements.csv");
  WriteMeasurementFile(path, file);
  return path;
}

std::string CorrectionParameter(const MeasurementFile& file, const std::string& correction, const std::string& key) {
  for (const AppliedCorrection& c : file.header.corrections)
    for (const auto& [k, v] : c.parameters)
      if (c.name == correction && k == key) return v;
  return "";
}

TEST(CliJobMeasure, WithAJobItWritesWhatTheEquivalentFlagsWrite) {
  TempDir dir;
  const std::string scan = TruthMeasurementFile(dir);
  WriteText(dir.file("job.toml"),
            "camera = \"orbigon\"\norientation = \"0\"\n[measure]\ntemperature_degC = 22.0\nemulsion_depth_um = 21.0\n"
            "model = \"affine\"\nlocal_reseau = false\ntolerance_um = 3.0\n");
  const auto flags = RunPlatemeter("measure '" + scan + "' --camera orbigon --orientation 0 --temperature-degC 22 "
                                   "--emulsion-depth-um 21 --model affine --no-local-reseau --tolerance-um 3 -o '" +
                                   dir.file("flags") + "'");
  ASSERT_EQ(flags.exit_code, 0) << flags.err;
  const auto job = RunPlatemeter("measure '" + scan + "' --job '" + dir.file("job.toml") + "' -o '" + dir.file("job") + "'");
  ASSERT_EQ(job.exit_code, 0) << job.err;
  const std::string a = ReadText(dir.file("flags/orbigon.measurements.csv"));
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(ReadText(dir.file("job/orbigon.measurements.csv")), a);
  EXPECT_EQ(ReadText(dir.file("job/orbigon.measure.json")), ReadText(dir.file("flags/orbigon.measure.json")));
  // And they are what the job asked for: thermal, emulsion, an affine fit, no local step.
  const MeasurementFile file = ReadMeasurementFile(dir.file("job/orbigon.measurements.csv"));
  std::vector<std::string> names;
  for (const AppliedCorrection& c : file.header.corrections) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"comparator", "thermal", "emulsion_depth", "reseau_fit"}));
  EXPECT_EQ(CorrectionParameter(file, "reseau_fit", "model"), "affine");
  const nlohmann::json report = nlohmann::json::parse(ReadText(dir.file("job/orbigon.measure.json")));
  EXPECT_EQ(report["reseau"]["tolerance_um"], 3.0);
  // The console text differs only by the output folder.
  EXPECT_EQ(std::regex_replace(job.out, std::regex(dir.file("job")), "OUT"),
            std::regex_replace(flags.out, std::regex(dir.file("flags")), "OUT"));
}

TEST(CliJobMeasure, ExplicitFlagsOverrideTheJob) {
  TempDir dir;
  const std::string scan = TruthMeasurementFile(dir);
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

TEST(CliJobMeasure, RunMeasureSummarizesWhatItWrote) {
  TempDir dir;
  MeasureRequest request;
  request.detect.scan = TruthMeasurementFile(dir, 119);
  request.detect.camera = "orbigon";
  request.temperature_degC = 22.0;
  request.emulsion_depth_um = 21.0;  // the simulated plate's
  request.out_dir = dir.file("out");
  const DefinitionRegistry registry;
  const MeasureSummary summary = RunMeasure(request, registry);
  EXPECT_EQ(summary.plate_id, "orbigon");
  EXPECT_EQ(summary.counts_by_kind, (std::map<std::string, int>{{"reseau", 121}}));
  EXPECT_EQ(summary.counts_by_status, (std::map<std::string, int>{{"measured", 119}, {"missing", 2}}));
  ASSERT_TRUE(summary.reseau_rms_um && summary.scale_x && summary.scale_y);
  const nlohmann::json report = nlohmann::json::parse(ReadText(dir.file("out/orbigon.measure.json")));
  EXPECT_DOUBLE_EQ(*summary.reseau_rms_um, report["reseau"]["rms_um"].get<double>());
  EXPECT_DOUBLE_EQ(*summary.scale_x, report["reseau"]["scale_x"]["value"].get<double>());
  EXPECT_DOUBLE_EQ(*summary.scale_y, report["reseau"]["scale_y"]["value"].get<double>());
  // Exact positions, the simulated temperature and emulsion depth corrected: the nominal grid.
  EXPECT_NEAR(*summary.scale_x, 1.0, 1e-6);
  EXPECT_NEAR(*summary.scale_y, 1.0, 1e-6);
  EXPECT_LT(*summary.reseau_rms_um, 0.1);
  const std::vector<std::string> expected = {"orbigon.measurements.csv", "orbigon.micmac.xml", "orbigon.residuals.png",
                                             "orbigon.measure.json"};
  ASSERT_EQ(summary.written_files.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(summary.written_files[i], std::filesystem::absolute(dir.file("out/" + expected[i])).string());
    EXPECT_TRUE(std::filesystem::exists(summary.written_files[i]));
  }
  EXPECT_EQ(summary.report_json, summary.written_files[3]);
  EXPECT_EQ(summary.plot_png, summary.written_files[2]);
  EXPECT_EQ(summary.message, "reseau fit (scales): 119 crosses, 0 rejected, rms " +
                                 [&] { std::ostringstream s; s << *summary.reseau_rms_um; return s.str(); }() + " um\n" +
                                 dir.file("out/orbigon.measurements.csv") + "\n" + dir.file("out/orbigon.measure.json") +
                                 "\n" + dir.file("out/orbigon.residuals.png") + "\n" + dir.file("out/orbigon.micmac.xml") + "\n");
}

// RunMeasure's error for `request`, "" when it succeeds.
std::string RunMeasureError(const MeasureRequest& request) {
  const DefinitionRegistry registry;
  try {
    RunMeasure(request, registry);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.what();
  }
  return "";
}

TEST(CliJobMeasure, TooFewCrossesOrTheWrongCameraFailNamingTheScan) {
  TempDir dir;
  MeasureRequest request;
  request.detect.scan = TruthMeasurementFile(dir, 4);  // 4 crosses: a fit, but one that extrapolates over the plate
  request.detect.camera = "orbigon";
  request.out_dir = dir.file("out");
  EXPECT_EQ(RunMeasureError(request), request.detect.scan +
                                          ": only 4 of the 121 crosses of grid 'orbigon-reseau' usable for the reseau fit, 61 "
                                          "needed (min_cross_fraction 0.5): wrong camera or pixel size, or most crosses "
                                          "hidden or damaged");
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
  request.min_cross_fraction = 0.03;  // 4 of 121 accepted when asked for
  EXPECT_EQ(RunMeasureError(request), "");

  request.detect.scan = TruthMeasurementFile(dir);
  request.detect.camera = "sn004-stellar";
  EXPECT_EQ(RunMeasureError(request), request.detect.scan + ": was detected with camera 'orbigon', not 'sn004-stellar'");
}

// A rendered scan, for what needs the detector.
class CliJobScan : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    scan_ = sim::WriteSimulatedPlate(OrbigonPlate(), dir_->path().string()).image_path;
  }
  static void TearDownTestSuite() { delete dir_; }
  static TempDir* dir_;
  static std::string scan_;
};
TempDir* CliJobScan::dir_ = nullptr;
std::string CliJobScan::scan_;

TEST_F(CliJobScan, DetectTakesTheJobAndTheFlagsOverIt) {
  TempDir dir;
  // The job's camera, its wrong orientation corrected on the command line.
  WriteText(dir.file("job.toml"), "camera = \"orbigon\"\norientation = \"90m\"\n");
  const auto result = RunPlatemeter("detect '" + scan_ + "' --job '" + dir.file("job.toml") + "' --orientation 0 -o '" +
                                    dir.file("out") + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const MeasurementFile file = ReadMeasurementFile(dir.file("out/orbigon.measurements.csv"));
  EXPECT_EQ(file.header.camera, "orbigon");
  EXPECT_EQ(file.points.size(), 121u);
  int measured = 0;
  for (const MeasuredPoint& p : file.points) measured += p.status == PointStatus::kMeasured;
  EXPECT_GE(measured, 119);
  const nlohmann::json summary = nlohmann::json::parse(ReadText(dir.file("out/orbigon.detect.json")));
  EXPECT_EQ(summary["orientation"], "0");
  // A bad job is one line naming it, and nothing is written.
  WriteText(dir.file("bad.toml"), "camera = \"orbigon\"\norientaton = \"0\"\n");
  const auto bad = RunPlatemeter("detect '" + scan_ + "' --job '" + dir.file("bad.toml") + "' -o '" + dir.file("bad") + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err, "platemeter: error: " + dir.file("bad.toml") + ": line 2: unknown key 'orientaton' (docs/job.md lists the keys)\n");
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad")));
}

TEST_F(CliJobScan, RunMeasureFailuresNameTheScan) {
  TempDir dir;
  MeasureRequest request;
  request.detect.camera = "orbigon";
  request.detect.orientation = "0";
  request.out_dir = dir.file("out");
  // A truncated scan.
  const std::string truncated = dir.file("truncated.tif");
  std::filesystem::copy_file(scan_, truncated);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(scan_) / 2);
  request.detect.scan = truncated;
  const std::string error = RunMeasureError(request);
  EXPECT_EQ(error.rfind(truncated + ": ", 0), 0u) << error;
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  // The scan of another camera: the SN-004 stellar camera's 5 x 5 crosses at 5 mm match few of the
  // Orbigon's 11 x 11 at 10 mm.
  request.detect.scan = scan_;
  request.detect.camera = "sn004-stellar";
  const std::string wrong = RunMeasureError(request);
  EXPECT_EQ(wrong.rfind(scan_ + ": ", 0), 0u) << wrong;
  EXPECT_NE(wrong.find("of the 25 crosses of grid 'ikotar-b' usable for the reseau fit, 13 needed"), std::string::npos) << wrong;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

}  // namespace
}  // namespace platemeter::cli
