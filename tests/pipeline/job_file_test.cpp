// Job definition files (pipeline/job_file.h, docs/job.md): the documented example
// loads and every key reaches the request; bad files name the file and the line;
// per-scan overrides; the options fingerprint (CanonicalOptionsText).
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/pipeline/job_file.h"
#include "platemeter/pipeline/measure_run.h"
#include "support/job_plates.h"
#include "support/test_support.h"

namespace platemeter::pipeline {
namespace {

using testing::JobDocsExample;
using testing::ReadTextFile;
using testing::TempDir;

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// The keys the docs' tables document: `key` in the first column, prefixed by the table the
// paragraph before the table names ("`[stars]`: ...").
std::set<std::string> DocumentedKeys() {
  std::istringstream doc(ReadTextFile(std::string(PLATEMETER_SOURCE_DIR) + "/docs/job.md"));
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

TEST(JobFile, DocsExampleLoadsAndEveryDocumentedKeyReachesTheRequest) {
  TempDir dir;
  const std::string example = JobDocsExample();
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

TEST(JobFile, BadFilesNameTheFileAndTheLine) {
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

TEST(JobFile, OverridesSetOneKeyFromText) {
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

TEST(JobFile, TheFingerprintHasEveryOutputChangingOption) {
  TempDir dir;
  WriteText(dir.file("job.toml"), JobDocsExample());
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

// ---------------------------------------------------------------------------
// Issue #28: numbers range-checked where they enter; the text variant the fuzz
// harness (tests/fuzz) reads.

std::string ParseError(const std::string& text) {
  try {
    ParseJobFile(text, "job.toml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(JobFileRanges, HugeLeadingDashCountIsRefusedNotWrappedToMinusOne) {
  // Reported: leading_dashes = [2^63-1] was reported as "-1 leading dashes".
  const std::string head = "camera = \"orbigon\"\n[trails]\nstart_utc = \"1972-05-12T05:30:00Z\"\n";
  EXPECT_EQ(ParseError(head + "leading_dashes = [9223372036854775807]\n"),
            "job.toml: line 4: key 'trails.leading_dashes' holds 9223372036854775807, outside the accepted range 2..5");
  EXPECT_EQ(ParseError(head + "leading_dashes = [2, 4294967298]\n"),
            "job.toml: line 4: key 'trails.leading_dashes' holds 4294967298, outside the accepted range 2..5");
  JobDefinition job;
  try {
    ApplyJobOverride(job, "trails.leading_dashes", "2,9223372036854775807");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "manifest: key 'trails.leading_dashes' holds 9223372036854775807, outside the accepted range 2..5");
  }
  EXPECT_EQ(ParseError(head + "leading_dashes = [5, 2]\n"), "");
}

TEST(JobFileText, TheTextVariantReadsLikeTheFile) {
  TempDir dir;
  WriteText(dir.file("job.toml"), JobDocsExample());
  const JobDefinition from_file = LoadJobFile(dir.file("job.toml"));
  const JobDefinition from_text = ParseJobFile(JobDocsExample(), dir.file("job.toml"));
  EXPECT_EQ(from_text.source, from_file.source);
  EXPECT_EQ(from_text.measure.detect.passpoints->list_file, from_file.measure.detect.passpoints->list_file);
  EXPECT_EQ(from_text.measure.detect.trails->leading_dashes, (std::vector<int>{2, 3, 4}));
  // A byte order mark is accepted (toml++ skips it).
  EXPECT_EQ(ParseJobFile("\xEF\xBB\xBF" + JobDocsExample(), "job.toml").measure.detect.camera, "sn004-stellar");
}

// Fuzz finding (tests/fuzz, job_file): a start_utc of thousands of characters
// is refused before core's regex parser, which recurses per character.
TEST(JobFileText, FuzzFindingAHugeStartTimeIsRefusedBeforeParsing) {
  const std::string huge = "1972-05-12T05:30:00." + std::string(50000, '0') + "Z";
  EXPECT_EQ(ParseError("[trails]\nstart_utc = \"" + huge + "\"\n"),
            "job.toml: line 2: key 'trails.start_utc' is longer than 64 characters (not an ISO 8601 time)");
}

// libFuzzer finding (docs/fuzzing.md): a table header starting with '#' trips
// a debug assertion inside toml++ (parse_key); a release build must still
// report it as malformed TOML on one line.
TEST(JobFileText, LibFuzzerFindingATableHeaderStartingWithHashIsMalformed) {
  EXPECT_EQ(ParseError("grid = \"orbigon\"\n[# a comment]\n"),
            "job.toml: line 2: Error while parsing key: expected bare key starting character or string delimiter, saw '#'");
}

}  // namespace
}  // namespace platemeter::pipeline
