// The measurement file: exact round trip through the writer and the reader;
// malformed files rejected with the line (and column) that is wrong.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using ::testing::HasSubstr;

// Bitwise comparison: "exact" means the same double, sign of zero included.
bool SameBits(const std::optional<double>& a, const std::optional<double>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || std::memcmp(&*a, &*b, sizeof(double)) == 0;
}

// The files (and temporaries) in a folder.
int EntriesIn(const std::filesystem::path& dir) {
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++entries;
  return entries;
}

MeasurementFile Sample() {
  MeasurementFile file;
  file.header.plate_id = "orbigon-1320";
  file.header.scan_file = "scans/plate 1320.tif";
  file.header.scan_sha256 = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
  file.header.camera = "orbigon";
  file.header.pixel_size_um = 5.0000000000000009;
  file.header.software_version = "platemeter 0.1.0";
  file.header.corrections.push_back({"thermal", {{"temperature_degC", "22"}, {"calibration_temperature_degC", "20"},
                                                 {"expansion_per_degC", "8.1e-06"}}});
  file.header.corrections.push_back({"emulsion_depth", {{"depth_um", "21"}, {"refractive_index", "1.65"}}});
  file.header.extra.push_back({"chain_file", "plate.chain.json"});

  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> uniform(-1e4, 1e4);
  for (int i = 1; i <= 11; ++i) {
    MeasuredPoint p;
    p.id = "X" + std::to_string(i) + "Y1";
    p.kind = PointKind::kReseau;
    p.status = PointStatus::kMeasured;
    p.x_px = uniform(random);  // random doubles need all 17 digits
    p.y_px = uniform(random);
    p.sigma_x_px = std::abs(uniform(random)) * 1e-7;
    p.sigma_y_px = 0.1 + 0.2;  // 0.30000000000000004
    p.x_mm = std::nextafter(10.0 * i, 0.0);
    p.y_mm = -0.0;
    p.sigma_x_mm = 1e-300;
    p.sigma_y_mm = 5e-324;  // smallest denormal
    if (i % 3 == 0) p.flags = {"saturated", "blended"};
    file.points.push_back(p);
  }
  MeasuredPoint rejected;
  rejected.id = "X5Y5";
  rejected.kind = PointKind::kReseau;
  rejected.status = PointStatus::kRejected;
  rejected.x_px = 1.5;
  rejected.y_px = 2.25;
  rejected.flags = {"rejected:low_contrast"};
  file.points.push_back(rejected);
  MeasuredPoint missing;
  missing.id = "X6Y6";
  missing.status = PointStatus::kMissing;
  file.points.push_back(missing);
  MeasuredPoint dot;
  dot.id = "T2-D17";
  dot.kind = PointKind::kTrailDot;
  dot.status = PointStatus::kTruth;
  dot.x_px = 123.456;
  dot.y_px = 789.0123;
  dot.x_mm = -12.5;
  dot.y_mm = 33.25;
  dot.star_id = "HIP 32349";
  dot.trail = "T2";
  dot.dot = 17;
  dot.mid_time_utc = "1972-03-25T04:12:31.250Z";
  dot.crb_x_px = 0.0123;
  dot.crb_y_px = 0.0234;
  dot.crb_xy_corr = -0.25;
  file.points.push_back(dot);
  return file;
}

void ExpectSame(const MeasurementFile& a, const MeasurementFile& b) {
  EXPECT_EQ(a.header.format_version, b.header.format_version);
  EXPECT_EQ(a.header.plate_id, b.header.plate_id);
  EXPECT_EQ(a.header.scan_file, b.header.scan_file);
  EXPECT_EQ(a.header.scan_sha256, b.header.scan_sha256);
  EXPECT_EQ(a.header.camera, b.header.camera);
  EXPECT_TRUE(SameBits(a.header.pixel_size_um, b.header.pixel_size_um));
  EXPECT_EQ(a.header.software_version, b.header.software_version);
  ASSERT_EQ(a.header.corrections.size(), b.header.corrections.size());
  for (size_t i = 0; i < a.header.corrections.size(); ++i) {
    EXPECT_EQ(a.header.corrections[i].name, b.header.corrections[i].name);
    EXPECT_EQ(a.header.corrections[i].parameters, b.header.corrections[i].parameters);
  }
  EXPECT_EQ(a.header.extra, b.header.extra);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    const MeasuredPoint& p = a.points[i];
    const MeasuredPoint& q = b.points[i];
    SCOPED_TRACE(p.id);
    EXPECT_EQ(p.id, q.id);
    EXPECT_EQ(p.kind, q.kind);
    EXPECT_EQ(p.status, q.status);
    for (auto member : {&MeasuredPoint::x_px, &MeasuredPoint::y_px, &MeasuredPoint::sigma_x_px,
                        &MeasuredPoint::sigma_y_px, &MeasuredPoint::x_mm, &MeasuredPoint::y_mm,
                        &MeasuredPoint::sigma_x_mm, &MeasuredPoint::sigma_y_mm, &MeasuredPoint::crb_x_px,
                        &MeasuredPoint::crb_y_px, &MeasuredPoint::crb_xy_corr}) {
      EXPECT_TRUE(SameBits(p.*member, q.*member));
    }
    EXPECT_EQ(p.flags, q.flags);
    EXPECT_EQ(p.star_id, q.star_id);
    EXPECT_EQ(p.trail, q.trail);
    EXPECT_EQ(p.dot, q.dot);
    EXPECT_EQ(p.mid_time_utc, q.mid_time_utc);
  }
}

TEST(MeasurementFile, RoundTripsExactlyThroughAFile) {
  testing::TempDir dir;
  const MeasurementFile original = Sample();
  const std::string path = dir.file("plate.csv");
  WriteMeasurementFile(path, original);
  const MeasurementFile back = ReadMeasurementFile(path);
  EXPECT_TRUE(back.truth_columns);  // a truth point forces the CRB columns
  ExpectSame(original, back);
  // Writing what was read gives the same bytes.
  EXPECT_EQ(FormatMeasurementFile(back), FormatMeasurementFile(original));
  // Nothing but the file itself is left in the folder (no temporary).
  EXPECT_EQ(EntriesIn(dir.path()), 1);
}

// The writer streams its rows to the temporary file: a defect found at the last row (after 100000 rows,
// several MB, are on the disk) must still leave the earlier file as it was and no temporary beside it.
TEST(MeasurementFile, AWriteRefusedLateLeavesTheEarlierFileAndNoTemporary) {
  testing::TempDir dir;
  const std::string path = dir.file("plate.csv");
  WriteMeasurementFile(path, Sample());
  const std::string before = FormatMeasurementFile(Sample());
  MeasurementFile large = Sample();
  const MeasuredPoint model = large.points.front();
  for (int i = 0; i < 100000; ++i) {
    MeasuredPoint p = model;
    p.id = "S" + std::to_string(i);
    p.kind = PointKind::kStar;
    large.points.push_back(p);
  }
  large.points.push_back(large.points.back());  // a duplicate id, found only at the end
  try {
    WriteMeasurementFile(path, large);
    FAIL() << "a file with a duplicate point written";
  } catch (const EnvironmentError&) {
    FAIL() << "a defect of the data reported as the machine's";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), path);
    EXPECT_EQ(e.reason(), "duplicate point star 'S99999'");
  }
  EXPECT_EQ(testing::ReadTextFile(path), before);
  EXPECT_EQ(EntriesIn(dir.path()), 1);
}

// A folder that does not exist is the machine's (or the user's path's) problem, reported as such.
TEST(MeasurementFile, AWriteIntoAMissingFolderIsAnEnvironmentError) {
  testing::TempDir dir;
  const std::string path = dir.file("no such folder/plate.csv");
  try {
    WriteMeasurementFile(path, Sample());
    FAIL() << "written into a missing folder";
  } catch (const EnvironmentError& e) {
    EXPECT_EQ(e.subject(), path);
    EXPECT_EQ(e.reason(), "write failed (No such file or directory)");
  }
}

TEST(MeasurementFile, LayoutIsTheDocumentedOne) {
  MeasurementFile file = Sample();
  file.points.resize(2);  // no truth points: no CRB columns
  const std::string text = FormatMeasurementFile(file);
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "# platemeter measurement file");
  std::getline(in, line);
  EXPECT_EQ(line, "# format_version: 1");
  EXPECT_THAT(text, HasSubstr("\n# correction: thermal temperature_degC=22 calibration_temperature_degC=20 "
                              "expansion_per_degC=8.1e-06\n"));
  EXPECT_THAT(text, HasSubstr("\nid,kind,status,x_px,y_px,sigma_x_px,sigma_y_px,x_mm,y_mm,sigma_x_mm,sigma_y_mm,"
                              "flags,star_id,trail,dot,mid_time_utc\n"));
  // 0.1 + 0.2 needs 17 significant digits, -0.0 keeps its sign, 10 - ulp is not 10.
  EXPECT_THAT(text, HasSubstr(",0.30000000000000004,"));
  EXPECT_THAT(text, HasSubstr(",-0,"));
  EXPECT_THAT(text, HasSubstr(",9.999999999999998,"));
}

// Replaces line `line_number` (1-based) of the sample file's text.
std::string WithLine(int line_number, const std::string& replacement) {
  std::istringstream in(FormatMeasurementFile(Sample()));
  std::string line, out;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    out += (n == line_number ? replacement : line) + "\n";
  }
  return out;
}

int LineOf(const std::string& text, const std::string& start) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.rfind(start, 0) == 0) return n;
  }
  return -1;
}

std::string ErrorOfFormat(const MeasurementFile& file) {
  try {
    FormatMeasurementFile(file);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseMeasurementFile(text, "plate.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(MeasurementFile, MalformedFilesNameTheLineAndColumn) {
  const std::string good = FormatMeasurementFile(Sample());
  const int columns_line = LineOf(good, "id,kind");
  const int first_row = columns_line + 1;
  ASSERT_GT(columns_line, 5);

  // A bad number in x_px (column 4) of the first data row.
  std::string row = "X1Y1,reseau,measured,12.x,3,,,,,,,,,,,,,,";
  EXPECT_EQ(ErrorOf(WithLine(first_row, row)),
            "plate.csv: line " + std::to_string(first_row) + ", column 4 (x_px): '12.x' is not a number");
  // Too few fields.
  EXPECT_THAT(ErrorOf(WithLine(first_row + 2, "X3Y1,reseau,measured,1,2")),
              HasSubstr("line " + std::to_string(first_row + 2) + ": expected 19 fields, found 5"));
  // Unknown kind and status.
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,cross,measured,1,2,,,,,,,,,,,,,,")),
              HasSubstr("line " + std::to_string(first_row) + ", column 2 (kind): unknown kind 'cross'"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,found,1,2,,,,,,,,,,,,,,")),
              HasSubstr("column 3 (status): unknown status 'found'"));
  // A duplicate id of the same kind.
  EXPECT_THAT(ErrorOf(WithLine(first_row + 1, "X1Y1,reseau,measured,1,2,,,,,,,,,,,,,,")),
              HasSubstr("line " + std::to_string(first_row + 1) + ", column 1 (id): duplicate reseau 'X1Y1'"));
  // Negative sigma, non-finite number, half a position, correlation out of range, bad dot index.
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,measured,1,2,-0.1,,,,,,,,,,,,,")),
              HasSubstr("column 6 (sigma_x_px): a standard deviation cannot be negative"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,measured,nan,2,,,,,,,,,,,,,,")),
              HasSubstr("column 4 (x_px): 'nan' is not a finite number"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,measured,,,,,4,,,,,,,,,,,")),
              HasSubstr("column 8 (x_mm): x_mm and y_mm must both be given"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,truth,1,2,,,,,,,,,,,,0.1,0.1,1.5")),
              HasSubstr("column 19 (crb_xy_corr): a correlation must lie in -1..1"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,trail_dot,truth,1,2,,,,,,,,,T1,3.5,,,,")),
              HasSubstr("column 15 (dot): '3.5' is not an integer"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,measured,,,,,,,,,,,,,,,,")),
              HasSubstr("column 4 (x_px): a measured point needs a position"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "X1Y1,reseau,measured,1,2,,,,,,,a||b,,,,,,,")),
              HasSubstr("column 12 (flags): empty flag"));
  // Header problems.
  EXPECT_EQ(ErrorOf(WithLine(1, "id,kind")),
            "plate.csv: line 1: not a measurement file (expected '# platemeter measurement file')");
  EXPECT_THAT(ErrorOf(WithLine(2, "# format_version: 9")), HasSubstr("line 2: format_version 9 is newer"));
  EXPECT_THAT(ErrorOf(WithLine(2, "# plate_id: x")), HasSubstr("line " + std::to_string(columns_line) +
                                                                 ": the header has no format_version line"));
  EXPECT_THAT(ErrorOf(WithLine(4, "# scan_sha256: 12ab")), HasSubstr("line 4: scan_sha256 must be 64"));
  EXPECT_THAT(ErrorOf(WithLine(columns_line, "id,kind,status,x_px,y_px,sigma_x_px,sigma_y_px,x,y")),
              HasSubstr("line " + std::to_string(columns_line) + ": column 8 is 'x', expected 'x_mm'"));
  EXPECT_THAT(ErrorOf(WithLine(first_row, "# late comment")),
              HasSubstr("line " + std::to_string(first_row) + ": comment lines belong in the header"));
  EXPECT_THAT(ErrorOf("# platemeter measurement file\n# format_version: 1\n"),
              HasSubstr("no column line"));
  EXPECT_EQ(ErrorOf(""), "plate.csv: empty file (not a measurement file)");
}

TEST(MeasurementFile, WriterRefusesWhatCannotBeReadBack) {
  MeasurementFile file = Sample();
  file.points[0].id = "a,b";
  EXPECT_THROW(FormatMeasurementFile(file), Error);
  file = Sample();
  file.points[1].id = file.points[0].id;
  EXPECT_THROW(FormatMeasurementFile(file), Error);
  file = Sample();
  file.points[0].x_px = std::numeric_limits<double>::infinity();
  EXPECT_THROW(FormatMeasurementFile(file), Error);
  file = Sample();
  file.points[0].flags = {"a|b"};
  EXPECT_THROW(FormatMeasurementFile(file), Error);
  file = Sample();
  file.header.plate_id = "two\nlines";
  EXPECT_THROW(FormatMeasurementFile(file), Error);
  file = Sample();
  file.header.extra.push_back({"camera", "again"});
  EXPECT_THROW(FormatMeasurementFile(file), Error);
}

TEST(MeasurementFile, MissingFileIsAnErrorNamingIt) {
  try {
    ReadMeasurementFile("/nonexistent/plate.csv");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), "/nonexistent/plate.csv");
  }
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

// The example in docs/measurement-file.md is a valid file and says what it shows.
TEST(MeasurementFile, DocumentedExampleParses) {
  std::ifstream in(std::string(PLATEMETER_SOURCE_DIR) + "/docs/measurement-file.md");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string doc = buffer.str();
  const size_t start = doc.find("```\n# platemeter measurement file");
  ASSERT_NE(start, std::string::npos);
  const size_t end = doc.find("```", start + 3);
  const std::string example = doc.substr(start + 4, end - start - 4);
  const MeasurementFile file = ParseMeasurementFile(example, "docs example");
  ASSERT_EQ(file.points.size(), 4u);
  EXPECT_FALSE(file.truth_columns);
  EXPECT_EQ(file.header.corrections.size(), 2u);
  EXPECT_EQ(file.points[1].flags, std::vector<std::string>{"rejected:low_contrast"});
  EXPECT_EQ(file.points[2].status, PointStatus::kMissing);
  EXPECT_EQ(file.points[3].kind, PointKind::kTrailDot);
  EXPECT_EQ(file.points[3].dot, 17);
  EXPECT_EQ(file.points[3].star_id, "HIP 32349");
  EXPECT_EQ(FormatMeasurementFile(file), example);  // the example is in canonical form
}

// ---------------------------------------------------------------------------
// Issue #28: numbers range-checked at entry, text fields valid UTF-8, a byte
// order mark accepted; the reported cases and the fuzz harness's findings.

// A 16-column file whose data row (line 4) is `row`.
std::string OneRow(const std::string& row, const std::string& header = "") {
  return "# platemeter measurement file\n# format_version: 1\n" + header +
         "id,kind,status,x_px,y_px,sigma_x_px,sigma_y_px,x_mm,y_mm,sigma_x_mm,sigma_y_mm,flags,star_id,trail,dot,"
         "mid_time_utc\n" + row + "\n";
}

TEST(MeasurementFileRanges, HugePixelCoordinateIsRefusedAtTheReader) {
  // Reported: x_px >= 1e307 made measure/validate segfault later.
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1e307,2,0.1,0.1,,,,,,,,,")),
            "plate.csv: line 4, column 4 (x_px): '1e307' is outside the accepted range -1e7..1e7 px");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1,-10000001,0.1,0.1,,,,,,,,,")),
            "plate.csv: line 4, column 5 (y_px): '-10000001' is outside the accepted range -1e7..1e7 px");
}

TEST(MeasurementFileRanges, HugeSigmaIsRefusedAtTheReader) {
  // Reported: a sigma >= 1e155 (its square overflows) made measure/validate segfault later.
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1,2,1e155,0.1,,,,,,,,,")),
            "plate.csv: line 4, column 6 (sigma_x_px): '1e155' is outside the accepted range 0..10000 px");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,,,,,1,2,0.001,1e3000,,,,,")),
            "plate.csv: line 4, column 11 (sigma_y_mm): '1e3000' is not a number");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,,,,,1,2,0.001,1001,,,,,")),
            "plate.csv: line 4, column 11 (sigma_y_mm): '1001' is outside the accepted range 0..1000 mm");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,,,,,-10000.5,2,,,,,,,")),
            "plate.csv: line 4, column 8 (x_mm): '-10000.5' is outside the accepted range -10000..10000 mm");
  EXPECT_EQ(ErrorOf(OneRow("T1-D1,trail_dot,measured,1,2,,,,,,,,,T1,9223372036854775807,")),
            "plate.csv: line 4, column 15 (dot): '9223372036854775807' is outside the accepted range 0..1e6");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1,2,,,,,,,,,,,", "# pixel_size_um: 1e300\n")),
            "plate.csv: line 3: pixel_size_um '1e300' is outside the accepted range 0.01..10000 um");
}

TEST(MeasurementFileRanges, TheBoundsThemselvesAreAccepted) {
  const MeasurementFile file = ParseMeasurementFile(
      OneRow("X1Y1,reseau,measured,10000000,-1e7,10000,0,-1e4,1e4,1000,0,,,,,"), "plate.csv");
  ASSERT_EQ(file.points.size(), 1u);
  EXPECT_EQ(*file.points[0].x_px, 1e7);
  EXPECT_EQ(*file.points[0].y_px, -1e7);
  EXPECT_EQ(*file.points[0].sigma_x_px, 1e4);
  EXPECT_EQ(*file.points[0].y_mm, 1e4);
  EXPECT_EQ(*file.points[0].sigma_x_mm, 1e3);
}

TEST(MeasurementFileRanges, WriterRefusesWhatTheReaderWouldRefuse) {
  MeasurementFile file = Sample();
  file.points[0].x_px = 1e307;
  EXPECT_EQ(ErrorOfFormat(file), "measurement file: point 'X1Y1': x_px '1e+307' is outside the accepted range -1e7..1e7 px");
  file = Sample();
  file.points[0].sigma_y_mm = 1e155;
  EXPECT_EQ(ErrorOfFormat(file),
            "measurement file: point 'X1Y1': sigma_y_mm '1e+155' is outside the accepted range 0..1000 mm");
  file = Sample();
  file.points[0].id = "X1\xffY1";
  EXPECT_EQ(ErrorOfFormat(file), "measurement file: point 'X1\xffY1': a text field byte 0xff at position 3 is not valid UTF-8");
}

TEST(MeasurementFileText, AByteOrderMarkIsAccepted) {
  const MeasurementFile file = ParseMeasurementFile("\xEF\xBB\xBF" + OneRow("X1Y1,reseau,measured,1,2,,,,,,,,,,,"), "plate.csv");
  ASSERT_EQ(file.points.size(), 1u);
  EXPECT_EQ(file.points[0].id, "X1Y1");
}

TEST(MeasurementFileText, IdsThatAreNotUtf8OrHoldControlCharactersAreRefused) {
  // Reported: a non-UTF-8 id made micmac.xml ill-formed.
  EXPECT_EQ(ErrorOf(OneRow("P\xe9,passpoint,measured,1,2,,,,,,,,,,,")),
            "plate.csv: line 4, column 1 (id): byte 0xe9 at position 2 is not valid UTF-8");
  EXPECT_EQ(ErrorOf(OneRow("P1,star,measured,1,2,,,,,,,,HIP\x01 7,,,")),
            "plate.csv: line 4, column 13 (star_id): contains the control character 0x01 at position 4");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1,2,,,,,,,,,,,", "# plate_id: \xc3(\n")),
            "plate.csv: line 3: the header line byte 0xc3 at position 13 is not valid UTF-8");
  // Valid UTF-8 beyond ASCII is fine.
  EXPECT_EQ(ParseMeasurementFile(OneRow("P\xc3\xa9,passpoint,measured,1,2,,,,,,,,,,,"), "plate.csv").points[0].id,
            "P\xc3\xa9");
}

// Fuzz findings (tests/fuzz, measurement_file): fields the reader accepted but
// the writer refuses, so a file read could not be written back.
TEST(MeasurementFileText, FuzzFindingsQuotesAndEqualsInACorrectionName) {
  EXPECT_EQ(ErrorOf(OneRow("T2-D17,trail_dot,measured,1,2,,,,,,,,HIP \"32349,T2,17,")),
            "plate.csv: line 4, column 13 (star_id): contains a double quote (there is no CSV quoting)");
  EXPECT_EQ(ErrorOf(OneRow("X1Y1,reseau,measured,1,2,,,,,,,,,,,", "# correction: ther=mal\n")),
            "plate.csv: line 3: correction name 'ther=mal' contains '=' (write NAME param=value ...)");
  EXPECT_EQ(ErrorOf(OneRow("T1-D1,trail_dot,measured,1,2,,,,,,,,,T1,1," + std::string(65, '1'))),
            "plate.csv: line 4, column 16 (mid_time_utc): longer than 64 characters (not an ISO 8601 time)");
}

}  // namespace
}  // namespace platemeter
