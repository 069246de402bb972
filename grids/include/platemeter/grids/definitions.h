#pragma once
// Definitions of master grids (reseau plates), fiducial sets and cameras, as
// plain values. They are read from TOML (docs/definitions.md); the built-ins
// (grids/builtin/*.toml) are written in the same format.
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace platemeter {

// Shape of a mark on the plate, as the detectors must look for it.
enum class MarkType { kCross, kDot, kRing, kCorner };
const char* MarkTypeName(MarkType type);
// Parses "cross", "dot", "ring", "corner"; returns false otherwise.
bool ParseMarkType(const std::string& name, MarkType* type);

// How a mark is drawn (the simulator renders it, the detectors model it).
struct MarkShape {
  MarkType type = MarkType::kCross;
  double line_width_um = 20.0;   // um; cross arm or ring line width
  double arm_length_um = 600.0;  // um; cross arm tip to tip, or dot/ring diameter
};

// A calibrated point of a grid or fiducial set, in plate millimetres
// (x right, y up, origin at the grid's centre cross unless the source says otherwise).
struct GridPoint {
  std::string id;  // reseau: X{i}Y{j}, i the column from the left, j the row from the bottom
  double x_mm = 0.0;
  double y_mm = 0.0;
};

struct MasterGrid {
  std::string name;         // e.g. "ikogon-b"
  std::string description;  // one line
  std::string source;       // where the values come from (document, table)
  std::optional<double> calibration_temperature_degC;  // degC at which the values hold
  MarkShape mark;
  int columns = 0;  // i runs 1..columns
  int rows = 0;     // j runs 1..rows
  std::vector<GridPoint> points;
  const GridPoint* Find(const std::string& id) const;
};

struct FiducialMark {
  std::string id;  // as named in the source table (A, B, C, D, A', ...)
  double x_mm = 0.0;
  double y_mm = 0.0;
  MarkShape mark;
};

struct FiducialSet {
  std::string name;
  std::string description;
  std::string source;
  std::vector<FiducialMark> marks;
  const FiducialMark* Find(const std::string& id) const;
};

// A lens calibration as published: the model's name and its coefficients by
// name (names carry units where they have them, e.g. "K1_per_mm2"), with
// standard deviations where the source gives them. The calib/ models read these.
struct LensCalibration {
  std::string model;   // "smac-radial-decentering" (seed 004), "brown-balanced" (seed 000), "orbigon-11" (seed 001)
  std::string source;  // document and table
  double principal_distance_mm = 0.0;  // calibrated focal length
  double principal_point_x_mm = 0.0;   // from the indicated principal point
  double principal_point_y_mm = 0.0;
  std::map<std::string, double> coefficients;
  std::map<std::string, double> sigmas;  // same keys, where given (plus principal_distance_mm etc.)
};

struct CameraDefinition {
  std::string name;
  std::string description;
  std::string source;
  double format_width_mm = 0.0;
  double format_height_mm = 0.0;
  double nominal_principal_distance_mm = 0.0;
  std::string grid;           // master grid name, empty if the camera has no reseau
  std::string fiducial_set;   // fiducial set name, empty if none
  bool format_corners_as_fiducials = false;  // seed 000: corners of the imaged format
  std::optional<double> calibration_temperature_degC;  // degC of the reseau calibration
  double glass_expansion_per_degC = 8.1e-6;  // 1/degC; reseau glass (seed 001's plate coefficient)
  std::optional<LensCalibration> lens;
};

}  // namespace platemeter
