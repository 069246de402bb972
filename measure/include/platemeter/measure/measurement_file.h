#pragma once
// The measurement file (docs/measurement-file.md): one CSV per plate with a
// commented header, written by detect/measure and by the simulator (truth
// files), read by the adjustments. Numbers are written in their shortest
// exact form, so writing and reading back gives the same doubles.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "platemeter/core/point_status.h"

namespace platemeter {

// One row. Empty optionals / strings are empty CSV fields.
struct MeasuredPoint {
  std::string id;  // reseau X{i}Y{j}, fiducial table name, star/passpoint id
  PointKind kind = PointKind::kReseau;
  PointStatus status = PointStatus::kMeasured;
  std::optional<double> x_px, y_px;              // px; scan position (core/pixel.h convention)
  std::optional<double> sigma_x_px, sigma_y_px;  // px; standard deviations
  std::optional<double> x_mm, y_mm;              // mm; plate/camera position (x right, y up)
  std::optional<double> sigma_x_mm, sigma_y_mm;  // mm
  std::vector<std::string> flags;                // e.g. {"saturated", "blended"}, {"rejected:low_contrast"}
  // Kind-specific.
  std::string star_id;               // catalog id of a star or trail image
  std::string trail;                 // trail name (trail_dot, trail_dash)
  std::optional<long> dot;           // index of a dot within its trail
  std::string mid_time_utc;          // ISO 8601 UTC mid-exposure time of the image
  // Truth files only: the Cramer-Rao bound of the position.
  std::optional<double> crb_x_px, crb_y_px;  // px; standard deviations
  std::optional<double> crb_xy_corr;         // correlation of x and y, -1..1
};

// A correction applied to the points, with its parameters in application order.
struct AppliedCorrection {
  std::string name;  // e.g. "thermal", "emulsion_depth", "reseau_fit"
  std::vector<std::pair<std::string, std::string>> parameters;  // name (with unit) -> value
};

struct MeasurementHeader {
  int format_version = 1;
  std::string plate_id;
  std::string scan_file;
  std::string scan_sha256;  // lower-case hex, 64 digits (empty if unknown)
  std::string camera;
  std::optional<double> pixel_size_um;
  std::string software_version;
  std::vector<AppliedCorrection> corrections;
  // Any other "# key: value" lines, kept in order (e.g. truth files' "chain_file").
  std::vector<std::pair<std::string, std::string>> extra;
};

struct MeasurementFile {
  MeasurementHeader header;
  std::vector<MeasuredPoint> points;
  // True when the file carries the truth columns crb_x_px, crb_y_px, crb_xy_corr
  // (the writer adds them also when any point has status truth or a CRB value).
  bool truth_columns = false;
};

// The current format version written by FormatMeasurementFile.
constexpr int kMeasurementFormatVersion = 1;

// The column names, in order (without / with the truth columns).
const std::vector<std::string>& MeasurementColumns(bool truth_columns);

// The file's text. Throws Error("measurement file", reason) for values that
// cannot be written (a comma or newline in a field, a non-finite number,
// an empty or duplicate (kind, id)).
std::string FormatMeasurementFile(const MeasurementFile& file);
// Writes atomically (temporary name + rename).
void WriteMeasurementFile(const std::string& path, const MeasurementFile& file);

// Parses the text; `origin` names it in errors: Error(origin, "line N, column
// C (name): what is wrong"). Rejects unknown columns, wrong column counts,
// bad numbers, unknown kinds/statuses, duplicate (kind, id), newer versions.
MeasurementFile ParseMeasurementFile(const std::string& text, const std::string& origin);
MeasurementFile ReadMeasurementFile(const std::string& path);

}  // namespace platemeter
