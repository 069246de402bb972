// Reads the TOML definition format (docs/definitions.md) into plain structs.
// Every problem is an Error "<file>: line N: <definition>: <problem>", and
// every key a table does not know is an error, so a typo never passes silently.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "platemeter/core/error.h"
#include "platemeter/core/text_input.h"
#include "platemeter/grids/definition_io.h"
#include "definition_table_reader.h"
#include "platemeter/grids/lens_models.h"

namespace platemeter {
namespace {

// um -> mm as the decimal the user wrote means it: -20.50 um is -0.0205 mm, not
// the nearest double to -20.50 / 1000 (which may print as -0.020499999999999997).
double MillimetresFromMicrometres(double value_um) {
  char text[64];
  std::snprintf(text, sizeof text, "%.15g", value_um / 1000.0);
  return std::strtod(text, nullptr);
}

using definition_toml::LineOf;
using definition_toml::TableReader;

// Accepted ranges (docs/definitions.md, "Accepted ranges"): every real plate
// camera fits well inside them; they keep products of the values finite.
constexpr NumberRange kPlateMm{-1000.0, 1000.0, "mm"};           // point and principal point coordinates
constexpr NumberRange kFormatMm{0.0, 1000.0, "mm"};              // format sides, > 0
constexpr NumberRange kSpacingMm{0.01, 1000.0, "mm"};            // lattice spacing
constexpr NumberRange kPrincipalDistanceMm{0.0, 25000.0, "mm"};  // > 0; the longest astrographs are ~20 m
constexpr NumberRange kLineWidthUm{0.0, 1e4, "um"};              // > 0
constexpr NumberRange kArmLengthUm{0.0, 1e5, "um"};              // > 0
constexpr NumberRange kTemperatureDegC{-100.0, 100.0, "degC"};   // as the job file's temperature_degC

// Definition names appear on command lines and in file names: keep them plain.
void CheckName(TableReader& reader, const std::string& kind) {
  const std::string name = reader.RequireString("name");
  // A loop, not std::regex: libstdc++'s matcher recurses per character and
  // overflows the stack on a name of some thousand characters (fuzz finding).
  const auto plain = [](char c, bool first) {
    return std::isalnum(static_cast<unsigned char>(c)) || (!first && (c == '.' || c == '_' || c == '-'));
  };
  bool ok = !name.empty() && name.size() <= 256;
  for (size_t i = 0; ok && i < name.size(); ++i) ok = plain(name[i], i == 0);
  if (!ok) {
    reader.Fail(reader.Get("name"), "name '" + name + "' must be letters, digits, '.', '_' or '-' (at most 256)");
  }
  reader.SetWhat(kind + " '" + name + "'");
}

// Point ids go into CSV files unquoted.
bool PlainId(const std::string& id) {
  if (id.empty()) return false;
  for (unsigned char c : id) {
    if (c <= ' ' || c == ',' || c == '"' || c == 0x7f) return false;
  }
  return true;
}

MarkShape ReadMark(const toml::table& table, const TableReader& parent) {
  TableReader reader(table, parent.origin(), parent.what() + ": mark");
  MarkShape mark;
  const std::string type = reader.RequireString("type");
  if (!ParseMarkType(type, &mark.type)) {
    reader.Fail(reader.Get("type"), "unknown mark type '" + type + "' (known: cross, dot, ring, corner)");
  }
  mark.line_width_um = reader.RequireNumber("line_width_um");
  mark.arm_length_um = reader.RequireNumber("arm_length_um");
  if (mark.line_width_um <= 0.0) reader.Fail(reader.Get("line_width_um"), "line_width_um must be > 0");
  if (mark.arm_length_um <= 0.0) reader.Fail(reader.Get("arm_length_um"), "arm_length_um must be > 0");
  reader.InRange(reader.Get("line_width_um"), "key 'line_width_um'", mark.line_width_um, kLineWidthUm);
  reader.InRange(reader.Get("arm_length_um"), "key 'arm_length_um'", mark.arm_length_um, kArmLengthUm);
  reader.RejectUnknownKeys();
  return mark;
}

// X{i}Y{j} with i, j in 1..999999 without leading zeros.
bool ParseReseauId(const std::string& id, int* i, int* j) {
  size_t at = 0;
  const auto number = [&](char letter, int* value) {
    if (at >= id.size() || id[at] != letter) return false;
    const size_t begin = ++at;
    while (at < id.size() && at - begin < 7 && std::isdigit(static_cast<unsigned char>(id[at]))) ++at;
    if (at == begin || at - begin > 6 || id[begin] == '0') return false;
    *value = std::stoi(id.substr(begin, at - begin));
    return true;
  };
  return number('X', i) && number('Y', j) && at == id.size();
}

struct RawPoint {
  std::string id;
  double x_mm = 0.0, y_mm = 0.0;
  std::optional<MarkShape> mark;
  const toml::node* node = nullptr;
};

// A point is ["id", x_mm, y_mm] or { id = "...", x_mm = ..., y_mm = ... [, mark = {...}] }.
std::vector<RawPoint> ReadPoints(const toml::array& array, const TableReader& parent, bool allow_mark) {
  std::vector<RawPoint> points;
  std::set<std::string> seen;
  for (const toml::node& node : array) {
    RawPoint point;
    point.node = &node;
    if (const toml::array* row = node.as_array()) {
      if (row->size() != 3 || !(*row)[0].is_string()) {
        parent.Fail(&node, "a point must be [\"id\", x_mm, y_mm]");
      }
      point.id = (*row)[0].as_string()->get();
      point.x_mm = parent.InRange(row->get(1), "x_mm of point '" + point.id + "'",
                                  parent.AsNumber(row->get(1), "x_mm of point '" + point.id + "'"), kPlateMm);
      point.y_mm = parent.InRange(row->get(2), "y_mm of point '" + point.id + "'",
                                  parent.AsNumber(row->get(2), "y_mm of point '" + point.id + "'"), kPlateMm);
    } else if (const toml::table* table = node.as_table()) {
      TableReader reader(*table, parent.origin(), parent.what() + ": point");
      point.id = reader.RequireString("id");
      reader.SetWhat(parent.what() + ": point '" + point.id + "'");
      point.x_mm = reader.RequireNumber("x_mm", kPlateMm);
      point.y_mm = reader.RequireNumber("y_mm", kPlateMm);
      if (allow_mark) {
        if (const toml::table* mark = reader.OptionalTable("mark")) point.mark = ReadMark(*mark, reader);
      }
      reader.RejectUnknownKeys();
    } else {
      parent.Fail(&node, "a point must be [\"id\", x_mm, y_mm] or a table");
    }
    if (!PlainId(point.id)) {
      parent.Fail(&node, "point id '" + point.id + "' must be non-empty, without spaces, commas or quotes");
    }
    if (!seen.insert(point.id).second) parent.Fail(&node, "duplicate point id '" + point.id + "'");
    points.push_back(std::move(point));
  }
  return points;
}

void Common(TableReader& reader, std::string* description, std::string* source) {
  *description = reader.RequireString("description");
  *source = reader.RequireString("source");
}

MasterGrid ReadGrid(const toml::table& table, const std::string& origin) {
  TableReader reader(table, origin, "grid");
  CheckName(reader, "grid");
  MasterGrid grid;
  grid.name = reader.RequireString("name");
  Common(reader, &grid.description, &grid.source);
  grid.columns = reader.RequireCount("columns");
  grid.rows = reader.RequireCount("rows");
  grid.calibration_temperature_degC = reader.OptionalNumber("calibration_temperature_degC", kTemperatureDegC);
  grid.mark = ReadMark(reader.RequireTable("mark"), reader);

  const toml::array* points = reader.OptionalArray("points");
  const std::optional<double> spacing_mm = reader.OptionalNumber("spacing_mm");
  if (points && spacing_mm) reader.Fail(reader.Get("spacing_mm"), "give either points or spacing_mm, not both");
  if (!points && !spacing_mm) reader.Fail(reader.line(), "missing 'points' (a list) or 'spacing_mm' (a lattice)");
  if (spacing_mm) {
    if (*spacing_mm <= 0.0) reader.Fail(reader.Get("spacing_mm"), "spacing_mm must be > 0");
    reader.InRange(reader.Get("spacing_mm"), "key 'spacing_mm'", *spacing_mm, kSpacingMm);
    const double half_extent_mm = 0.5 * (std::max(grid.columns, grid.rows) - 1) * *spacing_mm;
    if (!kPlateMm.Contains(half_extent_mm)) {
      reader.Fail(reader.Get("spacing_mm"), "the lattice reaches " + ShortNumber(half_extent_mm) +
                                                " mm from its centre, outside the accepted range " + kPlateMm.Describe());
    }
    if (static_cast<int64_t>(grid.columns) * grid.rows > 1000000) {
      reader.Fail(reader.Get("spacing_mm"), "a lattice of more than 1000000 crosses is not a reseau");
    }
    // A regular lattice centred on the grid's centre: i from the left, j from the bottom.
    for (int j = 1; j <= grid.rows; ++j) {
      for (int i = 1; i <= grid.columns; ++i) {
        grid.points.push_back({"X" + std::to_string(i) + "Y" + std::to_string(j),
                               (i - 0.5 * (grid.columns + 1)) * *spacing_mm,
                               (j - 0.5 * (grid.rows + 1)) * *spacing_mm});
      }
    }
  } else {
    for (const RawPoint& point : ReadPoints(*points, reader, false)) {
      int i = 0, j = 0;
      if (!ParseReseauId(point.id, &i, &j)) {
        reader.Fail(point.node, "reseau id '" + point.id + "' is not of the form X{i}Y{j}");
      }
      if (i > grid.columns || j > grid.rows) {
        reader.Fail(point.node, "reseau id '" + point.id + "' is outside the " + std::to_string(grid.columns) +
                                    " columns x " + std::to_string(grid.rows) + " rows");
      }
      grid.points.push_back({point.id, point.x_mm, point.y_mm});
    }
    if (grid.points.empty()) reader.Fail(reader.Get("points"), "points is empty");
  }
  reader.RejectUnknownKeys();
  return grid;
}

FiducialSet ReadFiducialSet(const toml::table& table, const std::string& origin) {
  TableReader reader(table, origin, "fiducial_set");
  CheckName(reader, "fiducial_set");
  FiducialSet set;
  set.name = reader.RequireString("name");
  Common(reader, &set.description, &set.source);
  const MarkShape mark = ReadMark(reader.RequireTable("mark"), reader);
  const toml::array* points = reader.OptionalArray("points");
  if (!points) reader.Fail(reader.line(), "missing required key 'points' (a list)");
  for (const RawPoint& point : ReadPoints(*points, reader, true)) {
    set.marks.push_back({point.id, point.x_mm, point.y_mm, point.mark.value_or(mark)});
  }
  if (set.marks.empty()) reader.Fail(reader.Get("points"), "points is empty");
  reader.RejectUnknownKeys();
  return set;
}

// A lens coefficient's range by its unit suffix (docs/definitions.md): angles
// one turn, a point of symmetry within the plate, dimensionless scale terms
// within +-1; polynomial coefficients within +-1e12 (real ones are many
// orders smaller; the bound keeps K r^6 finite for r up to 1 m).
NumberRange CoefficientRange(const std::string& key) {
  if (key.ends_with("_deg")) return {-360.0, 360.0, "deg"};
  if (key.ends_with("_rad")) return {-6.283185307179586, 6.283185307179586, "rad"};
  if (key.ends_with("_um")) return {kPlateMm.min * 1000.0, kPlateMm.max * 1000.0, "um"};
  if (key.find("_per_") == std::string::npos) return {-1.0, 1.0, ""};
  return {-1e12, 1e12, ""};  // the unit is in the key (K1_per_mm2)
}

// A sigma is at most the largest magnitude its value may have.
NumberRange SigmaRange(const std::string& key) {
  if (key.rfind("principal_distance", 0) == 0 || key.rfind("principal_point", 0) == 0) {
    const double max_mm = key.rfind("principal_distance", 0) == 0 ? kPrincipalDistanceMm.max : kPlateMm.max;
    return key.ends_with("_um") ? NumberRange{0.0, max_mm * 1000.0, "um"} : NumberRange{0.0, max_mm, "mm"};
  }
  const NumberRange value = CoefficientRange(key);
  return {0.0, value.max, value.unit};
}

LensCalibration ReadLens(const toml::table& table, const TableReader& camera) {
  TableReader reader(table, camera.origin(), camera.what() + ": lens");
  LensCalibration lens;
  lens.model = reader.RequireString("model");
  const LensModelInfo* info = FindLensModel(lens.model);
  if (!info) {
    reader.Fail(reader.Get("model"), "unknown lens model '" + lens.model + "' (known: " + KnownLensModelNames() + ")");
  }
  lens.source = reader.RequireString("source");

  // The principal distance and point may be given in mm or, as seed 001 prints them, in um.
  std::map<std::string, std::string> sigma_key_to_struct_key;
  auto read_length = [&](const std::string& stem, double* value_mm) {
    const bool mm = reader.Has(stem + "_mm"), um = reader.Has(stem + "_um");
    if (mm && um) reader.Fail(reader.Get(stem + "_um"), "give " + stem + "_mm or " + stem + "_um, not both");
    if (!mm && !um) reader.Fail(reader.line(), "missing required key '" + stem + "_mm' (or '" + stem + "_um')");
    const NumberRange range_mm = stem == "principal_distance" ? kPrincipalDistanceMm : kPlateMm;
    const NumberRange range_um{range_mm.min * 1000.0, range_mm.max * 1000.0, "um"};
    *value_mm = mm ? reader.RequireNumber(stem + "_mm", range_mm)
                   : MillimetresFromMicrometres(reader.RequireNumber(stem + "_um", range_um));
    sigma_key_to_struct_key[stem + (mm ? "_mm" : "_um")] = stem + "_mm";
  };
  read_length("principal_distance", &lens.principal_distance_mm);
  read_length("principal_point_x", &lens.principal_point_x_mm);
  read_length("principal_point_y", &lens.principal_point_y_mm);
  if (lens.principal_distance_mm <= 0.0) reader.Fail(reader.line(), "the principal distance must be > 0");

  std::string expected_list;
  for (const LensCoefficientInfo& c : info->coefficients) expected_list += (expected_list.empty() ? "" : ", ") + c.key;
  const toml::table& coefficients = reader.RequireTable("coefficients");
  TableReader coefficient_reader(coefficients, camera.origin(), reader.what() + ": coefficients");
  std::set<std::string> expected;
  for (const LensCoefficientInfo& c : info->coefficients) expected.insert(c.key);
  for (auto&& [key, node] : coefficients) {
    const std::string name(key.str());
    if (!expected.count(name)) {
      coefficient_reader.Fail(&node, "unknown coefficient '" + name + "' for model " + lens.model + " (expected: " +
                                         expected_list + ")");
    }
  }
  for (const LensCoefficientInfo& c : info->coefficients) {
    if (!coefficient_reader.Has(c.key)) {
      coefficient_reader.Fail(coefficient_reader.line(), "missing '" + c.key + "' (" + c.meaning + ") for model " +
                                                             lens.model);
    }
    lens.coefficients[c.key] = coefficient_reader.RequireNumber(c.key, CoefficientRange(c.key));
  }

  if (const toml::table* sigmas = reader.OptionalTable("sigmas")) {
    TableReader sigma_reader(*sigmas, camera.origin(), reader.what() + ": sigmas");
    for (auto&& [key, node] : *sigmas) {
      const std::string name(key.str());
      double sigma = sigma_reader.AsNumber(&node, "sigma '" + name + "'");
      if (sigma < 0.0) sigma_reader.Fail(&node, "sigma '" + name + "' must be >= 0");
      sigma_reader.InRange(&node, "sigma '" + name + "'", sigma, SigmaRange(name));
      std::string stored = name;
      if (auto it = sigma_key_to_struct_key.find(name); it != sigma_key_to_struct_key.end()) {
        stored = it->second;
        if (name.ends_with("_um")) sigma = MillimetresFromMicrometres(sigma);
      } else if (!lens.coefficients.count(name)) {
        sigma_reader.Fail(&node, "unknown key '" + name + "': a sigma must name a coefficient or the principal " +
                                     "distance/point as written in this lens table");
      }
      lens.sigmas[stored] = sigma;
    }
  }
  reader.RejectUnknownKeys();
  return lens;
}

CameraDefinition ReadCamera(const toml::table& table, const std::string& origin) {
  TableReader reader(table, origin, "camera");
  CheckName(reader, "camera");
  CameraDefinition camera;
  camera.name = reader.RequireString("name");
  Common(reader, &camera.description, &camera.source);
  auto positive = [&](const std::string& key, const NumberRange& range) {
    const double value = reader.RequireNumber(key);
    if (value <= 0.0) reader.Fail(reader.Get(key), key + " must be > 0");
    return reader.InRange(reader.Get(key), "key '" + key + "'", value, range);
  };
  camera.format_width_mm = positive("format_width_mm", kFormatMm);
  camera.format_height_mm = positive("format_height_mm", kFormatMm);
  camera.nominal_principal_distance_mm = positive("nominal_principal_distance_mm", kPrincipalDistanceMm);
  camera.grid = reader.OptionalString("grid");
  camera.fiducial_set = reader.OptionalString("fiducial_set");
  camera.format_corners_as_fiducials = reader.OptionalBool("format_corners_as_fiducials", false);
  camera.calibration_temperature_degC = reader.OptionalNumber("calibration_temperature_degC", kTemperatureDegC);
  if (const std::optional<double> expansion = reader.OptionalNumber("glass_expansion_per_degC")) {
    if (*expansion < 0.0 || *expansion > 1e-3) {
      reader.Fail(reader.Get("glass_expansion_per_degC"), "glass_expansion_per_degC must be in [0, 1e-3]");
    }
    camera.glass_expansion_per_degC = *expansion;
  }
  if (const toml::table* lens = reader.OptionalTable("lens")) camera.lens = ReadLens(*lens, reader);
  reader.RejectUnknownKeys();
  return camera;
}

}  // namespace

DefinitionFile ReadDefinitions(const std::string& text, const std::string& origin) {
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw Error(origin, "line " + std::to_string(e.source().begin.line) + ": malformed TOML: " +
                            std::string(e.description()));
  }
  DefinitionFile file;
  file.origin = origin;
  std::set<std::string> point_set_names, camera_names;
  auto each_table = [&](const std::string& key, auto&& read) {
    const toml::node* node = root.get(key);
    if (!node) return;
    if (!node->is_array_of_tables()) {
      throw Error(origin, "line " + std::to_string(LineOf(*node)) + ": '" + key + "' must be written as [[" + key +
                              "]] tables");
    }
    for (const toml::node& element : *node->as_array()) read(*element.as_table());
  };
  auto check_unique = [&](std::set<std::string>& names, const std::string& name, const toml::table& table) {
    if (!names.insert(name).second) {
      throw Error(origin, "line " + std::to_string(LineOf(table)) + ": a second definition named '" + name + "'");
    }
  };
  each_table("grid", [&](const toml::table& table) {
    file.grids.push_back(ReadGrid(table, origin));
    file.grid_lines.push_back(LineOf(table));
    check_unique(point_set_names, file.grids.back().name, table);
  });
  each_table("fiducial_set", [&](const toml::table& table) {
    file.fiducial_sets.push_back(ReadFiducialSet(table, origin));
    file.fiducial_set_lines.push_back(LineOf(table));
    check_unique(point_set_names, file.fiducial_sets.back().name, table);
  });
  each_table("camera", [&](const toml::table& table) {
    file.cameras.push_back(ReadCamera(table, origin));
    file.camera_lines.push_back(LineOf(table));
    check_unique(camera_names, file.cameras.back().name, table);
  });
  for (auto&& [key, node] : root) {
    const std::string name(key.str());
    if (name != "grid" && name != "fiducial_set" && name != "camera") {
      throw Error(origin, "line " + std::to_string(key.source().begin.line) + ": unknown key '" + name +
                              "' (a file holds [[grid]], [[fiducial_set]] and [[camera]] tables)");
    }
  }
  if (file.grids.empty() && file.fiducial_sets.empty() && file.cameras.empty()) {
    throw Error(origin, "no definitions (expected [[grid]], [[fiducial_set]] or [[camera]] tables)");
  }
  return file;
}

DefinitionFile ReadDefinitionFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the definition file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path, "cannot read the definition file");
  return ReadDefinitions(buffer.str(), path);
}

}  // namespace platemeter
