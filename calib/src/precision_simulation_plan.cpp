// The precision simulation's plan (precision_simulation.h): the struct's
// checks and the TOML reader (docs/precision-simulation.md). Every key is
// checked against its table's list, so a misspelt key is an error with its
// line, never a silent default.
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "platemeter/calib/precision_simulation.h"
#include "platemeter/core/error.h"
#include "platemeter/core/why.h"
#include "toml_job_reader.h"

namespace platemeter {
namespace {

// Short names of the camera parameters, kBundleCameraParamNames order.
constexpr std::array<const char*, kBundleCameraParams> kShortNames = {"c",  "xp", "yp", "k1", "k2",
                                                                      "k3", "p1", "p2", "b1", "b2"};

class PlanReader {
 public:
  explicit PlanReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void Fail(const toml::node* node, const std::string& problem) const {
    const int line = node ? static_cast<int>(node->source().begin.line) : 0;
    throw Error(source_, (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) + problem);
  }

  void CheckKeys(const toml::table& table, const std::string& prefix, const std::vector<std::string>& allowed) const {
    for (const auto& [name, node] : table) {
      const std::string key(name.str());
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        Fail(&node, "unknown key '" + prefix + key + "' (known: " + job_toml::Join(allowed) + "; docs/precision-simulation.md)");
      }
    }
  }

  const toml::table* Table(const toml::table& root, const std::string& name) const {
    const toml::node* node = root.get(name);
    if (!node) return nullptr;
    if (!node->is_table()) Fail(node, "'" + name + "' must be a table, [" + name + "]");
    return node->as_table();
  }

  std::string String(const toml::node& node, const std::string& key) const {
    if (!node.is_string()) Fail(&node, "key '" + key + "' must be a string");
    return node.as_string()->get();
  }

  double Number(const toml::node& node, const std::string& key, double min, double max, bool min_open = false) const {
    double value = 0.0;
    if (node.is_integer()) {
      value = static_cast<double>(node.as_integer()->get());
    } else if (node.is_floating_point()) {
      value = node.as_floating_point()->get();
    } else {
      Fail(&node, "key '" + key + "' must be a number");
    }
    if (!std::isfinite(value) || value > max || (min_open ? value <= min : value < min)) {
      Fail(&node, fmt::format("key '{}' = {:g} must lie in {}{:g}, {:g}]", key, value, min_open ? "(" : "[", min, max));
    }
    return value;
  }

  long Integer(const toml::node& node, const std::string& key, long min, long max) const {
    if (!node.is_integer()) Fail(&node, "key '" + key + "' must be an integer");
    const long value = static_cast<long>(node.as_integer()->get());
    if (value < min || value > max) Fail(&node, fmt::format("key '{}' = {} must lie in {}..{}", key, value, min, max));
    return value;
  }

  std::vector<double> Numbers(const toml::node& node, const std::string& key, double min, double max) const {
    const toml::array* array = node.as_array();
    if (!array || array->empty()) Fail(&node, "key '" + key + "' must be a non-empty array of numbers");
    std::vector<double> out;
    for (const toml::node& item : *array) out.push_back(Number(item, key, min, max));
    return out;
  }

  std::vector<int> Integers(const toml::node& node, const std::string& key, long min, long max) const {
    const toml::array* array = node.as_array();
    if (!array || array->empty()) Fail(&node, "key '" + key + "' must be a non-empty array of integers");
    std::vector<int> out;
    for (const toml::node& item : *array) out.push_back(static_cast<int>(Integer(item, key, min, max)));
    return out;
  }

  // Sets *out when the key is present.
  void Get(const toml::table& t, const std::string& key, double min, double max, double* out, bool open = false) const {
    if (const toml::node* n = t.get(key)) *out = Number(*n, key, min, max, open);
  }
  void GetOptional(const toml::table& t, const std::string& key, double min, double max, std::optional<double>* out,
                   bool open = false) const {
    if (const toml::node* n = t.get(key)) *out = Number(*n, key, min, max, open);
  }
  void GetInt(const toml::table& t, const std::string& key, long min, long max, int* out) const {
    if (const toml::node* n = t.get(key)) *out = static_cast<int>(Integer(*n, key, min, max));
  }

  PrecisionPlan Read(const toml::table& root) const {
    PrecisionPlan plan;
    plan.source = source_;
    CheckKeys(root, "",
              {"title", "camera", "orbits", "passpoints", "errors", "adjustment", "station_constraints", "report",
               "reference", "simulation"});
    if (const toml::node* n = root.get("title")) plan.title = String(*n, "title");

    constexpr double kHuge = 1e300;
    if (const toml::table* t = Table(root, "camera")) {
      CheckKeys(*t, "camera.",
                {"focal_length_mm", "format_width_mm", "format_height_mm", "xp_mm", "yp_mm", "k1_per_mm2",
                 "k2_per_mm4", "k3_per_mm6", "p1_per_mm", "p2_per_mm"});
      Get(*t, "focal_length_mm", 0.0, 1e5, &plan.focal_length_mm, true);
      Get(*t, "format_width_mm", 0.0, 1e4, &plan.format_width_mm, true);
      Get(*t, "format_height_mm", 0.0, 1e4, &plan.format_height_mm, true);
      Get(*t, "xp_mm", -kHuge, kHuge, &plan.xp_mm);
      Get(*t, "yp_mm", -kHuge, kHuge, &plan.yp_mm);
      Get(*t, "k1_per_mm2", -kHuge, kHuge, &plan.k1_per_mm2);
      Get(*t, "k2_per_mm4", -kHuge, kHuge, &plan.k2_per_mm4);
      Get(*t, "k3_per_mm6", -kHuge, kHuge, &plan.k3_per_mm6);
      Get(*t, "p1_per_mm", -kHuge, kHuge, &plan.p1_per_mm);
      Get(*t, "p2_per_mm", -kHuge, kHuge, &plan.p2_per_mm);
    }
    if (const toml::table* t = Table(root, "orbits")) {
      CheckKeys(*t, "orbits.",
                {"body_radius_km", "altitude_km", "count", "track_spacing_km", "revolutions", "exposures_per_orbit",
                 "convergence_deg", "kappa_start_deg", "kappa_increment_deg", "kappa_sequence"});
      Get(*t, "body_radius_km", 0.0, 1e6, &plan.body_radius_km, true);
      Get(*t, "altitude_km", 0.0, 1e6, &plan.altitude_km, true);
      GetInt(*t, "count", 1, 100, &plan.orbits);
      Get(*t, "track_spacing_km", 0.0, 1e5, &plan.track_spacing_km);
      if (const toml::node* n = t->get("revolutions")) {
        plan.revolutions = Integers(*n, "revolutions", -1000000, 1000000);
        if (t->get("count") && static_cast<int>(plan.revolutions.size()) != plan.orbits) {
          Fail(n, fmt::format("key 'revolutions' names {} orbits but 'count' = {}", plan.revolutions.size(),
                              plan.orbits));
        }
        plan.orbits = static_cast<int>(plan.revolutions.size());
      }
      GetInt(*t, "exposures_per_orbit", 2, 100, &plan.exposures_per_orbit);
      Get(*t, "convergence_deg", 0.0, 170.0, &plan.convergence_deg, true);
      Get(*t, "kappa_start_deg", -360.0, 360.0, &plan.kappa_start_deg);
      Get(*t, "kappa_increment_deg", -360.0, 360.0, &plan.kappa_increment_deg);
      if (const toml::node* n = t->get("kappa_sequence")) {
        if (!ParseKappaSequence(String(*n, "kappa_sequence"), &plan.kappa_sequence)) {
          Fail(n, "key 'kappa_sequence' must be \"continuous\" or \"per-orbit\"");
        }
      }
    }
    if (const toml::table* t = Table(root, "passpoints")) {
      CheckKeys(*t, "passpoints.", {"count", "min_frames", "relief_m", "format_margin_mm"});
      GetInt(*t, "count", 1, 1000000, &plan.passpoints);
      GetInt(*t, "min_frames", 0, 10000, &plan.min_frames_per_point);
      Get(*t, "relief_m", 0.0, 1e7, &plan.relief_m);
      Get(*t, "format_margin_mm", 0.0, 1e4, &plan.format_margin_mm);
    }
    if (const toml::table* t = Table(root, "errors")) {
      CheckKeys(*t, "errors.", {"image_sigma_um"});
      Get(*t, "image_sigma_um", 0.0, 1e6, &plan.image_sigma_um, true);
    }
    if (const toml::table* t = Table(root, "adjustment")) {
      CheckKeys(*t, "adjustment.", {"free", "datum"});
      if (const toml::node* n = t->get("free")) {
        const toml::array* array = n->as_array();
        if (!array) Fail(n, "key 'free' must be an array of parameter names, e.g. [\"c\", \"xp\", \"yp\", \"k1\"]");
        plan.free.fill(false);
        for (const toml::node& item : *array) {
          const std::string name = String(item, "free");
          int index = -1;
          for (int i = 0; i < kBundleCameraParams; ++i) {
            if (name == kShortNames[i] || name == kBundleCameraParamNames[i]) index = i;
          }
          if (index < 0) Fail(&item, "key 'free': unknown parameter '" + name + "' (c, xp, yp, k1, k2, k3, p1, p2, b1, b2)");
          plan.free[index] = true;
        }
      }
      if (const toml::node* n = t->get("datum")) {
        if (!ParsePrecisionDatum(String(*n, "datum"), &plan.datum)) {
          Fail(n, "key 'datum' must be \"auto\", \"inner-constraints\" or \"stations\"");
        }
      }
    }
    if (const toml::node* node = root.get("station_constraints")) {
      const toml::array* array = node->as_array();
      if (!array || !array->is_array_of_tables()) {
        Fail(node, "'station_constraints' must be an array of tables, [[station_constraints]]");
      }
      for (const toml::node& item : *array) {
        const toml::table& t = *item.as_table();
        CheckKeys(t, "station_constraints.",
                  {"orbits", "sigma_in_track_m", "sigma_cross_track_m", "sigma_radial_m", "sigma_angle_deg"});
        StationConstraint c;
        if (const toml::node* n = t.get("orbits")) c.orbits = Integers(*n, "orbits", 1, 100);
        for (const char* key : {"sigma_in_track_m", "sigma_cross_track_m", "sigma_radial_m"}) {
          if (!t.get(key)) Fail(&item, std::string("[[station_constraints]] needs '") + key + "'");
        }
        Get(t, "sigma_in_track_m", 0.0, 1e9, &c.sigma_in_track_m, true);
        Get(t, "sigma_cross_track_m", 0.0, 1e9, &c.sigma_cross_track_m, true);
        Get(t, "sigma_radial_m", 0.0, 1e9, &c.sigma_radial_m, true);
        GetOptional(t, "sigma_angle_deg", 0.0, 180.0, &c.sigma_angle_deg, true);
        plan.station_constraints.push_back(std::move(c));
      }
    }
    if (const toml::table* t = Table(root, "report")) {
      CheckKeys(*t, "report.", {"balance", "balance_radius_mm", "radii_mm", "correlation_threshold"});
      if (const toml::node* n = t->get("balance")) {
        const std::string name = String(*n, "balance");
        bool known = false;
        for (RadialBalance b : {RadialBalance::kAsGiven, RadialBalance::kZeroAtRadius, RadialBalance::kEqualLobePeaks,
                                RadialBalance::kEqualLobeAreas}) {
          if (name == RadialBalanceName(b)) plan.balance = b, known = true;
        }
        if (!known) Fail(n, "key 'balance' must be \"as-given\", \"zero-at-radius\", \"equal-lobe-peaks\" or \"equal-lobe-areas\"");
      }
      Get(*t, "balance_radius_mm", 0.0, 1e4, &plan.balance_radius_mm, true);
      if (const toml::node* n = t->get("radii_mm")) plan.radii_mm = Numbers(*n, "radii_mm", 0.0, 1e4);
      Get(*t, "correlation_threshold", 0.0, 1.0, &plan.correlation_threshold);
    }
    if (const toml::table* t = Table(root, "reference")) {
      CheckKeys(*t, "reference.", {"source", "xp_um", "yp_um", "c_prime_um", "radial_corner_um", "decentering_corner_um"});
      if (const toml::node* n = t->get("source")) plan.reference.source = String(*n, "source");
      GetOptional(*t, "xp_um", 0.0, 1e9, &plan.reference.xp_um);
      GetOptional(*t, "yp_um", 0.0, 1e9, &plan.reference.yp_um);
      GetOptional(*t, "c_prime_um", 0.0, 1e9, &plan.reference.c_prime_um);
      GetOptional(*t, "radial_corner_um", 0.0, 1e9, &plan.reference.radial_corner_um);
      GetOptional(*t, "decentering_corner_um", 0.0, 1e9, &plan.reference.decentering_corner_um);
    }
    if (const toml::table* t = Table(root, "simulation")) {
      CheckKeys(*t, "simulation.", {"seed"});
      if (const toml::node* n = t->get("seed")) plan.seed = static_cast<std::uint64_t>(Integer(*n, "seed", 0, 1L << 62));
    }
    std::string why;
    if (!plan.Check(&why)) throw Error(source_, why);
    return plan;
  }

 private:
  std::string source_;
};

}  // namespace

const char* KappaSequenceName(KappaSequence sequence) {
  return sequence == KappaSequence::kContinuous ? "continuous" : "per-orbit";
}

bool ParseKappaSequence(const std::string& name, KappaSequence* sequence) {
  if (name == "continuous") *sequence = KappaSequence::kContinuous;
  else if (name == "per-orbit") *sequence = KappaSequence::kPerOrbit;
  else return false;
  return true;
}

const char* PrecisionDatumName(PrecisionDatum datum) {
  switch (datum) {
    case PrecisionDatum::kAuto: return "auto";
    case PrecisionDatum::kInnerConstraints: return "inner-constraints";
    case PrecisionDatum::kStations: return "stations";
  }
  return "?";
}

bool ParsePrecisionDatum(const std::string& name, PrecisionDatum* datum) {
  for (PrecisionDatum d : {PrecisionDatum::kAuto, PrecisionDatum::kInnerConstraints, PrecisionDatum::kStations}) {
    if (name == PrecisionDatumName(d)) {
      *datum = d;
      return true;
    }
  }
  return false;
}

double PrecisionPlan::CornerRadius_mm() const { return FormatHalfDiagonal_mm(format_width_mm, format_height_mm); }

bool PrecisionPlan::Check(std::string* why) const {
  auto finite = [](std::initializer_list<double> values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
  };
  if (!(focal_length_mm > 0.0) || !(format_width_mm > 0.0) || !(format_height_mm > 0.0) ||
      !finite({focal_length_mm, format_width_mm, format_height_mm})) {
    return Fail(why, "camera.focal_length_mm, format_width_mm and format_height_mm must be positive");
  }
  if (!finite({xp_mm, yp_mm, k1_per_mm2, k2_per_mm4, k3_per_mm6, p1_per_mm, p2_per_mm})) {
    return Fail(why, "the camera's lens values must be finite");
  }
  if (!(body_radius_km > 0.0) || !(altitude_km > 0.0) || !finite({body_radius_km, altitude_km})) {
    return Fail(why, "orbits.body_radius_km and altitude_km must be positive");
  }
  if (orbits < 1) return Fail(why, "orbits.count must be at least 1");
  if (!revolutions.empty() && static_cast<int>(revolutions.size()) != orbits) {
    return Fail(why, "orbits.revolutions must name every orbit");
  }
  if (!revolutions.empty() && std::set<int>(revolutions.begin(), revolutions.end()).size() != revolutions.size()) {
    return Fail(why, "orbits.revolutions must not repeat a revolution");
  }
  if (!(track_spacing_km >= 0.0) || !std::isfinite(track_spacing_km)) {
    return Fail(why, "orbits.track_spacing_km must be >= 0");
  }
  if (exposures_per_orbit < 2) return Fail(why, "orbits.exposures_per_orbit must be at least 2");
  if (!(convergence_deg > 0.0 && convergence_deg < 170.0)) return Fail(why, "orbits.convergence_deg must be in (0, 170)");
  if (!finite({kappa_start_deg, kappa_increment_deg})) return Fail(why, "orbits.kappa angles must be finite");
  const int frames = orbits * exposures_per_orbit;
  if (passpoints < 1) return Fail(why, "passpoints.count must be at least 1");
  if (min_frames_per_point < 0 || min_frames_per_point > frames || min_frames_per_point == 1) {
    return Fail(why, fmt::format("passpoints.min_frames must be 0 (all frames) or in 2..{}", frames));
  }
  if (!(relief_m >= 0.0) || !(relief_m < 1e3 * altitude_km)) {
    return Fail(why, "passpoints.relief_m must be >= 0 and below the altitude");
  }
  if (!(format_margin_mm >= 0.0) || !(2.0 * format_margin_mm < std::min(format_width_mm, format_height_mm))) {
    return Fail(why, "passpoints.format_margin_mm must be >= 0 and smaller than half the format");
  }
  if (!(image_sigma_um > 0.0) || !std::isfinite(image_sigma_um)) return Fail(why, "errors.image_sigma_um must be positive");
  if (std::none_of(free.begin(), free.end(), [](bool b) { return b; })) {
    return Fail(why, "adjustment.free must name at least one camera parameter");
  }
  for (const StationConstraint& c : station_constraints) {
    for (double s : {c.sigma_in_track_m, c.sigma_cross_track_m, c.sigma_radial_m}) {
      if (!(s > 0.0) || !std::isfinite(s)) return Fail(why, "station_constraints sigmas must be positive (m)");
    }
    if (c.sigma_angle_deg && !(*c.sigma_angle_deg > 0.0)) {
      return Fail(why, "station_constraints.sigma_angle_deg must be positive");
    }
    for (int o : c.orbits) {
      if (o < 1 || o > orbits) {
        return Fail(why, fmt::format("station_constraints.orbits names orbit {}; the plan has 1..{}", o, orbits));
      }
    }
  }
  if (datum == PrecisionDatum::kStations && station_constraints.empty()) {
    return Fail(why, "adjustment.datum = \"stations\" needs [[station_constraints]]");
  }
  if (datum == PrecisionDatum::kInnerConstraints && !station_constraints.empty()) {
    return Fail(why, "adjustment.datum = \"inner-constraints\" cannot be combined with [[station_constraints]]: "
                     "the constrained stations fix the datum (use \"stations\" or \"auto\")");
  }
  if (balance == RadialBalance::kZeroAtRadius && !(balance_radius_mm > 0.0)) {
    return Fail(why, "report.balance_radius_mm must be positive");
  }
  for (double r : radii_mm) {
    if (!(r >= 0.0) || !std::isfinite(r)) return Fail(why, "report.radii_mm must be finite and >= 0");
  }
  if (!(correlation_threshold >= 0.0 && correlation_threshold <= 1.0)) {
    return Fail(why, "report.correlation_threshold must be in [0, 1]");
  }
  return true;
}

PrecisionPlan ParsePrecisionPlan(const std::string& toml_text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source);
  } catch (const toml::parse_error& e) {
    throw Error(source, fmt::format("line {}: {}", e.source().begin.line, OneLine(std::string(e.description()))));
  }
  return PlanReader(source).Read(root);
}

PrecisionPlan ReadPrecisionPlan(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the plan file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path, "cannot read the plan file");
  return ParsePrecisionPlan(text.str(), path);
}

}  // namespace platemeter
