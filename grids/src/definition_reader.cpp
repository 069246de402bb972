// Reads the TOML definition format (docs/definitions.md) into plain structs.
// Every problem is an Error "<file>: line N: <definition>: <problem>", and
// every key a table does not know is an error, so a typo never passes silently.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "platemeter/core/error.h"
#include "platemeter/grids/definition_io.h"
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

int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

// Reads the keys of one TOML table and remembers which ones were used, so the
// rest can be reported as unknown.
class TableReader {
 public:
  TableReader(const toml::table& table, const std::string& origin, std::string what)
      : table_(table), origin_(origin), what_(std::move(what)) {}

  [[noreturn]] void Fail(int line, const std::string& problem) const {
    std::string reason;
    if (line > 0) reason = "line " + std::to_string(line) + ": ";
    if (!what_.empty()) reason += what_ + ": ";
    throw Error(origin_, reason + problem);
  }
  [[noreturn]] void Fail(const toml::node* node, const std::string& problem) const {
    Fail(node ? LineOf(*node) : LineOf(table_), problem);
  }

  void SetWhat(std::string what) { what_ = std::move(what); }
  int line() const { return LineOf(table_); }

  const toml::node* Get(const std::string& key) {
    used_.insert(key);
    return table_.get(key);
  }
  bool Has(const std::string& key) const { return table_.contains(key); }

  std::string RequireString(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a string)");
    return AsString(node, key);
  }
  std::string OptionalString(const std::string& key) {
    const toml::node* node = Get(key);
    return node ? AsString(node, key) : std::string();
  }
  std::string AsString(const toml::node* node, const std::string& key) const {
    if (!node->is_string()) Fail(node, "key '" + key + "' must be a string");
    return node->as_string()->get();
  }

  double RequireNumber(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a number)");
    return AsNumber(node, "key '" + key + "'");
  }
  std::optional<double> OptionalNumber(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return std::nullopt;
    return AsNumber(node, "key '" + key + "'");
  }
  // Integers are accepted where a number is expected (x = 0 means 0.0).
  double AsNumber(const toml::node* node, const std::string& name) const {
    double value = 0.0;
    if (node->is_floating_point()) {
      value = node->as_floating_point()->get();
    } else if (node->is_integer()) {
      value = static_cast<double>(node->as_integer()->get());
    } else {
      Fail(node, name + " must be a number");
    }
    if (!std::isfinite(value)) Fail(node, name + " must be a finite number");
    return value;
  }

  int RequireCount(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a positive integer)");
    if (!node->is_integer()) Fail(node, "key '" + key + "' must be an integer");
    const int64_t value = node->as_integer()->get();
    if (value < 1 || value > 100000) Fail(node, "key '" + key + "' must be between 1 and 100000");
    return static_cast<int>(value);
  }

  bool OptionalBool(const std::string& key, bool fallback) {
    const toml::node* node = Get(key);
    if (!node) return fallback;
    if (!node->is_boolean()) Fail(node, "key '" + key + "' must be true or false");
    return node->as_boolean()->get();
  }

  const toml::table* OptionalTable(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return nullptr;
    if (!node->is_table()) Fail(node, "key '" + key + "' must be a table");
    return node->as_table();
  }
  const toml::table& RequireTable(const std::string& key) {
    if (!Has(key)) Fail(line(), "missing required table '" + key + "'");
    return *OptionalTable(key);
  }
  const toml::array* OptionalArray(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return nullptr;
    if (!node->is_array()) Fail(node, "key '" + key + "' must be an array");
    return node->as_array();
  }

  void RejectUnknownKeys() const {
    for (auto&& [key, node] : table_) {
      const std::string name(key.str());
      if (used_.count(name)) continue;
      const int line = key.source().begin.line > 0 ? static_cast<int>(key.source().begin.line) : LineOf(node);
      Fail(line, "unknown key '" + name + "'");
    }
  }

  const std::string& origin() const { return origin_; }
  const std::string& what() const { return what_; }

 private:
  const toml::table& table_;
  const std::string& origin_;
  std::string what_;
  std::set<std::string> used_;
};

// Definition names appear on command lines and in file names: keep them plain.
void CheckName(TableReader& reader, const std::string& kind) {
  const std::string name = reader.RequireString("name");
  static const std::regex pattern("[A-Za-z0-9][A-Za-z0-9._-]*");
  if (!std::regex_match(name, pattern)) {
    reader.Fail(reader.Get("name"), "name '" + name + "' must be letters, digits, '.', '_' or '-'");
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
  reader.RejectUnknownKeys();
  return mark;
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
      point.x_mm = parent.AsNumber(row->get(1), "x_mm of point '" + point.id + "'");
      point.y_mm = parent.AsNumber(row->get(2), "y_mm of point '" + point.id + "'");
    } else if (const toml::table* table = node.as_table()) {
      TableReader reader(*table, parent.origin(), parent.what() + ": point");
      point.id = reader.RequireString("id");
      reader.SetWhat(parent.what() + ": point '" + point.id + "'");
      point.x_mm = reader.RequireNumber("x_mm");
      point.y_mm = reader.RequireNumber("y_mm");
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
  grid.calibration_temperature_degC = reader.OptionalNumber("calibration_temperature_degC");
  grid.mark = ReadMark(reader.RequireTable("mark"), reader);

  const toml::array* points = reader.OptionalArray("points");
  const std::optional<double> spacing_mm = reader.OptionalNumber("spacing_mm");
  if (points && spacing_mm) reader.Fail(reader.Get("spacing_mm"), "give either points or spacing_mm, not both");
  if (!points && !spacing_mm) reader.Fail(reader.line(), "missing 'points' (a list) or 'spacing_mm' (a lattice)");
  if (spacing_mm) {
    if (*spacing_mm <= 0.0) reader.Fail(reader.Get("spacing_mm"), "spacing_mm must be > 0");
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
    static const std::regex reseau_id("X([1-9][0-9]{0,5})Y([1-9][0-9]{0,5})");
    for (const RawPoint& point : ReadPoints(*points, reader, false)) {
      std::smatch match;
      if (!std::regex_match(point.id, match, reseau_id)) {
        reader.Fail(point.node, "reseau id '" + point.id + "' is not of the form X{i}Y{j}");
      }
      const int i = std::stoi(match[1]), j = std::stoi(match[2]);
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
    *value_mm = mm ? reader.RequireNumber(stem + "_mm") : MillimetresFromMicrometres(reader.RequireNumber(stem + "_um"));
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
    lens.coefficients[c.key] = coefficient_reader.RequireNumber(c.key);
  }

  if (const toml::table* sigmas = reader.OptionalTable("sigmas")) {
    TableReader sigma_reader(*sigmas, camera.origin(), reader.what() + ": sigmas");
    for (auto&& [key, node] : *sigmas) {
      const std::string name(key.str());
      double sigma = sigma_reader.AsNumber(&node, "sigma '" + name + "'");
      if (sigma < 0.0) sigma_reader.Fail(&node, "sigma '" + name + "' must be >= 0");
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
  auto positive = [&](const std::string& key) {
    const double value = reader.RequireNumber(key);
    if (value <= 0.0) reader.Fail(reader.Get(key), key + " must be > 0");
    return value;
  };
  camera.format_width_mm = positive("format_width_mm");
  camera.format_height_mm = positive("format_height_mm");
  camera.nominal_principal_distance_mm = positive("nominal_principal_distance_mm");
  camera.grid = reader.OptionalString("grid");
  camera.fiducial_set = reader.OptionalString("fiducial_set");
  camera.format_corners_as_fiducials = reader.OptionalBool("format_corners_as_fiducials", false);
  camera.calibration_temperature_degC = reader.OptionalNumber("calibration_temperature_degC");
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
