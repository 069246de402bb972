// Writes definitions back as TOML (the format ReadDefinitions reads) and
// point sets as CSV. Numbers are written so that reading them back gives the
// same double: coordinates with the fewest decimals that represent every
// point of the set exactly (4 for the seed tables), others in shortest form.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "platemeter/grids/definition_io.h"

namespace platemeter {
namespace {

std::string Fixed(double value, int decimals) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value + 0.0, std::chars_format::fixed, decimals);
  return std::string(buffer, result.ptr);
}

// Shortest text that reads back as `value`, always a TOML float ("80.0", "1e-06").
std::string Shortest(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value + 0.0);  // + 0.0: no "-0"
  std::string text(buffer, result.ptr);
  if (text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}

// The fewest decimals (at least 1) at which every value prints exactly; -1 if
// some value needs more than 12 (then Shortest() is used instead).
int DecimalsFor(const std::vector<double>& values) {
  int decimals = 1;
  for (double value : values) {
    int needed = -1;
    for (int d = 0; d <= 12; ++d) {
      if (std::strtod(Fixed(value, d).c_str(), nullptr) == value) {
        needed = d;
        break;
      }
    }
    if (needed < 0) return -1;
    decimals = std::max(decimals, needed);
  }
  return decimals;
}

class CoordinateFormat {
 public:
  explicit CoordinateFormat(const std::vector<double>& values) : decimals_(DecimalsFor(values)) {}
  std::string operator()(double value) const { return decimals_ < 0 ? Shortest(value) : Fixed(value, decimals_); }

 private:
  int decimals_;
};

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char escape[8];
          std::snprintf(escape, sizeof escape, "\\u%04x", c);
          out += escape;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string MarkToml(const MarkShape& mark) {
  return std::string("{ type = \"") + MarkTypeName(mark.type) + "\", line_width_um = " + Shortest(mark.line_width_um) +
         ", arm_length_um = " + Shortest(mark.arm_length_um) + " }";
}

bool SameMark(const MarkShape& a, const MarkShape& b) {
  return a.type == b.type && a.line_width_um == b.line_width_um && a.arm_length_um == b.arm_length_um;
}

template <typename Point>
CoordinateFormat FormatOf(const std::vector<Point>& points) {
  std::vector<double> values;
  for (const Point& point : points) {
    values.push_back(point.x_mm);
    values.push_back(point.y_mm);
  }
  return CoordinateFormat(values);
}

template <typename Point>
std::string Csv(const std::vector<Point>& points) {
  const CoordinateFormat format = FormatOf(points);
  std::string out = "id,x_mm,y_mm\n";
  for (const Point& point : points) out += point.id + "," + format(point.x_mm) + "," + format(point.y_mm) + "\n";
  return out;
}

}  // namespace

std::string ToToml(const MasterGrid& grid) {
  std::ostringstream out;
  out << "[[grid]]\n"
      << "name = " << Quoted(grid.name) << "\n"
      << "description = " << Quoted(grid.description) << "\n"
      << "source = " << Quoted(grid.source) << "\n"
      << "columns = " << grid.columns << "\n"
      << "rows = " << grid.rows << "\n";
  if (grid.calibration_temperature_degC) {
    out << "calibration_temperature_degC = " << Shortest(*grid.calibration_temperature_degC) << "\n";
  }
  out << "mark = " << MarkToml(grid.mark) << "\n"
      << "points = [\n";
  const CoordinateFormat format = FormatOf(grid.points);
  for (const GridPoint& point : grid.points) {
    out << "  [" << Quoted(point.id) << ", " << format(point.x_mm) << ", " << format(point.y_mm) << "],\n";
  }
  out << "]\n";
  return out.str();
}

std::string ToToml(const FiducialSet& fiducials) {
  std::ostringstream out;
  const MarkShape set_mark = fiducials.marks.empty() ? MarkShape{} : fiducials.marks.front().mark;
  out << "[[fiducial_set]]\n"
      << "name = " << Quoted(fiducials.name) << "\n"
      << "description = " << Quoted(fiducials.description) << "\n"
      << "source = " << Quoted(fiducials.source) << "\n"
      << "mark = " << MarkToml(set_mark) << "\n"
      << "points = [\n";
  const CoordinateFormat format = FormatOf(fiducials.marks);
  for (const FiducialMark& mark : fiducials.marks) {
    if (SameMark(mark.mark, set_mark)) {
      out << "  [" << Quoted(mark.id) << ", " << format(mark.x_mm) << ", " << format(mark.y_mm) << "],\n";
    } else {
      out << "  { id = " << Quoted(mark.id) << ", x_mm = " << format(mark.x_mm) << ", y_mm = " << format(mark.y_mm)
          << ", mark = " << MarkToml(mark.mark) << " },\n";
    }
  }
  out << "]\n";
  return out.str();
}

std::string ToToml(const CameraDefinition& camera) {
  std::ostringstream out;
  out << "[[camera]]\n"
      << "name = " << Quoted(camera.name) << "\n"
      << "description = " << Quoted(camera.description) << "\n"
      << "source = " << Quoted(camera.source) << "\n"
      << "format_width_mm = " << Shortest(camera.format_width_mm) << "\n"
      << "format_height_mm = " << Shortest(camera.format_height_mm) << "\n"
      << "nominal_principal_distance_mm = " << Shortest(camera.nominal_principal_distance_mm) << "\n";
  if (!camera.grid.empty()) out << "grid = " << Quoted(camera.grid) << "\n";
  if (!camera.fiducial_set.empty()) out << "fiducial_set = " << Quoted(camera.fiducial_set) << "\n";
  out << "format_corners_as_fiducials = " << (camera.format_corners_as_fiducials ? "true" : "false") << "\n";
  if (camera.calibration_temperature_degC) {
    out << "calibration_temperature_degC = " << Shortest(*camera.calibration_temperature_degC) << "\n";
  }
  out << "glass_expansion_per_degC = " << Shortest(camera.glass_expansion_per_degC) << "\n";
  if (camera.lens) {
    const LensCalibration& lens = *camera.lens;
    out << "\n[camera.lens]\n"
        << "model = " << Quoted(lens.model) << "\n"
        << "source = " << Quoted(lens.source) << "\n"
        << "principal_distance_mm = " << Shortest(lens.principal_distance_mm) << "\n"
        << "principal_point_x_mm = " << Shortest(lens.principal_point_x_mm) << "\n"
        << "principal_point_y_mm = " << Shortest(lens.principal_point_y_mm) << "\n";
    out << "\n[camera.lens.coefficients]\n";
    for (const auto& [key, value] : lens.coefficients) out << key << " = " << Shortest(value) << "\n";
    if (!lens.sigmas.empty()) {
      out << "\n[camera.lens.sigmas]\n";
      for (const auto& [key, value] : lens.sigmas) out << key << " = " << Shortest(value) << "\n";
    }
  }
  return out.str();
}

std::string ToCsv(const MasterGrid& grid) { return Csv(grid.points); }
std::string ToCsv(const FiducialSet& fiducials) { return Csv(fiducials.marks); }

}  // namespace platemeter
