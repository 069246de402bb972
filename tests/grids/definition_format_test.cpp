// The TOML definition format: lattices, explicit lists, cameras, the writers'
// round trip, and the one-line errors for bad input (docs/definitions.md).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "platemeter/grids/registry.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using ::testing::HasSubstr;

const char* kUserFile = R"toml(
# A user camera with a 3 x 2 lattice and two fiducials.
[[grid]]
name = "test-lattice"
description = "3 x 2 lattice"
source = "test"
columns = 3
rows = 2
spacing_mm = 5.0
mark = { type = "dot", line_width_um = 10.0, arm_length_um = 100.0 }

[[fiducial_set]]
name = "test-fiducials"
description = "two"
source = "test"
mark = { type = "corner", line_width_um = 30.0, arm_length_um = 2000.0 }
points = [
  ["left", -20.5, 0.0],
  { id = "right", x_mm = 20.5, y_mm = 0, mark = { type = "ring", line_width_um = 5.0, arm_length_um = 50.0 } },
]

[[camera]]
name = "test-camera"
description = "test"
source = "test"
format_width_mm = 60.0
format_height_mm = 40.0
nominal_principal_distance_mm = 50
grid = "test-lattice"
fiducial_set = "test-fiducials"
calibration_temperature_degC = 21.5

[camera.lens]
model = "brown-balanced"
source = "test"
principal_distance_mm = 50.1
principal_point_x_um = 12.5
principal_point_y_mm = -0.003

[camera.lens.coefficients]
k0 = -1e-3
k1_per_mm2 = 2e-6
k2_per_mm4 = 0
p1_per_mm = 1e-7
p2_per_mm = -2e-7

[camera.lens.sigmas]
principal_point_x_um = 1.5
k0 = 1e-5
)toml";

TEST(DefinitionFormat, LatticeExpandsToColumnsFromTheLeftAndRowsFromTheBottom) {
  const DefinitionFile file = ReadDefinitions(kUserFile, "user.toml");
  ASSERT_EQ(file.grids.size(), 1u);
  const MasterGrid& grid = file.grids[0];
  ASSERT_EQ(grid.points.size(), 6u);
  // Centred: columns at -5, 0, +5 mm, rows at -2.5, +2.5 mm.
  EXPECT_EQ(grid.Find("X1Y1")->x_mm, -5.0);
  EXPECT_EQ(grid.Find("X1Y1")->y_mm, -2.5);
  EXPECT_EQ(grid.Find("X3Y1")->x_mm, 5.0);
  EXPECT_EQ(grid.Find("X2Y2")->x_mm, 0.0);
  EXPECT_EQ(grid.Find("X2Y2")->y_mm, 2.5);
  EXPECT_EQ(grid.Find("X4Y1"), nullptr);
  EXPECT_EQ(grid.mark.type, MarkType::kDot);
  EXPECT_EQ(grid.mark.arm_length_um, 100.0);
}

TEST(DefinitionFormat, OrbigonReseauIsTheNominal10mmLattice) {
  const DefinitionRegistry registry;
  const MasterGrid& grid = registry.Grid("orbigon-reseau");
  ASSERT_EQ(grid.points.size(), 121u);
  EXPECT_EQ(grid.Find("X1Y1")->x_mm, -50.0);
  EXPECT_EQ(grid.Find("X1Y1")->y_mm, -50.0);
  EXPECT_EQ(grid.Find("X6Y6")->x_mm, 0.0);
  EXPECT_EQ(grid.Find("X11Y3")->x_mm, 50.0);
  EXPECT_EQ(grid.Find("X11Y3")->y_mm, -30.0);
  EXPECT_EQ(grid.calibration_temperature_degC, 20.0);
}

TEST(DefinitionFormat, FiducialMarksAndCameraFields) {
  const DefinitionFile file = ReadDefinitions(kUserFile, "user.toml");
  const FiducialSet& set = file.fiducial_sets.at(0);
  EXPECT_EQ(set.Find("left")->mark.type, MarkType::kCorner);
  EXPECT_EQ(set.Find("right")->mark.type, MarkType::kRing);
  EXPECT_EQ(set.Find("right")->x_mm, 20.5);
  const CameraDefinition& camera = file.cameras.at(0);
  EXPECT_EQ(camera.format_height_mm, 40.0);
  EXPECT_EQ(camera.calibration_temperature_degC, 21.5);
  EXPECT_EQ(camera.glass_expansion_per_degC, 8.1e-6);  // documented default
  ASSERT_TRUE(camera.lens);
  EXPECT_EQ(camera.lens->principal_point_x_mm, 0.0125);  // given in um
  EXPECT_EQ(camera.lens->sigmas.at("principal_point_x_mm"), 0.0015);
  EXPECT_EQ(camera.lens->coefficients.at("k2_per_mm4"), 0.0);
}

template <typename T>
void ExpectSamePoints(const T& a, const T& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].id, b[k].id);
    EXPECT_EQ(a[k].x_mm, b[k].x_mm) << a[k].id;
    EXPECT_EQ(a[k].y_mm, b[k].y_mm) << a[k].id;
  }
}

TEST(DefinitionFormat, TomlWritersRoundTrip) {
  const DefinitionRegistry registry = DefinitionRegistry::FromTexts({{"user.toml", kUserFile}});
  std::string text;
  for (const std::string& name : registry.GridNames()) text += ToToml(registry.Grid(name)) + "\n";
  for (const std::string& name : registry.FiducialSetNames()) text += ToToml(registry.Fiducials(name)) + "\n";
  for (const std::string& name : registry.CameraNames()) text += ToToml(registry.Camera(name)) + "\n";
  const DefinitionFile back = ReadDefinitions(text, "written.toml");
  ASSERT_EQ(back.grids.size(), registry.GridNames().size());
  ASSERT_EQ(back.fiducial_sets.size(), registry.FiducialSetNames().size());
  ASSERT_EQ(back.cameras.size(), registry.CameraNames().size());
  for (const MasterGrid& grid : back.grids) {
    const MasterGrid& original = registry.Grid(grid.name);
    ExpectSamePoints(grid.points, original.points);
    EXPECT_EQ(grid.columns, original.columns);
    EXPECT_EQ(grid.rows, original.rows);
    EXPECT_EQ(grid.description, original.description);
    EXPECT_EQ(grid.source, original.source);
    EXPECT_EQ(grid.calibration_temperature_degC, original.calibration_temperature_degC);
    EXPECT_EQ(grid.mark.type, original.mark.type);
    EXPECT_EQ(grid.mark.line_width_um, original.mark.line_width_um);
  }
  for (const FiducialSet& set : back.fiducial_sets) {
    const FiducialSet& original = registry.Fiducials(set.name);
    ExpectSamePoints(set.marks, original.marks);
    for (size_t k = 0; k < set.marks.size(); ++k) {
      EXPECT_EQ(set.marks[k].mark.type, original.marks[k].mark.type);
      EXPECT_EQ(set.marks[k].mark.arm_length_um, original.marks[k].mark.arm_length_um);
    }
  }
  for (const CameraDefinition& camera : back.cameras) {
    const CameraDefinition& original = registry.Camera(camera.name);
    EXPECT_EQ(camera.format_width_mm, original.format_width_mm);
    EXPECT_EQ(camera.nominal_principal_distance_mm, original.nominal_principal_distance_mm);
    EXPECT_EQ(camera.grid, original.grid);
    EXPECT_EQ(camera.fiducial_set, original.fiducial_set);
    EXPECT_EQ(camera.format_corners_as_fiducials, original.format_corners_as_fiducials);
    EXPECT_EQ(camera.calibration_temperature_degC, original.calibration_temperature_degC);
    EXPECT_EQ(camera.glass_expansion_per_degC, original.glass_expansion_per_degC);
    ASSERT_EQ(camera.lens.has_value(), original.lens.has_value());
    if (!camera.lens) continue;
    EXPECT_EQ(camera.lens->model, original.lens->model);
    EXPECT_EQ(camera.lens->principal_distance_mm, original.lens->principal_distance_mm);
    EXPECT_EQ(camera.lens->principal_point_x_mm, original.lens->principal_point_x_mm);
    EXPECT_EQ(camera.lens->principal_point_y_mm, original.lens->principal_point_y_mm);
    EXPECT_EQ(camera.lens->coefficients, original.lens->coefficients) << camera.name;
    EXPECT_EQ(camera.lens->sigmas, original.lens->sigmas) << camera.name;
  }
}

TEST(DefinitionFormat, CsvHasTheTableDecimals) {
  const DefinitionRegistry registry;
  const std::string csv = ToCsv(registry.Grid("ikogon-b"));
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "id,x_mm,y_mm");
  EXPECT_THAT(csv, HasSubstr("\nX1Y1,-50.0014,-50.0019\n"));
  EXPECT_THAT(csv, HasSubstr("\nX6Y6,0.0000,0.0000\n"));
  EXPECT_THAT(csv, HasSubstr("\nX7Y7,9.9992,10.0000\n"));
  const std::string fiducials = ToCsv(registry.Fiducials("sn004-terrain-fiducials"));
  EXPECT_THAT(fiducials, HasSubstr("\nC,0.010,-60.482\n"));
  EXPECT_THAT(fiducials, HasSubstr("\nA',-60.555,30.796\n"));
}

// Runs the reader on `text` and returns the error message ("" if none).
std::string ErrorOf(const std::string& text) {
  try {
    DefinitionRegistry::FromTexts({{"bad.toml", text}});
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(DefinitionFormat, BadInputIsAOneLineErrorNamingFileLineAndProblem) {
  struct Case {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
      {"columns = 3", "columns = 3 3", "malformed TOML"},
      {"spacing_mm = 5.0", "spacing_mm = 5.0\nspacng_mm = 5.0", "unknown key 'spacng_mm'"},
      {"rows = 2", "rows = \"2\"", "key 'rows' must be an integer"},
      {"spacing_mm = 5.0", "spacing_mm = nan", "must be a finite number"},
      {"spacing_mm = 5.0", "spacing_mm = inf", "must be a finite number"},
      {"description = \"3 x 2 lattice\"\n", "", "missing required key 'description'"},
      {"type = \"dot\"", "type = \"star\"", "unknown mark type 'star'"},
      {"[\"left\", -20.5, 0.0]", "[\"right\", -20.5, 0.0]", "duplicate point id 'right'"},
      {"grid = \"test-lattice\"", "grid = \"no-such-grid\"", "unknown grid 'no-such-grid'"},
      {"fiducial_set = \"test-fiducials\"", "fiducial_set = \"nope\"", "unknown fiducial_set 'nope'"},
      {"k0 = -1e-3", "k0 = -1e-3\nk3 = 0", "unknown coefficient 'k3'"},
      {"k0 = -1e-3\n", "", "missing 'k0'"},
      {"model = \"brown-balanced\"", "model = \"brown\"", "unknown lens model 'brown'"},
      {"k0 = 1e-5", "k00 = 1e-5", "unknown key 'k00'"},
      {"nominal_principal_distance_mm = 50", "nominal_principal_distance_mm = -50", "must be > 0"},
      {"[[camera]]", "[camera]", "must be written as [[camera]]"},
  };
  for (const Case& c : cases) {
    const std::string message = ErrorOf(Replace(kUserFile, c.from, c.to));
    EXPECT_THAT(message, HasSubstr("bad.toml: ")) << c.expected;
    EXPECT_THAT(message, HasSubstr(c.expected));
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  // Where toml++ or the key has a line, the message gives it.
  EXPECT_THAT(ErrorOf(Replace(kUserFile, "columns = 3", "columns = 3 3")), HasSubstr("line 7"));
  EXPECT_THAT(ErrorOf(Replace(kUserFile, "type = \"dot\"", "type = \"star\"")), HasSubstr("line 10"));
  EXPECT_THAT(ErrorOf(Replace(kUserFile, "type = \"dot\"", "type = \"star\"")), HasSubstr("grid 'test-lattice'"));
}

TEST(DefinitionFormat, ReseauIdsMustBeXiYjInsideTheGrid) {
  const std::string grid = R"toml(
[[grid]]
name = "g"
description = "d"
source = "s"
columns = 2
rows = 2
mark = { type = "cross", line_width_um = 20.0, arm_length_um = 600.0 }
points = [ ["X1Y1", 0.0, 0.0], ["ID", 1.0, 1.0] ]
)toml";
  EXPECT_THAT(ErrorOf(grid), HasSubstr("line 9: grid 'g': reseau id 'ID' is not of the form X{i}Y{j}"));
  EXPECT_THAT(ErrorOf(Replace(grid, "\"ID\"", "\"X3Y1\"")), HasSubstr("reseau id 'X3Y1' is outside"));
  EXPECT_THAT(ErrorOf(Replace(grid, "\"ID\"", "\"X0Y1\"")), HasSubstr("not of the form"));
  EXPECT_THAT(ErrorOf(Replace(grid, "\"ID\"", "\"X1Y1\"")), HasSubstr("duplicate point id 'X1Y1'"));
  EXPECT_EQ(ErrorOf(Replace(grid, "\"ID\"", "\"X2Y2\"")), "");
  EXPECT_THAT(ErrorOf(Replace(grid, "[\"ID\", 1.0, 1.0]", "[\"X2Y2\", 1.0]")), HasSubstr("[\"id\", x_mm, y_mm]"));
  EXPECT_THAT(ErrorOf(""), HasSubstr("no definitions"));
  EXPECT_THAT(ErrorOf("[[gird]]\nname = \"x\"\n"), HasSubstr("unknown key 'gird'"));
}

TEST(DefinitionRegistry, UnknownNamesListTheKnownOnes) {
  const DefinitionRegistry registry;
  try {
    registry.Grid("ikogon-c");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("ikogon-c"));
    EXPECT_THAT(e.what(), HasSubstr("ikogon-b, ikotar-b, orbigon-reseau"));
  }
  EXPECT_THROW(registry.Camera("sn004"), Error);
  EXPECT_THROW(registry.Fiducials("ikogon-b"), Error);  // a grid, not a fiducial set
  EXPECT_EQ(registry.CameraNames(),
            (std::vector<std::string>{"hasselblad-500", "hasselblad-80", "orbigon", "sn004-stellar", "sn004-terrain"}));
  EXPECT_EQ(registry.OriginOf("ikogon-b"), "builtin/ikogon-b.toml");
}

TEST(DefinitionRegistry, UserDefinitionReplacesABuiltInWithAWarning) {
  std::vector<std::string> warnings;
  SetWarningSink([&](const std::string& line) { warnings.push_back(line); });
  const std::string replacement = Replace(Replace(kUserFile, "\"test-lattice\"\n", "\"ikotar-b\"\n"),
                                          "grid = \"test-lattice\"", "grid = \"ikotar-b\"");
  const DefinitionRegistry registry = DefinitionRegistry::FromTexts({{"mine.toml", replacement}});
  SetWarningSink(nullptr);
  EXPECT_EQ(registry.Grid("ikotar-b").points.size(), 6u);
  EXPECT_EQ(registry.OriginOf("ikotar-b"), "mine.toml");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("mine.toml"));
  EXPECT_THAT(warnings[0], HasSubstr("grid 'ikotar-b' replaces the built-in"));
}

TEST(DefinitionRegistry, TwoUserDefinitionsWithOneNameAreAnError) {
  try {
    DefinitionRegistry::FromTexts({{"one.toml", kUserFile}, {"two.toml", kUserFile}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("two.toml: line 3: grid 'test-lattice' is already defined in one.toml line 3"));
  }
}

TEST(DefinitionRegistry, ReadsFilesNamedInTheEnvironment) {
  testing::TempDir dir;
  const std::string path = dir.file("env.toml");
  std::ofstream(path) << kUserFile;
  ::setenv("PLATEMETER_DEFINITIONS", (":" + path + ":").c_str(), 1);
  const DefinitionRegistry registry = DefinitionRegistry::Load({});
  EXPECT_NE(registry.FindCamera("test-camera"), nullptr);
  ::setenv("PLATEMETER_DEFINITIONS", dir.file("missing.toml").c_str(), 1);
  EXPECT_THROW(DefinitionRegistry::Load({}), Error);
  EXPECT_EQ(DefinitionRegistry::Load({}, DefinitionLoadOptions{false}).FindCamera("test-camera"), nullptr);
  ::unsetenv("PLATEMETER_DEFINITIONS");
  EXPECT_EQ(DefinitionRegistry::Load({}).FindCamera("test-camera"), nullptr);
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

// The complete example of docs/definitions.md must load (and keep loading).
TEST(DefinitionFormat, DocumentedExampleLoads) {
  std::ifstream in(std::string(PLATEMETER_SOURCE_DIR) + "/docs/definitions.md");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string doc = buffer.str();
  const size_t begin = doc.find("```toml\n");
  ASSERT_NE(begin, std::string::npos);
  const size_t end = doc.find("```", begin + 8);
  const std::string example = doc.substr(begin + 8, end - begin - 8);
  const DefinitionRegistry registry = DefinitionRegistry::FromTexts({{"docs example", example}});
  const CameraDefinition& camera = registry.Camera("rc70");
  EXPECT_EQ(registry.Grid(camera.grid).points.size(), 25u);
  EXPECT_EQ(registry.Fiducials(camera.fiducial_set).Find("4")->mark.type, MarkType::kRing);
  EXPECT_EQ(camera.lens->coefficients.size(), 6u);
}

// ---------------------------------------------------------------------------
// Issue #28: every number of a definition range-checked where it is read; a
// byte order mark accepted; the fuzz harness's crash as a regression test.

TEST(DefinitionRanges, HugeSpacingIsRefusedNotExpandedToInfinity) {
  // Reported: spacing_mm = 1e308 loaded and printed -inf coordinates.
  EXPECT_EQ(ErrorOf(Replace(kUserFile, "spacing_mm = 5.0", "spacing_mm = 1e308")),
            "bad.toml: line 9: grid 'test-lattice': key 'spacing_mm' = 1e308 is outside the accepted range 0.01..1000 mm");
  EXPECT_EQ(ErrorOf(Replace(Replace(kUserFile, "columns = 3", "columns = 3001"), "spacing_mm = 5.0", "spacing_mm = 1")),
            "bad.toml: line 9: grid 'test-lattice': the lattice reaches 1500 mm from its centre, outside the accepted "
            "range -1000..1000 mm");
}

TEST(DefinitionRanges, HugePrincipalDistanceIsRefused) {
  // Reported: a camera with principal distance 1e200 was accepted.
  EXPECT_EQ(ErrorOf(Replace(kUserFile, "principal_distance_mm = 50.1", "principal_distance_mm = 1e200")),
            "bad.toml: line 36: camera 'test-camera': lens: key 'principal_distance_mm' = 1e200 is outside the "
            "accepted range 0..25000 mm");
  EXPECT_EQ(ErrorOf(Replace(kUserFile, "nominal_principal_distance_mm = 50", "nominal_principal_distance_mm = 1e200")),
            "bad.toml: line 28: camera 'test-camera': key 'nominal_principal_distance_mm' = 1e200 is outside the "
            "accepted range 0..25000 mm");
  EXPECT_EQ(ErrorOf(Replace(kUserFile, "principal_point_x_um = 12.5", "principal_point_x_um = -2e6")),
            "bad.toml: line 37: camera 'test-camera': lens: key 'principal_point_x_um' = -2e6 is outside the "
            "accepted range -1e6..1e6 um");
}

TEST(DefinitionRanges, EveryOtherNumberHasItsRange) {
  const std::vector<std::pair<std::pair<std::string, std::string>, std::string>> cases = {
      {{"[\"left\", -20.5, 0.0]", "[\"left\", -2000.5, 0.0]"},
       "x_mm of point 'left' = -2000.5 is outside the accepted range -1000..1000 mm"},
      {{"x_mm = 20.5", "x_mm = 1e9"}, "key 'x_mm' = 1e9 is outside the accepted range -1000..1000 mm"},
      {{"format_width_mm = 60.0", "format_width_mm = 1e5"},
       "key 'format_width_mm' = 1e5 is outside the accepted range 0..1000 mm"},
      {{"calibration_temperature_degC = 21.5", "calibration_temperature_degC = -300"},
       "key 'calibration_temperature_degC' = -300 is outside the accepted range -100..100 degC"},
      {{"line_width_um = 10.0", "line_width_um = 1e6"},
       "key 'line_width_um' = 1e6 is outside the accepted range 0..10000 um"},
      {{"k0 = -1e-3", "k0 = 2"}, "key 'k0' = 2 is outside the accepted range -1..1"},
      {{"k1_per_mm2 = 2e-6", "k1_per_mm2 = 1e300"}, "key 'k1_per_mm2' = 1e300 is outside the accepted range -1e12..1e12"},
      {{"principal_point_x_um = 1.5", "principal_point_x_um = 1e300"},
       "sigma 'principal_point_x_um' = 1e300 is outside the accepted range 0..1e6 um"},
  };
  for (const auto& [change, expected] : cases) {
    const std::string message = ErrorOf(Replace(kUserFile, change.first, change.second));
    EXPECT_THAT(message, HasSubstr(expected)) << change.second;
    EXPECT_THAT(message, HasSubstr("bad.toml: line ")) << change.second;
  }
}

TEST(DefinitionText, AByteOrderMarkIsAccepted) {
  const DefinitionRegistry registry = DefinitionRegistry::FromTexts({{"bom.toml", "\xEF\xBB\xBF" + std::string(kUserFile)}});
  EXPECT_EQ(registry.Camera("test-camera").format_width_mm, 60.0);
}

// Fuzz finding (tests/fuzz, definitions): a name of 20000 characters
// overflowed the stack in std::regex_match (a segfault); now a one-line error.
TEST(DefinitionText, FuzzFindingAHugeNameIsAnErrorNotACrash) {
  const std::string name(20000, 'A');
  EXPECT_THAT(ErrorOf(Replace(kUserFile, "name = \"test-lattice\"", "name = \"" + name + "\"")),
              HasSubstr("' must be letters, digits, '.', '_' or '-' (at most 256)"));
  const std::string grid = "[[grid]]\nname = \"g\"\ndescription = \"d\"\nsource = \"s\"\ncolumns = 2\nrows = 2\n"
                           "mark = { type = \"cross\", line_width_um = 10, arm_length_um = 100 }\n"
                           "points = [[\"X1Y" + std::string(20000, '1') + "\", 1.0, 1.0]]\n";
  EXPECT_THAT(ErrorOf(grid), HasSubstr("line 8: grid 'g': reseau id 'X1Y111"));
  EXPECT_THAT(ErrorOf(grid), HasSubstr("' is not of the form X{i}Y{j}"));
}

}  // namespace
}  // namespace platemeter
