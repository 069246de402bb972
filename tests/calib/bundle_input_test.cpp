// The bundle's input (bundle_input_io.h, docs/bundle-job.md): the two CSV
// readers and writers with every error naming file and line, observations from
// measurement files, the checks (points seen once, thin frames and their
// cascade, unobserved ground points), Gyer's station covariance (seed 000
// section 3.3), BundleOptions, cameras from definitions and the job file (the
// example of docs/bundle-job.md parsed).
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/calib/bundle_options.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using ::platemeter::testing::TempDir;

void WriteText(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string ReadTextOfInput(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// The message of the Error `f` throws ("" and a test failure if none).
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no platemeter::Error thrown";
  return "";
}

#define EXPECT_ERROR(statement, expected_substring)                                      \
  do {                                                                                 \
    const std::string message_ = ErrorOf([&] { statement; });                          \
    EXPECT_NE(message_.find(expected_substring), std::string::npos) << message_;       \
  } while (0)

ImageObservation Obs(const std::string& frame, const std::string& point, double x = 1.0, double y = 2.0) {
  ImageObservation o;
  o.frame = frame;
  o.point_id = point;
  o.x_mm = x;
  o.y_mm = y;
  o.sigma_x_mm = 0.003;
  o.sigma_y_mm = 0.004;
  return o;
}

// ---------------------------------------------------------------------------
// Observations CSV.

TEST(BundleInputCsv, ObservationsRoundTripGivesTheSameDoubles) {
  TempDir dir;
  std::vector<ImageObservation> observations = {
      Obs("F1", "P1", 0.1 + 0.2, -1.0 / 3.0), Obs("F1", "P2", -0.0, 1e-300), Obs("F 2", "P1", 27.5, -27.5)};
  observations[1].sigma_x_mm = 5e-324;  // the smallest positive double
  observations[2].sigma_y_mm = 0.1 * 3;
  const std::string path = dir.file("obs.csv");
  WriteObservationsCsv(path, observations);
  const std::vector<ImageObservation> back = ReadObservationsCsv(path);
  ASSERT_EQ(back.size(), observations.size());
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].frame, observations[i].frame);
    EXPECT_EQ(back[i].point_id, observations[i].point_id);
    EXPECT_EQ(back[i].x_mm, observations[i].x_mm);
    EXPECT_EQ(std::signbit(back[i].x_mm), std::signbit(observations[i].x_mm));
    EXPECT_EQ(back[i].y_mm, observations[i].y_mm);
    EXPECT_EQ(back[i].sigma_x_mm, observations[i].sigma_x_mm);
    EXPECT_EQ(back[i].sigma_y_mm, observations[i].sigma_y_mm);
    EXPECT_EQ(back[i].origin, path + ":" + std::to_string(i + 2));  // the header is line 1
  }
  // Writing what was read gives the same bytes.
  EXPECT_EQ(FormatObservationsCsv(back), ReadTextOfInput(path));
  EXPECT_FALSE(std::filesystem::exists(dir.file(".obs.partial.csv")));
}

TEST(BundleInputCsv, ObservationsCommentsBlankLinesSpacesAndOrigins) {
  const std::string text =
      "# comment before the header\n"
      "\n"
      "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\r\n"
      "  # an indented comment\n"
      " F1 , P1 , +1.5 , -2 , 0.003 , 4e-3 \r\n"
      "\n"
      "F1,P2,3,4,0.003,0.003\n";
  const std::vector<ImageObservation> o = ParseObservationsCsv("\xEF\xBB\xBF" + text, "obs.csv");  // with a BOM
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o[0].frame, "F1");
  EXPECT_EQ(o[0].point_id, "P1");
  EXPECT_EQ(o[0].x_mm, 1.5);
  EXPECT_EQ(o[0].y_mm, -2.0);
  EXPECT_EQ(o[0].sigma_y_mm, 0.004);
  EXPECT_EQ(o[0].origin, "obs.csv:5");
  EXPECT_EQ(o[1].origin, "obs.csv:7");
}

TEST(BundleInputCsv, ObservationErrorsNameFileLineAndColumn) {
  const std::string header = "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\n";
  const std::string good = "F1,P1,1,2,0.003,0.003\n";
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"", "obs.csv: no header line: observation files start with the column names "
           "'frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm'"},
      {"# only a comment\n", "obs.csv: no header line"},
      {"frame,point,x_mm,y_mm,sigma_x_mm,sigma_y_mm\n",
       "obs.csv: line 1: column 2 of the header is 'point', expected 'point_id'"},
      {"frame,point_id,x_mm,y_mm,sigma_x_mm\n", "obs.csv: line 1: the header has 5 columns, expected 6"},
      {"F1,P1,1,2,0.003,0.003\n", "obs.csv: line 1: column 1 of the header is 'F1', expected 'frame'"},
      {header + good + "F1,P2,1,2,0.003\n", "obs.csv: line 3: expected 6 fields"},
      {header + "F1,P2,1,2,0.003,0.003,7\n", "obs.csv: line 2: expected 6 fields"},
      {header + ",P2,1,2,0.003,0.003\n", "obs.csv: line 2, column 1 (frame): empty"},
      {header + "F1,,1,2,0.003,0.003\n", "obs.csv: line 2, column 2 (point_id): empty"},
      {header + "F1,P2,12.x,2,0.003,0.003\n", "obs.csv: line 2, column 3 (x_mm): '12.x' is not a number"},
      {header + "F1,P2,1,,0.003,0.003\n", "obs.csv: line 2, column 4 (y_mm): empty (a number is required)"},
      {header + "F1,P2,nan,2,0.003,0.003\n", "obs.csv: line 2, column 3 (x_mm): 'nan' is not a finite number"},
      {header + "F1,P2,1,inf,0.003,0.003\n", "obs.csv: line 2, column 4 (y_mm): 'inf' is not a finite number"},
      {header + "F1,P2,1e999,2,0.003,0.003\n", "obs.csv: line 2, column 3 (x_mm): '1e999' is out of a double's range"},
      {header + "F1,P2,1,2,NaN,0.003\n", "obs.csv: line 2, column 5 (sigma_x_mm): 'NaN' is not a finite number"},
      {header + "F1,P2,1,2,0,0.003\n",
       "obs.csv: line 2, column 5 (sigma_x_mm): a standard deviation of an image observation must be positive ('0')"},
      {header + "F1,P2,1,2,0.003,-0.003\n",
       "obs.csv: line 2, column 6 (sigma_y_mm): a standard deviation of an image observation must be positive"},
      {header + "F1,\"P2\",1,2,0.003,0.003\n", "obs.csv: line 2, column 2 (point_id): '\"P2\"' contains a double quote"},
      {header + good + "# between\n" + good,
       "obs.csv: line 4, column 2 (point_id): point 'P1' is observed twice in frame 'F1' (first on line 2)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_ERROR(ParseObservationsCsv(c.text, "obs.csv"), c.expected);
  }
  EXPECT_ERROR(ReadObservationsCsv("/nonexistent/obs.csv"), "/nonexistent/obs.csv: cannot open the observations file");
}

TEST(BundleInputCsv, ObservationWriterRefusesWhatTheReaderWould) {
  EXPECT_ERROR(FormatObservationsCsv({Obs("F,1", "P1")}), "observations: frame id 'F,1' contains a comma");
  EXPECT_ERROR(FormatObservationsCsv({Obs("#F1", "P1")}), "begins with '#'");
  EXPECT_ERROR(FormatObservationsCsv({Obs("F1", " P1")}), "begins or ends with a space");
  EXPECT_ERROR(FormatObservationsCsv({Obs("F1", "")}), "point id is empty");
  EXPECT_ERROR(FormatObservationsCsv({Obs("F1", "P1", std::nan(""))}), "cannot write a non-finite number");
  EXPECT_ERROR(FormatObservationsCsv({Obs("F1", "P1"), Obs("F1", "P1")}), "is given twice");
  ImageObservation zero = Obs("F1", "P1");
  zero.sigma_y_mm = 0.0;
  EXPECT_ERROR(FormatObservationsCsv({zero}), "the standard deviations must be positive");
  TempDir dir;
  EXPECT_ERROR(WriteObservationsCsv(dir.file("o.csv"), {zero}), dir.file("o.csv") + ": observation of 'P1'");
  EXPECT_FALSE(std::filesystem::exists(dir.file("o.csv")));
}

// ---------------------------------------------------------------------------
// Ground points CSV.

TEST(BundleInputCsv, GroundPointsRoundTripKeepsFreeFixedAndWeighted) {
  TempDir dir;
  GroundPoint fixed{"C1", Eigen::Vector3d(1736512.25, -20450.5, 88034.75), {0.0, 0.0, 0.0}, ""};
  GroundPoint weighted{"C2", Eigen::Vector3d(0.1 + 0.2, -1.0 / 3.0, 1e22), {5.0, 5.0, 2.0}, ""};
  GroundPoint height{"H7", Eigen::Vector3d(1.0, 2.0, 3.0), {std::nullopt, std::nullopt, 1.5}, ""};
  GroundPoint free{"T9", Eigen::Vector3d(-0.0, 4.0, 5.0), {}, ""};
  const std::vector<GroundPoint> points = {fixed, weighted, height, free};
  const std::string path = dir.file("ground.csv");
  WriteGroundPointsCsv(path, points);
  EXPECT_NE(ReadTextOfInput(path).find("H7,1,2,3,,,1.5\n"), std::string::npos) << ReadTextOfInput(path);
  const std::vector<GroundPoint> back = ReadGroundPointsCsv(path);
  ASSERT_EQ(back.size(), points.size());
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].id, points[i].id);
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_EQ(back[i].position_m[axis], points[i].position_m[axis]);
      EXPECT_EQ(back[i].sigma_m[axis], points[i].sigma_m[axis]) << points[i].id << " axis " << axis;
    }
    EXPECT_EQ(back[i].origin, path + ":" + std::to_string(i + 2));
  }
  EXPECT_TRUE(std::signbit(back[3].position_m.x()));
  EXPECT_EQ(FormatGroundPointsCsv(back), ReadTextOfInput(path));
}

TEST(BundleInputCsv, GroundPointErrorsNameFileLineAndColumn) {
  const std::string header = "point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m\n";
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"", "gp.csv: no header line: ground point files start with the column names"},
      {"point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z\n",
       "gp.csv: line 1: column 7 of the header is 'sigma_z', expected 'sigma_z_m'"},
      {header + "G1,1,2,3,,\n", "gp.csv: line 2: expected 7 fields"},
      {header + "G1,1,,3,,,\n", "gp.csv: line 2, column 3 (y_m): empty (a number is required)"},
      {header + "G1,1,2,x3,,,\n", "gp.csv: line 2, column 4 (z_m): 'x3' is not a number"},
      {header + "G1,1,2,-inf,,,\n", "gp.csv: line 2, column 4 (z_m): '-inf' is not a finite number"},
      {header + "G1,1,2,3,,,nan\n", "gp.csv: line 2, column 7 (sigma_z_m): 'nan' is not a finite number"},
      {header + "G1,1,2,3,,,-1\n",
       "gp.csv: line 2, column 7 (sigma_z_m): a standard deviation cannot be negative ('-1'; 0 = fixed, empty = free)"},
      {header + "G1,1,2,3,,,\n# x\nG1,4,5,6,0,0,0\n",
       "gp.csv: line 4, column 1 (point_id): ground point 'G1' is listed twice (first on line 2)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_ERROR(ParseGroundPointsCsv(c.text, "gp.csv"), c.expected);
  }
  GroundPoint negative{"G1", Eigen::Vector3d::Zero(), {-1.0, std::nullopt, std::nullopt}, ""};
  EXPECT_ERROR(FormatGroundPointsCsv({negative}), "ground point 'G1': a standard deviation cannot be negative");
}

// ---------------------------------------------------------------------------
// Observations from measurement files.

MeasuredPoint Measured(const std::string& id, PointKind kind, std::optional<double> x_mm, double sigma = 0.002) {
  MeasuredPoint p;
  p.id = id;
  p.kind = kind;
  p.status = PointStatus::kMeasured;
  p.x_px = 100.0;
  p.y_px = 200.0;
  if (x_mm) {
    p.x_mm = *x_mm;
    p.y_mm = -*x_mm;
    p.sigma_x_mm = sigma;
    p.sigma_y_mm = sigma;
  }
  return p;
}

MeasurementFile SamplePlate() {
  MeasurementFile file;
  file.header.plate_id = "30-9601";
  file.header.camera = "hasselblad-500";
  file.points.push_back(Measured("X1Y1", PointKind::kReseau, 1.0));
  file.points.push_back(Measured("UL", PointKind::kFiducial, 2.0));
  file.points.push_back(Measured("P1", PointKind::kPasspoint, 3.0));
  MeasuredPoint rejected = Measured("P2", PointKind::kPasspoint, 4.0);
  rejected.status = PointStatus::kRejected;
  rejected.flags = {"rejected:low_contrast"};
  file.points.push_back(rejected);
  file.points.push_back(Measured("P3", PointKind::kPasspoint, std::nullopt));  // pixels only
  file.points.push_back(Measured("P4", PointKind::kPasspoint, 5.0));
  file.points.push_back(Measured("S1", PointKind::kStar, 6.0));
  return file;
}

TEST(BundleInputMeasurements, PasspointsMeasuredInPlateCoordinatesWithFileAndLine) {
  TempDir dir;
  const std::string path = dir.file("plate.csv");
  WriteMeasurementFile(path, SamplePlate());
  std::vector<BundleWarning> warnings;
  const std::vector<ImageObservation> o = ReadObservationsFromMeasurementFile(path, {}, &warnings);
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o[0].frame, "30-9601");
  EXPECT_EQ(o[0].point_id, "P1");
  EXPECT_EQ(o[0].x_mm, 3.0);
  EXPECT_EQ(o[0].y_mm, -3.0);
  EXPECT_EQ(o[0].sigma_x_mm, 0.002);
  EXPECT_EQ(o[1].point_id, "P4");
  // The origin's line holds the point's row.
  std::vector<std::string> lines;
  std::istringstream in(ReadTextOfInput(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (const ImageObservation& obs : o) {
    const size_t colon = obs.origin.rfind(':');
    ASSERT_EQ(obs.origin.substr(0, colon), path);
    const int line = std::stoi(obs.origin.substr(colon + 1));
    EXPECT_EQ(lines.at(line - 1).rfind(obs.point_id + ",passpoint,measured,", 0), 0u) << lines.at(line - 1);
  }
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].item, "frame 30-9601");
  EXPECT_NE(warnings[0].reason.find("1 measured point(s) of the selected kinds (passpoint)"), std::string::npos);
  EXPECT_NE(warnings[0].reason.find("e.g. 'P3'"), std::string::npos);
}

TEST(BundleInputMeasurements, GivenFrameIdKindsAndErrors) {
  MeasurementObservationOptions options;
  options.frame_id = "F9";
  options.kinds = {PointKind::kStar, PointKind::kPasspoint};
  std::vector<ImageObservation> o = ObservationsFromMeasurementFile(SamplePlate(), "plate.csv", options);
  ASSERT_EQ(o.size(), 3u);
  EXPECT_EQ(o[0].frame, "F9");
  EXPECT_EQ(o[2].point_id, "S1");
  EXPECT_EQ(o[0].origin, "plate.csv");  // no text: no line

  MeasurementFile no_id = SamplePlate();
  no_id.header.plate_id.clear();
  EXPECT_ERROR(ObservationsFromMeasurementFile(no_id, "plate.csv"), "plate.csv: the header's plate_id is empty");

  MeasurementFile shared = SamplePlate();
  shared.points.push_back(Measured("P1", PointKind::kStar, 7.0));
  EXPECT_ERROR(ObservationsFromMeasurementFile(shared, "plate.csv", options), "id 'P1' is both a passpoint and a star");

  TempDir dir;
  MeasurementFile zero = SamplePlate();
  zero.points[5].sigma_y_mm = 0.0;
  const std::string path = dir.file("zero.csv");
  WriteMeasurementFile(path, zero);
  const std::string message = ErrorOf([&] { ReadObservationsFromMeasurementFile(path); });
  EXPECT_NE(message.find(path + ": line "), std::string::npos) << message;
  EXPECT_NE(message.find("passpoint 'P4': sigma_x_mm and sigma_y_mm must be positive"), std::string::npos) << message;
}

// ---------------------------------------------------------------------------
// The checks.

BundleInput Network() {
  // Frames A, B, C see P1..P4; D sees Q1 (only D), Q2 (also A), R1 (also E);
  // E sees R1, R2 (also A), R3 (also B).
  BundleInput input;
  CameraSetup camera;
  camera.name = "cam";
  camera.values[0] = 100.0;
  input.cameras = {camera};
  for (const char* id : {"A", "B", "C", "D", "E"}) input.frames.push_back({id, "cam", {}, {}, {}, {}, false});
  for (const char* f : {"A", "B", "C"}) {
    for (const char* p : {"P1", "P2", "P3", "P4"}) input.observations.push_back(Obs(f, p));
  }
  for (const auto& [f, p] : std::vector<std::pair<const char*, const char*>>{
           {"D", "Q1"}, {"D", "Q2"}, {"A", "Q2"}, {"D", "R1"}, {"E", "R1"},
           {"E", "R2"}, {"A", "R2"}, {"E", "R3"}, {"B", "R3"}}) {
    input.observations.push_back(Obs(f, p));
  }
  for (size_t i = 0; i < input.observations.size(); ++i) {
    input.observations[i].origin = "obs.csv:" + std::to_string(i + 2);
  }
  return input;
}

std::vector<std::string> Items(const std::vector<BundleWarning>& warnings) {
  std::vector<std::string> items;
  for (const BundleWarning& w : warnings) items.push_back(w.item);
  return items;
}

TEST(BundleInputCheck, PointSeenInOneFrameIsLeftOutUnlessControl) {
  BundleInput input = Network();
  input.frames.resize(3);  // A, B, C
  input.observations.resize(12);
  input.observations.push_back(Obs("A", "T1"));  // seen once: left out
  input.observations.back().origin = "obs.csv:40";
  input.observations.push_back(Obs("A", "H1"));  // seen once, but a height control point: kept
  input.ground_points.push_back({"H1", Eigen::Vector3d(1, 2, 3), {std::nullopt, std::nullopt, 0.5}, "gp.csv:2"});
  input.observations.push_back(Obs("B", "N1"));  // seen once, listed without sigmas: left out
  input.ground_points.push_back({"N1", Eigen::Vector3d(1, 2, 3), {}, "gp.csv:3"});
  const CheckedBundleInput checked = CheckBundleInput(input);
  EXPECT_EQ(checked.input.observations.size(), 13u);
  ASSERT_EQ(Items(checked.warnings), (std::vector<std::string>{"point T1", "point N1", "ground point N1"}));
  EXPECT_EQ(checked.warnings[0].reason,
            "seen in frame A only and not a control point: one ray gives 2 equations for its 3 unknowns; its "
            "observation (obs.csv:40) is left out");
  EXPECT_NE(checked.warnings[2].reason.find("left out"), std::string::npos);
  ASSERT_EQ(checked.input.ground_points.size(), 1u);
  EXPECT_EQ(checked.input.ground_points[0].id, "H1");
  EXPECT_EQ(checked.input.frames.size(), 3u);
}

TEST(BundleInputCheck, ThinFramesAndTheCascadeUntilStable) {
  const CheckedBundleInput checked = CheckBundleInput(Network());
  // Q1 is seen once -> D sees 2 -> D left out -> Q2, R1 seen once -> E sees 2 -> E left out -> R2, R3.
  EXPECT_EQ(Items(checked.warnings), (std::vector<std::string>{"point Q1", "frame D", "point Q2", "point R1",
                                                               "frame E", "point R2", "point R3"}));
  EXPECT_EQ(checked.warnings[1].reason,
            "sees 2 point(s) (3 before others were left out): its 6 orientation unknowns need at least 3 points (2 "
            "equations each); left out with its 2 observation(s)");
  EXPECT_EQ(checked.warnings[2].reason,
            "seen in frame A only (its other 1 frame(s) were left out) and not a control point: one ray gives 2 "
            "equations for its 3 unknowns; its observation (obs.csv:16) is left out");
  ASSERT_EQ(checked.input.frames.size(), 3u);
  EXPECT_EQ(checked.input.observations.size(), 12u);
  for (const ImageObservation& o : checked.input.observations) EXPECT_EQ(o.point_id[0], 'P');

  // A lower minimum keeps D and E (each keeps 2 points seen twice) -- only Q1 goes.
  BundleInputCheckOptions two;
  two.min_points_per_frame = 2;
  EXPECT_EQ(Items(CheckBundleInput(Network(), two).warnings), (std::vector<std::string>{"point Q1"}));
  BundleInputCheckOptions zero;
  zero.min_points_per_frame = 0;
  EXPECT_ERROR(CheckBundleInput(Network(), zero), "min_points_per_frame must be at least 1");
}

TEST(BundleInputCheck, FixedFramesAreExemptAndUnobservedOnesGo) {
  BundleInput input = Network();
  input.frames[3].position_m = Eigen::Vector3d(1, 2, 3);
  input.frames[3].angles = PhiOmegaKappaT{};
  input.frames[3].fixed = true;  // D: no unknowns, kept with 2 points
  input.frames.push_back({"Z", "cam", Eigen::Vector3d(4, 5, 6), PhiOmegaKappaT{}, {}, {}, true});  // sees nothing
  const CheckedBundleInput checked = CheckBundleInput(input);
  EXPECT_EQ(Items(checked.warnings), (std::vector<std::string>{"point Q1", "frame Z"}));
  EXPECT_EQ(checked.warnings[1].reason,
            "sees 0 point(s) and no distance names it: a fixed frame with nothing to hold adds nothing; left out");
  EXPECT_EQ(checked.input.frames.size(), 5u);
}

TEST(BundleInputCheck, UnobservedGroundPointsAndDistances) {
  BundleInput input = Network();
  input.frames.resize(3);
  input.observations.resize(12);
  input.ground_points = {
      {"P1", Eigen::Vector3d(0, 0, 0), {0.0, 0.0, 0.0}, "gp.csv:2"},
      {"G_far", Eigen::Vector3d(1, 0, 0), {0.0, 0.0, 0.0}, "gp.csv:3"},   // control, unobserved: left out
      {"G_tied", Eigen::Vector3d(2, 0, 0), {1.0, 1.0, 1.0}, "gp.csv:4"},  // control, distance to A: kept
      {"G_free", Eigen::Vector3d(3, 0, 0), {}, "gp.csv:5"},               // approximation only, distance: left out
  };
  input.distances = {{"G_tied", "A", 10.0, 0.1}, {"G_free", "P2", 5.0, 0.0}, {"P1", "P2", 3.0, 0.01}};
  const CheckedBundleInput checked = CheckBundleInput(input);
  ASSERT_EQ(Items(checked.warnings),
            (std::vector<std::string>{"ground point G_far", "ground point G_tied", "ground point G_free",
                                      "distance G_free-P2"}));
  EXPECT_EQ(checked.warnings[0].reason,
            "not observed in any frame; left out: without an observation or a distance to the network it has no "
            "effect on the adjustment, the datum included");
  EXPECT_EQ(checked.warnings[1].reason,
            "not observed in any frame; kept: the distance to A ties its a-priori coordinates to the network (it acts "
            "on the datum)");
  EXPECT_EQ(checked.warnings[3].reason,
            "G_free is not in the adjustment (left out or never observed); the distance is left out");
  ASSERT_EQ(checked.input.ground_points.size(), 2u);
  EXPECT_EQ(checked.input.ground_points[1].id, "G_tied");
  ASSERT_EQ(checked.input.distances.size(), 2u);
  EXPECT_EQ(checked.input.distances[1].from, "P1");
}

TEST(BundleInputCheck, ErrorsNameTheRecord) {
  BundleInput unknown_frame = Network();
  unknown_frame.observations[5].frame = "F9";
  EXPECT_ERROR(CheckBundleInput(unknown_frame),
               "obs.csv: line 7: observation of point 'P2' names frame 'F9', which no frame lists");

  BundleInput twice = Network();
  twice.observations.push_back(Obs("A", "P1"));
  twice.observations.back().origin = "more.csv:3";
  EXPECT_ERROR(CheckBundleInput(twice), "more.csv: line 3: point 'P1' is observed twice in frame 'A' (also at obs.csv:2)");

  BundleInput frames_twice = Network();
  frames_twice.frames.push_back(frames_twice.frames[0]);
  EXPECT_ERROR(CheckBundleInput(frames_twice), "bundle input: frame 'A' is listed twice");

  BundleInput cameras_twice = Network();
  cameras_twice.cameras.push_back(cameras_twice.cameras[0]);
  EXPECT_ERROR(CheckBundleInput(cameras_twice), "bundle input: camera 'cam' is listed twice");

  BundleInput unknown_camera = Network();
  unknown_camera.frames[2].camera = "other";
  EXPECT_ERROR(CheckBundleInput(unknown_camera), "frame 'C': camera 'other' is not listed (cameras: cam)");

  BundleInput bad_sigma = Network();
  bad_sigma.observations[3].sigma_x_mm = 0.0;
  EXPECT_ERROR(CheckBundleInput(bad_sigma), "obs.csv: line 5: observation of point 'P4' in frame 'A': the standard deviations");

  BundleInput ground_twice = Network();
  ground_twice.ground_points = {{"P1", Eigen::Vector3d::Zero(), {}, "gp.csv:2"},
                                {"P1", Eigen::Vector3d::Zero(), {}, "gp.csv:3"}};
  EXPECT_ERROR(CheckBundleInput(ground_twice), "gp.csv: line 3: ground point 'P1' is listed twice (also at gp.csv:2)");

  BundleInput weighted = Network();
  weighted.cameras[0].states[8] = ParameterState::Weighted(0.0);
  EXPECT_ERROR(CheckBundleInput(weighted), "camera 'cam': b1 is weighted with sigma 0");

  BundleInput not_pd = Network();
  not_pd.frames[0].position_m = Eigen::Vector3d(1, 2, 3);
  not_pd.frames[0].position_covariance_m2 = Eigen::Vector3d(1, 1, 0).asDiagonal();
  EXPECT_ERROR(CheckBundleInput(not_pd), "frame 'A': the position covariance is not positive definite");

  BundleInput fixed = Network();
  fixed.frames[0].fixed = true;
  EXPECT_ERROR(CheckBundleInput(fixed), "frame 'A': a fixed frame needs its position and angles");

  BundleInput distance = Network();
  distance.distances = {{"A", "nowhere", 1.0, 0.0}};
  EXPECT_ERROR(CheckBundleInput(distance), "distance A-nowhere: 'nowhere' is neither a frame nor a point");

  BundleInput empty = Network();
  empty.observations.clear();
  EXPECT_ERROR(CheckBundleInput(empty), "bundle input: no image observations");
}

TEST(BundleInputCheck, FramesNotListedComeFromTheOnlyCamera) {
  BundleInput input = Network();
  input.frames.clear();
  const CheckedBundleInput checked = CheckBundleInput(input);
  ASSERT_EQ(checked.input.frames.size(), 3u);  // D and E left out as before
  EXPECT_EQ(checked.input.frames[0].id, "A");
  EXPECT_EQ(checked.input.frames[0].camera, "cam");
  input.cameras.push_back(input.cameras[0]);
  input.cameras.back().name = "cam2";
  EXPECT_ERROR(CheckBundleInput(input), "no frames are listed and there are 2 cameras: list the frames with their camera");
}

TEST(BundleInputCheck, UnusedCameraIsLeftOut) {
  BundleInput input = Network();
  input.cameras.push_back(input.cameras[0]);
  input.cameras.back().name = "spare";
  const CheckedBundleInput checked = CheckBundleInput(input);
  EXPECT_EQ(checked.warnings.back().item, "camera spare");
  EXPECT_EQ(checked.warnings.back().reason, "no kept frame uses it; left out");
  ASSERT_EQ(checked.input.cameras.size(), 1u);
}

// ---------------------------------------------------------------------------
// Gyer's station covariance (seed 000 section 3.3).

TEST(StationCovariance, EigenvectorsAreTheTrackTriadAndEigenvaluesTheSigmasSquared) {
  const Eigen::Vector3d position(1.2e6, -0.9e6, 0.8e6);
  const Eigen::Vector3d velocity(300.0, 1200.0, -800.0);
  const double s_in = 50.0, s_cross = 20.0, s_radial = 5.0;
  const Eigen::Matrix3d c = StationCovarianceFromTrack(position, velocity, s_in, s_cross, s_radial);
  EXPECT_LT((c - c.transpose()).norm(), 1e-12);
  const Eigen::Vector3d radial = position.normalized();
  const Eigen::Vector3d in_track = (velocity - velocity.dot(radial) * radial).normalized();
  const Eigen::Vector3d cross = radial.cross(in_track);
  EXPECT_NEAR(in_track.cross(cross).dot(radial), 1.0, 1e-12);  // (in, cross, radial) right-handed
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(c);
  // Ascending: radial, cross-track, in-track.
  EXPECT_NEAR(eigen.eigenvalues()[0], s_radial * s_radial, 1e-9);
  EXPECT_NEAR(eigen.eigenvalues()[1], s_cross * s_cross, 1e-9);
  EXPECT_NEAR(eigen.eigenvalues()[2], s_in * s_in, 1e-9);
  EXPECT_NEAR(std::abs(eigen.eigenvectors().col(0).dot(radial)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(eigen.eigenvectors().col(1).dot(cross)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(eigen.eigenvectors().col(2).dot(in_track)), 1.0, 1e-12);
  // Each direction's variance directly.
  EXPECT_NEAR(radial.dot(c * radial), s_radial * s_radial, 1e-9);
  EXPECT_NEAR(in_track.dot(c * in_track), s_in * s_in, 1e-9);
  EXPECT_NEAR(cross.dot(c * in_track), 0.0, 1e-9);
}

TEST(StationCovariance, HandComputedCase) {
  // Station on +X; velocity (7, 1, 1): its radial part (7, 0, 0) removed, the
  // track runs along (0, 1, 1)/sqrt2, cross-track = X x track = (0, -1, 1)/sqrt2.
  // C = 9 t t^T + 4 c c^T + 1 r r^T = [[1, 0, 0], [0, 6.5, 2.5], [0, 2.5, 6.5]].
  const Eigen::Matrix3d c = StationCovarianceFromTrack(Eigen::Vector3d(1737e3, 0, 0), Eigen::Vector3d(7, 1, 1),
                                                       3.0, 2.0, 1.0);
  Eigen::Matrix3d expected;
  expected << 1, 0, 0, 0, 6.5, 2.5, 0, 2.5, 6.5;
  EXPECT_LT((c - expected).cwiseAbs().maxCoeff(), 1e-12) << c;
}

TEST(StationCovariance, RefusesWhatHasNoTriad) {
  const Eigen::Vector3d v(0, 1600, 0);
  EXPECT_ERROR(StationCovarianceFromTrack(Eigen::Vector3d::Zero(), v, 1, 1, 1), "station is at the object frame's origin");
  EXPECT_ERROR(StationCovarianceFromTrack(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(5, 0, 0), 1, 1, 1),
               "the velocity is zero or radial");
  EXPECT_ERROR(StationCovarianceFromTrack(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), 1, 1, 1),
               "the velocity is zero or radial");
  EXPECT_ERROR(StationCovarianceFromTrack(Eigen::Vector3d(1, 0, 0), v, 0, 1, 1), "sigmas must be positive");
}

// ---------------------------------------------------------------------------
// BundleOptions.

TEST(BundleOptions, DatumNamesAndChecks) {
  for (DatumKind kind : {DatumKind::kAuto, DatumKind::kControlPoints, DatumKind::kFixedFrames,
                         DatumKind::kInnerConstraints}) {
    DatumKind back = DatumKind::kAuto;
    ASSERT_TRUE(ParseDatumKind(DatumKindName(kind), &back)) << DatumKindName(kind);
    EXPECT_EQ(back, kind);
  }
  EXPECT_STREQ(DatumKindName(DatumKind::kControlPoints), "control");
  EXPECT_FALSE(ParseDatumKind("free", nullptr));
  std::string why;
  EXPECT_TRUE(BundleOptions{}.Check(&why)) << why;
  auto fails = [](auto change, const char* expected) {
    BundleOptions o;
    change(o);
    std::string reason;
    EXPECT_FALSE(o.Check(&reason));
    EXPECT_NE(reason.find(expected), std::string::npos) << reason;
  };
  fails([](BundleOptions& o) { o.adjustment.robust_loss_scale = -1; }, "robust_loss_scale");
  fails([](BundleOptions& o) { o.adjustment.rejection_threshold = -1; }, "rejection_threshold");
  fails([](BundleOptions& o) { o.adjustment.false_rejection_rate = 0; }, "false_rejection_rate");
  fails([](BundleOptions& o) { o.adjustment.max_iterations = 0; }, "max_iterations");
  fails([](BundleOptions& o) { o.adjustment.function_tolerance = 0; }, "function_tolerance");
  fails([](BundleOptions& o) { o.adjustment.correlation_threshold = 1.5; }, "correlation_threshold");
  fails([](BundleOptions& o) { o.adjustment.significance_level = 1.0; }, "significance_level");
  fails([](BundleOptions& o) { o.adjustment.rank_tolerance = std::nan(""); }, "rank_tolerance");
  fails([](BundleOptions& o) { o.adjustment.num_threads = -1; }, "num_threads");
}

// ---------------------------------------------------------------------------
// Cameras from definitions.

// measured + dx_BA(measured) must be proportional (c_BA / c_lens) to the lens
// model's ideal point, relative to the principal point.
double WorstMismatchMm(const CameraDefinition& definition, const CameraSetup& camera) {
  const CameraModel model = CameraModelFromLensCalibration(*definition.lens);
  const double scale = camera.values[0] / definition.lens->principal_distance_mm;
  double worst = 0.0;
  for (double x : {-27.0, -10.0, 0.5, 13.0, 27.0}) {
    for (double y : {-27.0, -3.0, 8.0, 27.0}) {
      const double xs = x * definition.format_width_mm / 55.0, ys = y * definition.format_height_mm / 55.0;
      const Eigen::Vector2d ideal = *model.IdealFromMeasured(Eigen::Vector2d(xs, ys));
      const double xb = xs - camera.values[1], yb = ys - camera.values[2];
      double dx = 0, dy = 0;
      BrownAffine::Apply(camera.values.data() + 3, xb, yb, &dx, &dy);
      worst = std::max(worst, std::hypot(xb + dx - scale * ideal.x(), yb + dy - scale * ideal.y()));
    }
  }
  return worst;
}

TEST(BundleInputCamera, DefinitionsConvertExactlyOrWithTheFitsResidual) {
  const DefinitionRegistry registry;
  std::vector<BundleWarning> warnings;
  const CameraDefinition& hasselblad = registry.Camera("hasselblad-500");
  const CameraSetup h = CameraSetupFromDefinition(hasselblad, "", &warnings);
  EXPECT_EQ(h.name, "hasselblad-500");
  EXPECT_EQ(h.format_width_mm, 55.0);
  EXPECT_NEAR(h.values[0], 507.306 / (1 - 0.14741e-1), 1e-9);
  EXPECT_NEAR(h.values[3], 0.17241e-4 / (1 - 0.14741e-1), 1e-18);
  EXPECT_LT(WorstMismatchMm(hasselblad, h), 1e-12);
  for (const ParameterState& s : h.states) EXPECT_EQ(s.kind, ParameterState::Kind::kFixed);
  EXPECT_TRUE(warnings.empty());

  const CameraDefinition& sn004 = registry.Camera("sn004-terrain");
  const CameraSetup s = CameraSetupFromDefinition(sn004, "terrain", &warnings);
  EXPECT_EQ(s.name, "terrain");
  EXPECT_NEAR(s.values[6], -0.3821279e-06 * std::sin(3.371325), 1e-20);
  EXPECT_NEAR(s.values[7], 0.3821279e-06 * std::cos(3.371325), 1e-20);
  EXPECT_LT(WorstMismatchMm(sn004, s), 1e-9);  // J2 = 1.2e-20 / mm^3 is below a picometre
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].reason.find("J2"), std::string::npos);

  warnings.clear();
  const CameraDefinition& orbigon = registry.Camera("orbigon");
  const CameraSetup o = CameraSetupFromDefinition(orbigon, "", &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].reason.find("fitted over the 114 x 114 mm format, RMS"), std::string::npos)
      << warnings[0].reason;
  EXPECT_LT(WorstMismatchMm(orbigon, o), 0.005) << warnings[0].reason;
  EXPECT_NEAR(o.values[0], 80.17103, 0.05);
}

// ---------------------------------------------------------------------------
// The job file.

// The ```toml block after "### Example" in docs/bundle-job.md.
std::string DocsExample() {
  const std::string doc = ReadTextOfInput(std::string(PLATEMETER_SOURCE_DIR) + "/docs/bundle-job.md");
  const size_t section = doc.find("### Example");
  EXPECT_NE(section, std::string::npos);
  const size_t begin = doc.find("```toml\n", section);
  EXPECT_NE(begin, std::string::npos);
  const size_t end = doc.find("```\n", begin + 8);
  return doc.substr(begin + 8, end - begin - 8);
}

// The files the example names: each frame sees P1..P5, all seen at least twice.
void WriteExampleFiles(const TempDir& dir) {
  std::vector<ImageObservation> observations;
  for (const char* frame : {"27-9515", "28-9565"}) {
    for (int i = 1; i <= 5; ++i) observations.push_back(Obs(frame, "P" + std::to_string(i), i, -i));
  }
  WriteObservationsCsv(dir.file("observations.csv"), observations);
  WriteGroundPointsCsv(dir.file("ground_points.csv"),
                       {{"P1", Eigen::Vector3d(1736512.25, -20450.5, 88034.75), {0.0, 0.0, 0.0}, ""},
                        {"P2", Eigen::Vector3d(1736980.5, -18012, 89911.25), {5.0, 5.0, 2.0}, ""}});
  MeasurementFile plate;
  plate.header.plate_id = "30-9601";
  for (int i = 1; i <= 4; ++i) plate.points.push_back(Measured("P" + std::to_string(i), PointKind::kPasspoint, i));
  plate.points.push_back(Measured("X1Y1", PointKind::kReseau, 9.0));
  std::filesystem::create_directories(dir.file("plates"));
  WriteMeasurementFile(dir.file("plates/30-9601.csv"), plate);
}

TEST(BundleJob, TheDocsExampleParsesAndEveryKeyArrives) {
  TempDir dir;
  WriteExampleFiles(dir);
  const std::string path = dir.file("bundle.toml");
  WriteText(path, DocsExample());
  const BundleJob job = ReadBundleJob(path);
  EXPECT_EQ(job.source, path);
  EXPECT_EQ(job.output.title, "Apollo 14 Hasselblad 500 mm: self-calibration with positional constraints");
  EXPECT_EQ(job.output.balance_radius_mm, 30.0);
  EXPECT_EQ(job.output.export_pixel_size_um, 7.5);
  EXPECT_EQ(job.output.export_image_size_px, (std::array<int, 2>{7334, 7334}));
  EXPECT_EQ(job.options.datum, DatumKind::kAuto);
  EXPECT_EQ(job.options.adjustment.robust_loss_scale, 3.0);
  EXPECT_EQ(job.options.adjustment.rejection_threshold, 4.0);
  EXPECT_EQ(job.options.adjustment.max_iterations, 50);
  EXPECT_EQ(job.options.adjustment.function_tolerance, 1e-10);
  EXPECT_EQ(job.options.adjustment.correlation_threshold, 0.95);
  EXPECT_EQ(job.options.adjustment.significance_level, 0.05);
  EXPECT_EQ(job.options.adjustment.rank_tolerance, 1e-12);
  EXPECT_EQ(job.options.adjustment.num_threads, 2);
  EXPECT_EQ(job.check_options.min_points_per_frame, 3);

  ASSERT_EQ(job.input.cameras.size(), 1u);
  const CameraSetup& camera = job.input.cameras[0];
  using Kind = ParameterState::Kind;
  EXPECT_EQ(camera.name, "hasselblad");
  EXPECT_EQ(camera.format_width_mm, 55.0);
  EXPECT_EQ(camera.values[0], 500.0);
  EXPECT_EQ(camera.states[0].kind, Kind::kFree);
  EXPECT_EQ(camera.states[1].kind, Kind::kFixed);
  EXPECT_EQ(camera.states[3].kind, Kind::kFree);
  EXPECT_NEAR(camera.values[3], 0.17241e-4 / (1 - 0.14741e-1), 1e-18);  // from the definition
  EXPECT_EQ(camera.values[4], 0.0);
  EXPECT_EQ(camera.states[4].kind, Kind::kFixed);
  EXPECT_EQ(camera.values[5], 0.0);
  EXPECT_EQ(camera.states[6].kind, Kind::kFree);
  EXPECT_NE(camera.values[6], 0.0);
  EXPECT_EQ(camera.states[8].kind, Kind::kWeighted);
  EXPECT_EQ(camera.states[8].sigma, 1e-4);
  EXPECT_EQ(camera.states[9].kind, Kind::kFixed);

  ASSERT_EQ(job.input.frames.size(), 3u);
  const double rad = std::numbers::pi / 180.0;
  const FrameSetup& f0 = job.input.frames[0];
  EXPECT_EQ(f0.id, "27-9515");
  EXPECT_EQ(f0.camera, "hasselblad");
  EXPECT_EQ(*f0.position_m, Eigen::Vector3d(1849000.0, -52000.0, 31000.0));
  EXPECT_DOUBLE_EQ(f0.angles->phi_rad, 38.5 * rad);
  EXPECT_DOUBLE_EQ(f0.angles->omega_rad, -1.2 * rad);
  EXPECT_DOUBLE_EQ(f0.angles->kappa_rad, 90.4 * rad);
  EXPECT_EQ(*f0.position_covariance_m2,
            StationCovarianceFromTrack(*f0.position_m, Eigen::Vector3d(45.0, 1625.0, -20.0), 50.0, 30.0, 20.0));
  EXPECT_LT((*f0.angle_sigma_rad - Eigen::Vector3d(0.5, 0.5, 1.0) * rad).norm(), 1e-15);
  EXPECT_FALSE(f0.fixed);
  const FrameSetup& f1 = job.input.frames[1];
  EXPECT_EQ(f1.camera, "hasselblad");  // the only camera
  EXPECT_TRUE(f1.fixed);
  EXPECT_FALSE(f1.position_covariance_m2.has_value());
  const FrameSetup& f2 = job.input.frames[2];
  EXPECT_EQ(f2.id, "30-9601");  // the file's plate_id
  EXPECT_EQ(*f2.position_covariance_m2, Eigen::Matrix3d(Eigen::Vector3d::Constant(1e4).asDiagonal()));
  EXPECT_FALSE(f2.angles.has_value());

  ASSERT_EQ(job.input.distances.size(), 1u);
  EXPECT_EQ(job.input.distances[0].from, "27-9515");
  EXPECT_EQ(job.input.distances[0].distance_m, 53258.7);
  EXPECT_EQ(job.input.distances[0].sigma_m, 10.0);

  EXPECT_EQ(job.input.observations.size(), 14u);  // 10 from the CSV, 4 passpoints (no reseau)
  EXPECT_EQ(job.input.observations[0].origin, dir.file("observations.csv") + ":2");
  EXPECT_EQ(job.input.observations.back().frame, "30-9601");
  EXPECT_EQ(job.input.ground_points.size(), 2u);
  EXPECT_TRUE(job.warnings.empty()) << job.warnings[0].item << ": " << job.warnings[0].reason;

  // And it passes the checks: P5 is seen in two frames, every frame sees >= 4 points.
  const CheckedBundleInput checked = CheckBundleInput(job.input);
  EXPECT_TRUE(checked.warnings.empty()) << checked.warnings[0].item << ": " << checked.warnings[0].reason;
  EXPECT_EQ(checked.input.observations.size(), 14u);
}

// The example with one line replaced (or added), read: the error message.
std::string ExampleError(const std::string& from, const std::string& to) {
  TempDir dir;
  WriteExampleFiles(dir);
  std::string text = DocsExample();
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  const std::string path = dir.file("bundle.toml");
  WriteText(path, text);
  return ErrorOf([&] { ReadBundleJob(path); });
}

int LineOfText(const std::string& text, const std::string& needle) {
  const size_t at = text.find(needle);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

TEST(BundleJob, UnknownKeysAndBadValuesNameTheLine) {
  const std::string text = DocsExample();
  const int position_line = LineOfText(text, "position_m = [1849000.0");
  std::string message = ExampleError("position_m = [1849000.0", "postion_m = [1849000.0");
  EXPECT_NE(message.find("bundle.toml: line " + std::to_string(position_line) + ": unknown key 'frame.postion_m'"),
            std::string::npos)
      << message;
  const int datum_line = LineOfText(text, "datum = \"auto\"");
  message = ExampleError("datum = \"auto\"", "datum = \"free\"");
  EXPECT_NE(message.find("line " + std::to_string(datum_line) +
                         ": key 'adjustment.datum' = 'free' must be one of auto, control, fixed-frames, "
                         "inner-constraints"),
            std::string::npos)
      << message;
  EXPECT_NE(ExampleError("[checks]", "[checks]\nstrict = true").find("unknown key 'checks.strict'"), std::string::npos);
  EXPECT_NE(ExampleError("k1_per_mm2 = \"free\"", "k1_per_mm2 = \"loose\"")
                .find("key 'camera.k1_per_mm2' = 'loose' must be \"free\" or \"fixed\""),
            std::string::npos);
  EXPECT_NE(ExampleError("b1 = { value = 0.0, sigma = 1e-4 }", "b1 = { value = 0.0, state = \"free\", sigma = 1e-4 }")
                .find("key 'camera.b1.state' = 'free' takes no sigma"),
            std::string::npos);
  EXPECT_NE(ExampleError("b2 = { sigma = 0 }", "b2 = { sigam = 0 }").find("unknown key 'camera.b2.sigam'"),
            std::string::npos);
  EXPECT_NE(ExampleError("from = \"hasselblad-500\"", "from = \"hasselblad-5000\"")
                .find("key 'camera.from' = 'hasselblad-5000' is not a known camera (known: "),
            std::string::npos);
  EXPECT_NE(ExampleError("max_iterations = 50", "max_iterations = 0.5").find("key 'adjustment.max_iterations' must be an integer"),
            std::string::npos);
  EXPECT_NE(ExampleError("significance_level = 0.05", "significance_level = 0.9")
                .find("key 'adjustment.significance_level' = 0.9 must lie in (0, 0.5]"),
            std::string::npos);
  EXPECT_NE(ExampleError("angles_deg = [38.5, -1.2, 90.4]", "angles_deg = [38.5, -1.2]")
                .find("key 'frame.angles_deg' must be an array of 3 numbers"),
            std::string::npos);
}

TEST(BundleJob, StructuralErrors) {
  EXPECT_NE(ExampleError("[[frame]]\nid = \"28-9565\"", "[[frame]]\nid = \"27-9515\"")
                .find("frame '27-9515' is listed twice (first on line"),
            std::string::npos);
  EXPECT_NE(ExampleError("id = \"28-9565\"\n", "id = \"28-9565\"\ncamera = \"zeiss\"\n")
                .find("frame '28-9565' names camera 'zeiss', which no [[camera]] defines (hasselblad)"),
            std::string::npos);
  EXPECT_NE(ExampleError("kinds = [\"passpoint\"]", "kinds = [\"reseau\"]")
                .find("key 'frame.kinds' = 'reseau': reseau crosses and fiducials are plate references"),
            std::string::npos);
  EXPECT_NE(ExampleError("position_sigma_m = [100.0, 100.0, 100.0]",
                         "position_sigma_m = [100.0, 100.0, 100.0]\nradial_sigma_m = 3.0")
                .find("frame '30-9601': give the position's sigmas one way"),
            std::string::npos);
  EXPECT_NE(ExampleError("velocity_m_per_s = [45.0, 1625.0, -20.0]", "velocity_m_per_s = [1849000.0, -52000.0, 31000.0]")
                .find("(frame '27-9515'): the velocity is zero or radial"),
            std::string::npos);
  EXPECT_NE(ExampleError("fixed = true", "fixed = true\nangle_sigma_deg = [1.0, 1.0, 1.0]")
                .find("key 'frame.fixed' = true takes no position or angle sigmas"),
            std::string::npos);
  EXPECT_NE(ExampleError("[[distance]]", "[distance]").find("'distance' must be an array of tables, written [[distance]]"),
            std::string::npos);
  EXPECT_NE(ExampleError("sigma_m = 10.0", "").find("[[distance]] needs sigma_m"), std::string::npos);
  EXPECT_NE(ExampleError("export_image_size_px = [7334, 7334]", "")
                .find("the pixel camera export needs both export_pixel_size_um and export_image_size_px"),
            std::string::npos);
  EXPECT_NE(ExampleError("name = \"hasselblad\"", "name = \"hasselblad\"\nname = \"again\"").find("bundle.toml: line "),
            std::string::npos);  // TOML syntax: a redefined key
  // Errors inside the named files name those files.
  EXPECT_NE(ExampleError("observations = [\"observations.csv\"]", "observations = [\"missing.csv\"]")
                .find("missing.csv: cannot open the observations file"),
            std::string::npos);
}

TEST(BundleJob, ErrorsInNamedFilesNameThoseFiles) {
  TempDir dir;
  WriteExampleFiles(dir);
  WriteText(dir.file("observations.csv"), "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\nF1,P1,1,2,0,1\n");
  const std::string path = dir.file("bundle.toml");
  WriteText(path, DocsExample());
  EXPECT_ERROR(ReadBundleJob(path), dir.file("observations.csv") + ": line 2, column 5 (sigma_x_mm)");
}

TEST(BundleJob, MinimalJobWithoutFrames) {
  TempDir dir;
  WriteText(dir.file("sub/obs.csv"), "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\nF1,P1,1,2,0.01,0.01\n");
  const std::string path = dir.file("job.toml");
  WriteText(path, "observations = \"sub/obs.csv\"\n[[camera]]\nname = \"c\"\nc_mm = 80.0\nk1_per_mm2 = \"free\"\n");
  const BundleJob job = ReadBundleJob(path);
  EXPECT_EQ(job.output.title, "job");
  ASSERT_EQ(job.input.cameras.size(), 1u);
  EXPECT_EQ(job.input.cameras[0].values[0], 80.0);
  EXPECT_EQ(job.input.cameras[0].states[3].kind, ParameterState::Kind::kFree);
  EXPECT_EQ(job.input.cameras[0].format_width_mm, 0.0);
  EXPECT_TRUE(job.input.frames.empty());
  ASSERT_EQ(job.input.observations.size(), 1u);

  WriteText(path, "observations = \"sub/obs.csv\"\n[[camera]]\nname = \"c\"\n");
  EXPECT_ERROR(ReadBundleJob(path), "line 2: [[camera]] 'c' needs c_mm (the initial principal distance)");
  WriteText(path, "[[camera]]\nname = \"c\"\nc_mm = 80.0\n");
  EXPECT_ERROR(ReadBundleJob(path), "no observations: give observations");
  WriteText(path, "observations = \"sub/obs.csv\"\n");
  EXPECT_ERROR(ReadBundleJob(path), "no [[camera]]");
  EXPECT_ERROR(ReadBundleJob(dir.file("none.toml")), "no such bundle job file");
}

// ---------------------------------------------------------------------------
// Issue #28: CSV numbers range-checked where they enter; ids valid UTF-8
// without control characters.
TEST(BundleCsvRanges, ObservationsOutsideTheAcceptedRangesAreRefused) {
  const std::string header = "frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\n";
  EXPECT_ERROR(ParseObservationsCsv(header + "F1,P1,1e307,2,0.003,0.003\n", "obs.csv"),
               "obs.csv: line 2, column 3 (x_mm): '1e307' is outside the accepted range -10000..10000 mm");
  EXPECT_ERROR(ParseObservationsCsv(header + "F1,P1,1,2,1e155,0.003\n", "obs.csv"),
               "obs.csv: line 2, column 5 (sigma_x_mm): '1e155' is outside the accepted range 0..1000 mm");
  EXPECT_EQ(ParseObservationsCsv(header + "F1,P1,-1e4,1e4,1000,1e-9\n", "obs.csv").size(), 1u);  // the bounds
}

TEST(BundleCsvRanges, GroundPointsOutsideTheAcceptedRangesAreRefused) {
  const std::string header = "point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m\n";
  EXPECT_ERROR(ParseGroundPointsCsv(header + "G1,1,2,-1e300,,,\n", "gp.csv"),
               "gp.csv: line 2, column 4 (z_m): '-1e300' is outside the accepted range -1e30..1e30 m");
  EXPECT_ERROR(ParseGroundPointsCsv(header + "G1,1,2,3,,1e200,\n", "gp.csv"),
               "gp.csv: line 2, column 6 (sigma_y_m): '1e200' is outside the accepted range 0..1e9 m");
}

TEST(BundleCsvText, IdsThatAreNotUtf8OrHoldControlCharactersAreRefused) {
  EXPECT_ERROR(ParseObservationsCsv("frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm\nF1,P\xc0\xaf,1,2,0.1,0.1\n", "obs.csv"),
               "obs.csv: line 2, column 2 (point_id): byte 0xc0 at position 2 is not valid UTF-8");
  EXPECT_ERROR(ParseGroundPointsCsv("point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m\nG\x7f,1,2,3,,,\n", "gp.csv"),
               "gp.csv: line 2, column 1 (point_id): contains the control character 0x7f at position 2");
}

}  // namespace
}  // namespace platemeter
