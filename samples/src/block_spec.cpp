// Reads the block spec (docs/block-simulator.md). Every problem is an Error
// "<file>: line N: <table>: <problem>"; unknown keys are errors.
#include "platemeter/samples/block_spec.h"

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "platemeter/core/error.h"
#include "spec_toml.h"

namespace platemeter::sim {
namespace {

using spec_toml::LineOf;
using spec_toml::Table;

constexpr double kNoLimit = 1e9;

toml::table ParseToml(const std::string& text, const std::string& origin) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw Error(origin, "line " + std::to_string(e.source().begin.line) + ": " + OneLine(std::string(e.description())));
  }
}

std::string ReadText(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the " + what);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

bool PlainName(const std::string& name) {
  static const std::regex kName("[A-Za-z0-9][A-Za-z0-9._-]*");
  return std::regex_match(name, kName);
}

void ReadBlockTable(Table& t, BlockSpec* spec) {
  spec->name = t.RequireString("name");
  if (!PlainName(spec->name)) {
    t.Fail(t.Get("name"), "name '" + spec->name + "' must be a plain file name (letters, digits, '.', '_', '-')");
  }
  spec->description = t.String("description", "");
  spec->frame_spec_path = t.RequireString("frame_spec");
  if (spec->frame_spec_path.empty()) t.Fail(t.Get("frame_spec"), "key 'frame_spec' must name a plate spec file");
  if (const toml::node* node = t.Get("seed")) {
    if (!node->is_integer() || node->as_integer()->get() < 0) t.Fail(node, "key 'seed' must be a non-negative integer");
    spec->seed = static_cast<std::uint64_t>(node->as_integer()->get());
  }
  t.Finish();
}

void ReadCamera(Table& t, BundleCameraTruth* camera) {
  const std::optional<double> c = t.OptionalNumber("c_mm", 1, 10000);
  if (!c) t.Fail(static_cast<const toml::node*>(nullptr), "missing required key 'c_mm' (the true principal distance, mm)");
  camera->c_mm = *c;
  camera->xp_mm = camera->yp_mm = 0.0;
  camera->k1_per_mm2 = camera->k2_per_mm4 = camera->k3_per_mm6 = 0.0;
  camera->p1_per_mm = camera->p2_per_mm = camera->b1 = camera->b2 = 0.0;
  t.Number("xp_mm", &camera->xp_mm, -100, 100);
  t.Number("yp_mm", &camera->yp_mm, -100, 100);
  t.Number("k1_per_mm2", &camera->k1_per_mm2, -1, 1);
  t.Number("k2_per_mm4", &camera->k2_per_mm4, -1, 1);
  t.Number("k3_per_mm6", &camera->k3_per_mm6, -1, 1);
  t.Number("p1_per_mm", &camera->p1_per_mm, -1, 1);
  t.Number("p2_per_mm", &camera->p2_per_mm, -1, 1);
  t.Number("b1", &camera->b1, -0.1, 0.1);
  t.Number("b2", &camera->b2, -0.1, 0.1);
  t.Finish();
}

std::vector<int> Integers(Table& t, const std::string& key, const std::vector<int>& fallback) {
  const toml::node* node = t.Get(key);
  if (!node) return fallback;
  const toml::array* array = node->as_array();
  if (!array || array->empty()) t.Fail(node, "key '" + key + "' must be a non-empty array of integers");
  std::vector<int> out;
  for (const toml::node& item : *array) {
    if (!item.is_integer() || std::abs(item.as_integer()->get()) > 1000000) {
      t.Fail(node, "key '" + key + "' must be an array of integers");
    }
    out.push_back(static_cast<int>(item.as_integer()->get()));
  }
  if (std::set<int>(out.begin(), out.end()).size() != out.size()) t.Fail(node, "key '" + key + "' has a value twice");
  return out;
}

void ReadOrbits(Table& t, LunarBlockOptions* g) {
  double radius_km = g->moon_radius_m * 1e-3, altitude_km = g->altitude_m * 1e-3, spacing_km = g->track_spacing_m * 1e-3;
  t.Number("body_radius_km", &radius_km, 1, 1e6);
  t.Number("altitude_km", &altitude_km, 1e-3, 1e6);
  t.Number("track_spacing_km", &spacing_km, 0, 1e4);
  g->moon_radius_m = radius_km * 1e3;
  g->altitude_m = altitude_km * 1e3;
  g->track_spacing_m = spacing_km * 1e3;
  g->revolutions = Integers(t, "revolutions", g->revolutions);
  t.Integer("exposures_per_orbit", &g->exposures_per_orbit, 2, 50);
  t.Number("convergence_deg", &g->convergence_deg, 1, 170);
  t.Number("kappa_start_deg", &g->kappa_start_deg, -360, 360);
  t.Number("kappa_increment_deg", &g->kappa_increment_deg, -360, 360);
  const std::string sequence = t.String("kappa_sequence", "continuous");
  if (sequence != "continuous" && sequence != "per-orbit") {
    t.Fail(t.Get("kappa_sequence"), "key 'kappa_sequence' = '" + sequence + "' must be \"continuous\" or \"per-orbit\"");
  }
  g->rolls_continue_across_orbits = sequence == "continuous";
  g->frame_ids = t.Strings("frame_ids");
  const std::size_t frames = g->revolutions.size() * static_cast<std::size_t>(g->exposures_per_orbit);
  if (!g->frame_ids.empty() && g->frame_ids.size() != frames) {
    t.Fail(t.Get("frame_ids"), "key 'frame_ids' must name all " + std::to_string(frames) +
                                   " frames (revolutions x exposures_per_orbit)");
  }
  std::set<std::string> seen;
  for (const std::string& id : g->frame_ids) {
    if (!PlainName(id)) t.Fail(t.Get("frame_ids"), "key 'frame_ids': '" + id + "' must be a plain file name");
    if (!seen.insert(id).second) t.Fail(t.Get("frame_ids"), "key 'frame_ids': '" + id + "' is listed twice");
  }
  t.Finish();
}

void ReadPoints(Table& t, BlockSpec* spec) {
  LunarBlockOptions& g = spec->geometry;
  t.Integer("count", &g.passpoints, 1, 10000);
  const int frames = static_cast<int>(g.revolutions.size()) * g.exposures_per_orbit;
  t.Integer("min_frames", &g.min_frames_per_point, 0, frames);
  if (g.min_frames_per_point == 1) t.Fail(t.Get("min_frames"), "key 'min_frames' = 1: a point needs two frames (0 = all)");
  t.Number("relief_m", &g.relief_m, 0, kNoLimit);
  t.Number("format_margin_mm", &g.format_margin_mm, 0, 1000);
  t.Number("min_separation_mm", &spec->min_separation_mm, 0, 100);
  t.Finish();
}

void ReadBundle(Table& t, BlockBundle* bundle) {
  if (t.Get("free")) {
    bundle->free = t.Strings("free");
    std::set<std::string> seen;
    for (const std::string& name : bundle->free) {
      if (BundleParameterName(name).empty()) {
        t.Fail(t.Get("free"), "key 'free': '" + name + "' is not one of c, xp, yp, k1, k2, k3, p1, p2, b1, b2");
      }
      if (!seen.insert(name).second) t.Fail(t.Get("free"), "key 'free': '" + name + "' is listed twice");
    }
  }
  bundle->measured_dir = t.String("measured_dir", bundle->measured_dir);
  const std::filesystem::path measured(bundle->measured_dir);
  if (bundle->measured_dir.empty() || measured.is_absolute() ||
      bundle->measured_dir.find_first_of("\"\\\n\r") != std::string::npos) {
    t.Fail(t.Get("measured_dir"), "key 'measured_dir' must be a relative folder name (inside the output folder)");
  }
  bundle->title = t.String("title", "");
  if (bundle->title.find_first_of("\"\\\n\r") != std::string::npos) {
    t.Fail(t.Get("title"), "key 'title' must be one line without quotes or backslashes");
  }
  bundle->datum = t.String("datum", bundle->datum);
  if (bundle->datum != "auto" && bundle->datum != "control" && bundle->datum != "fixed-frames" &&
      bundle->datum != "inner-constraints") {
    t.Fail(t.Get("datum"), "key 'datum' = '" + bundle->datum +
                               "' must be one of auto, control, fixed-frames, inner-constraints");
  }
  t.Finish();
}

// The tables after [block]; each optional.
void ReadTables(Table& top, const std::string& origin, BlockSpec* spec) {
  LunarBlockOptions& g = spec->geometry;
  if (const toml::table* table = top.SubTable("camera")) {
    Table t(*table, origin, "camera");
    ReadCamera(t, &g.camera);
  } else {
    top.Fail(0, "missing table [camera] (the true camera: c_mm and the distortion)");
  }
  if (const toml::table* table = top.SubTable("orbits")) {
    Table t(*table, origin, "orbits");
    ReadOrbits(t, &g);
  }
  if (const toml::table* table = top.SubTable("points")) {
    Table t(*table, origin, "points");
    ReadPoints(t, spec);
  }
  if (const toml::table* table = top.SubTable("control")) {
    Table t(*table, origin, "control");
    t.Integer("count", &spec->control.count, 0, g.passpoints);
    t.Number("sigma_m", &spec->control.sigma_m, 0, kNoLimit);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("transfer")) {
    Table t(*table, origin, "transfer");
    t.Number("sigma_px", &spec->transfer.sigma_px, 0, 1000);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("frames")) {
    Table t(*table, origin, "frames");
    t.Number("scanner_rotation_sigma_deg", &spec->frames.scanner_rotation_sigma_deg, 0, 5);
    t.Number("film_affine_sigma_ppm", &spec->frames.film_affine_sigma_ppm, 0, 1e4);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("approximations")) {
    Table t(*table, origin, "approximations");
    t.Number("station_sigma_m", &g.approximations.station_sigma_m, 0, kNoLimit);
    t.Number("angle_sigma_deg", &g.approximations.angle_sigma_deg, 0, 10);
    t.Number("point_sigma_m", &g.approximations.point_sigma_m, 0, kNoLimit);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("bundle")) {
    Table t(*table, origin, "bundle");
    ReadBundle(t, &spec->bundle);
  }
}

}  // namespace

std::string BundleParameterName(const std::string& short_name) {
  static const char* kShort[kBundleCameraParams] = {"c", "xp", "yp", "k1", "k2", "k3", "p1", "p2", "b1", "b2"};
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (short_name == kShort[i]) return kBundleCameraParamNames[i];
  }
  return "";
}

BlockSpec ParseBlockSpec(const std::string& text, const std::string& origin) {
  const toml::table root = ParseToml(text, origin);
  BlockSpec spec;
  spec.origin = origin;
  // The block's defaults: seed 000 section 4's orbits (Fig. 3, the rolls
  // carrying on across the orbits), 60 points 2 mm inside the format, images
  // rendered (no added noise: sigma_um 0, weight unused).
  LunarBlockOptions& g = spec.geometry;
  g.passpoints = 60;
  g.format_margin_mm = 2.0;
  g.rolls_continue_across_orbits = true;
  g.sigma_um = 0.0;
  g.weight_sigma_um = 1.0;
  g.approximations.station_sigma_m = 1000.0;
  g.approximations.angle_sigma_deg = 0.5;
  g.approximations.point_sigma_m = 500.0;

  Table top(root, origin, "");
  // A misspelt table is named as such before anything it would have held is missed.
  static const std::set<std::string> kTables = {"block",  "camera",   "orbits",         "points", "control",
                                                "transfer", "frames", "approximations", "bundle"};
  for (const auto& [key, node] : root) {
    if (!kTables.count(std::string(key.str()))) {
      top.Fail(&node, "unknown key '" + std::string(key.str()) +
                          "' (the tables: block, camera, orbits, points, control, transfer, frames, approximations, "
                          "bundle)");
    }
  }
  const toml::table* block = top.SubTable("block");
  if (!block) top.Fail(0, "missing table [block] (name, frame_spec, seed): not a block spec");
  {
    Table t(*block, origin, "block");
    ReadBlockTable(t, &spec);
  }
  ReadTables(top, origin, &spec);
  top.Finish();
  g.seed = spec.seed;
  std::string why;
  if (!g.Check(&why)) top.Fail(0, why);
  if (spec.control.count > g.passpoints) top.Fail(0, "control: count exceeds points.count");

  // The frame spec, relative to the block file's folder.
  const std::filesystem::path frame_spec(spec.frame_spec_path);
  const std::filesystem::path resolved =
      frame_spec.is_absolute() ? frame_spec : std::filesystem::path(origin).parent_path() / frame_spec;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(resolved, ec)) {
    Table t(*block, origin, "block");
    t.Fail(t.Get("frame_spec"), "key 'frame_spec' = '" + spec.frame_spec_path + "': no such file ('" +
                                    resolved.string() + "')");
  }
  spec.frame_spec_path = resolved.lexically_normal().string();
  return spec;
}

BlockSpec ReadBlockSpec(const std::string& path) {
  BlockSpec spec = ParseBlockSpec(ReadText(path, "block spec file"), path);
  spec.frame_spec = ReadSimulationSpec(spec.frame_spec_path);
  return spec;
}

bool IsBlockSpecFile(const std::string& path) {
  const toml::table root = ParseToml(ReadText(path, "spec file"), path);
  return root.contains("block");
}

}  // namespace platemeter::sim
