// platemeter grids list|show and cameras list|show, through the binary.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "grids/seed_text.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using ::testing::HasSubstr;
using testing::RunPlatemeter;
using testing::TempDir;

std::vector<std::string> Lines(const std::string& text) { return testing::SplitLines(text); }

void ExpectCsvMatchesSeedTable(const std::string& name, const std::map<std::string, testing::SeedPoint>& seed) {
  const auto result = RunPlatemeter("grids show " + name + " --format csv");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto lines = Lines(result.out);
  ASSERT_EQ(lines.size(), seed.size() + 1) << name;
  EXPECT_EQ(lines[0], "id,x_mm,y_mm");
  for (size_t k = 1; k < lines.size(); ++k) {
    std::stringstream row(lines[k]);
    std::string id, x, y;
    std::getline(row, id, ',');
    std::getline(row, x, ',');
    std::getline(row, y, ',');
    ASSERT_TRUE(seed.count(id)) << lines[k];
    EXPECT_EQ(std::stod(x), seed.at(id).x_mm) << lines[k];
    EXPECT_EQ(std::stod(y), seed.at(id).y_mm) << lines[k];
  }
}

TEST(GridsCli, ShowPrintsEveryCrossAsCsv) {
  ExpectCsvMatchesSeedTable("ikogon-b", testing::SeedCrossTable("A.1"));
  ExpectCsvMatchesSeedTable("ikotar-b", testing::SeedCrossTable("A.3"));
  ExpectCsvMatchesSeedTable("sn004-terrain-fiducials", testing::SeedFiducialTable());
  const auto result = RunPlatemeter("grids show ikogon-b");  // csv is the default
  EXPECT_THAT(result.out, HasSubstr("\nX1Y1,-50.0014,-50.0019\n"));
  EXPECT_THAT(result.out, HasSubstr("\nX5Y2,-9.9990,-40.0022\n"));
}

TEST(GridsCli, ListShowsEveryDefinitionWithItsPointCount) {
  const auto result = RunPlatemeter("grids list");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  auto row_of = [&](const std::string& name) {
    for (const std::string& line : Lines(result.out)) {
      std::stringstream fields(line);
      std::string kind, row_name, count;
      fields >> kind >> row_name >> count;
      if (row_name == name) return kind + " " + count;
    }
    return std::string("absent");
  };
  EXPECT_EQ(row_of("ikogon-b"), "grid 121");
  EXPECT_EQ(row_of("ikotar-b"), "grid 25");
  EXPECT_EQ(row_of("orbigon-reseau"), "grid 121");
  EXPECT_EQ(row_of("sn004-terrain-fiducials"), "fiducial_set 8");
  EXPECT_EQ(row_of("sn004-terrain"), "camera 129");
  EXPECT_EQ(row_of("sn004-stellar"), "camera 25");
  EXPECT_EQ(row_of("orbigon"), "camera 121");
  EXPECT_EQ(row_of("hasselblad-500"), "camera 4");
  EXPECT_EQ(row_of("hasselblad-80"), "camera 4");
  const auto cameras = RunPlatemeter("cameras list");
  EXPECT_EQ(cameras.exit_code, 0);
  EXPECT_EQ(Lines(cameras.out).size(), 6u);
}

TEST(GridsCli, CamerasShowPrintsToml) {
  const auto result = RunPlatemeter("cameras show sn004-terrain");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_THAT(result.out, HasSubstr("[[camera]]\nname = \"sn004-terrain\"\n"));
  EXPECT_THAT(result.out, HasSubstr("grid = \"ikogon-b\"\n"));
  EXPECT_THAT(result.out, HasSubstr("K1_per_mm2 = -1.278842e-06\n"));
  EXPECT_THAT(result.out, HasSubstr("principal_distance_mm = 75.8069\n"));
}

// `grids show X --format toml` loaded back under a new name equals the original.
TEST(GridsCli, TomlRoundTripThroughDefinitionsFile) {
  TempDir dir;
  for (const std::string name : {"ikogon-b", "ikotar-b", "orbigon-reseau", "sn004-terrain-fiducials"}) {
    const auto toml = RunPlatemeter("grids show " + name + " --format toml");
    ASSERT_EQ(toml.exit_code, 0) << toml.err;
    std::string text = toml.out;
    const std::string from = "name = \"" + name + "\"";
    ASSERT_NE(text.find(from), std::string::npos);
    text.replace(text.find(from), from.size(), "name = \"copy-of-" + name + "\"");
    const std::string path = dir.file(name + ".toml");
    std::ofstream(path) << text;
    const auto copy = RunPlatemeter("--definitions '" + path + "' grids show copy-of-" + name + " --format csv");
    ASSERT_EQ(copy.exit_code, 0) << copy.err;
    EXPECT_EQ(copy.err, "");
    EXPECT_EQ(copy.out, RunPlatemeter("grids show " + name + " --format csv").out) << name;
    const auto copy_toml = RunPlatemeter("--definitions '" + path + "' grids show copy-of-" + name + " --format toml");
    EXPECT_EQ(copy_toml.out, text) << name;
  }
}

// A bad input: a non-zero exit and exactly one line on stderr naming `subject`
// and `problem` (besides warnings about earlier files, which are lines of their own).
void ExpectOneLineError(const testing::CommandResult& result, const std::string& subject,
                        const std::string& problem) {
  EXPECT_NE(result.exit_code, 0);
  EXPECT_EQ(result.out, "");
  int other_lines = 0;
  for (const std::string& line : Lines(result.err)) other_lines += line.rfind("warning: ", 0) == 0 ? 0 : 1;
  EXPECT_EQ(other_lines, 1) << result.err;
  EXPECT_EQ(result.err.back(), '\n');
  EXPECT_THAT(result.err, HasSubstr("platemeter: error: "));
  EXPECT_THAT(result.err, HasSubstr(subject));
  EXPECT_THAT(result.err, HasSubstr(problem));
}

TEST(GridsCli, UnknownNamesFail) {
  ExpectOneLineError(RunPlatemeter("grids show ikogon-z"), "ikogon-z", "unknown grid or fiducial set");
  ExpectOneLineError(RunPlatemeter("cameras show apollo"), "apollo", "unknown camera");
}

const char* kGood = R"toml([[grid]]
name = "mine"
description = "a user grid"
source = "test"
columns = 2
rows = 1
mark = { type = "cross", line_width_um = 20.0, arm_length_um = 600.0 }
points = [
  ["X1Y1", -1.0, 0.0],
  ["X2Y1", 1.0, 0.0],
]
)toml";

std::string WriteFile(const TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

std::string With(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(GridsCli, BadDefinitionFilesFailWithOneLine) {
  TempDir dir;
  auto run = [&](const std::string& file, const std::string& text) {
    return RunPlatemeter("--definitions '" + WriteFile(dir, file, text) + "' grids list");
  };
  ASSERT_EQ(run("good.toml", kGood).exit_code, 0);
  ExpectOneLineError(run("malformed.toml", With(kGood, "rows = 1", "rows = = 1")), "malformed.toml",
                     "line 6: malformed TOML");
  ExpectOneLineError(run("duplicate.toml", With(kGood, "\"X2Y1\"", "\"X1Y1\"")), "duplicate.toml",
                     "line 10: grid 'mine': duplicate point id 'X1Y1'");
  ExpectOneLineError(run("typo.toml", With(kGood, "columns = 2", "columns = 2\ncolums = 2")), "typo.toml",
                     "line 6: grid 'mine': unknown key 'colums'");
  const std::string camera = std::string(kGood) + R"toml(
[[camera]]
name = "cam"
description = "d"
source = "s"
format_width_mm = 10.0
format_height_mm = 10.0
nominal_principal_distance_mm = 20.0
grid = "mien"
)toml";
  ExpectOneLineError(run("camera.toml", camera), "camera.toml", "camera 'cam': unknown grid 'mien'");
  ExpectOneLineError(run("camera2.toml", With(camera, "grid = \"mien\"", "grid = \"mine\"\ngrid = \"x\"")),
                     "camera2.toml", "malformed TOML");
  EXPECT_EQ(run("camera3.toml", With(camera, "grid = \"mien\"", "grid = \"mine\"")).exit_code, 0);
}

TEST(GridsCli, ReplacingABuiltInWarnsAndTwoUserDefinitionsFail) {
  TempDir dir;
  const std::string mine = WriteFile(dir, "ikotar.toml", With(kGood, "\"mine\"", "\"ikotar-b\""));
  const auto replaced = RunPlatemeter("--definitions '" + mine + "' grids show ikotar-b");
  EXPECT_EQ(replaced.exit_code, 0);
  EXPECT_EQ(Lines(replaced.out).size(), 3u);
  EXPECT_THAT(replaced.err, HasSubstr("replaces the built-in"));
  const std::string again = WriteFile(dir, "again.toml", With(kGood, "\"mine\"", "\"ikotar-b\""));
  ExpectOneLineError(RunPlatemeter("--definitions '" + mine + "' --definitions '" + again + "' grids list"),
                     "again.toml", "already defined in " + mine);
}

}  // namespace
}  // namespace platemeter
