// Job definition files (job_file.h, docs/job.md): every key has one setter, shared by
// the TOML reader (typed values, errors with file and line) and the per-scan
// overrides of a manifest (text values).
#include "platemeter/pipeline/job_file.h"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/error.h"
#include "platemeter/core/scan_orientation.h"
#include "platemeter/core/utc_time.h"
#include "platemeter/measure/reseau_fit.h"

namespace platemeter::pipeline {
namespace {

constexpr size_t kMaxUtcLength = 64;

int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

// One key's value: a TOML node (typed) or a manifest cell (text).
class Value {
 public:
  Value(const toml::node& node, const std::string& origin, const std::string& key)
      : node_(&node), origin_(origin), key_(key) {}
  Value(const std::string& text, const std::string& key) : text_(text), origin_("manifest"), key_(key) {}

  [[noreturn]] void Fail(const std::string& problem) const {
    const std::string where = node_ ? "line " + std::to_string(LineOf(*node_)) + ": " : std::string();
    throw Error(origin_, where + "key '" + key_ + "' " + problem);
  }
  bool FromManifest() const { return node_ == nullptr; }
  // A manifest cell left empty.
  bool Empty() const { return !node_ && text_.empty(); }

  std::string String() const {
    if (!node_) return text_;
    if (!node_->is_string()) Fail("must be a string");
    return node_->as_string()->get();
  }
  // One of `allowed`.
  std::string Choice(std::initializer_list<const char*> allowed) const {
    const std::string value = String();
    std::string list;
    for (const char* a : allowed) {
      if (value == a) return value;
      list += std::string(list.empty() ? "" : ", ") + a;
    }
    Fail("= '" + value + "' must be one of " + list);
  }
  double Number(double min, double max) const {
    double value = 0.0;
    if (node_) {
      if (node_->is_integer()) {
        value = static_cast<double>(node_->as_integer()->get());
      } else if (node_->is_floating_point()) {
        value = node_->as_floating_point()->get();
      } else {
        Fail("must be a number");
      }
    } else {
      const char* end = text_.data() + text_.size();
      const auto result = std::from_chars(text_.data(), end, value);
      if (text_.empty() || result.ec != std::errc() || result.ptr != end) Fail("= '" + text_ + "' must be a number");
    }
    if (!std::isfinite(value) || value < min || value > max) {
      std::ostringstream range;
      range << "= " << value << " must lie in " << min << ".." << max;
      Fail(range.str());
    }
    return value;
  }
  bool Bool() const {
    if (node_) {
      if (!node_->is_boolean()) Fail("must be true or false");
      return node_->as_boolean()->get();
    }
    if (text_ == "true") return true;
    if (text_ == "false") return false;
    Fail("= '" + text_ + "' must be true or false");
  }
  // An array of integers (TOML) or a comma-separated list (manifest: "2,3,4"), each in min..max.
  std::vector<int> Integers(int min, int max) const {
    std::vector<int> out;
    auto check = [&](long long n) {
      if (n < min || n > max) {
        Fail("holds " + std::to_string(n) + ", outside the accepted range " + std::to_string(min) + ".." +
             std::to_string(max));
      }
      out.push_back(static_cast<int>(n));
    };
    if (node_) {
      const toml::array* array = node_->as_array();
      if (!array) Fail("must be an array of integers");
      for (const toml::node& item : *array) {
        if (!item.is_integer()) Fail("must be an array of integers");
        check(item.as_integer()->get());
      }
      return out;
    }
    std::stringstream items(text_);
    for (std::string item; std::getline(items, item, ',');) {
      long long n = 0;
      const auto result = std::from_chars(item.data(), item.data() + item.size(), n);
      if (result.ec != std::errc() || result.ptr != item.data() + item.size()) Fail("= '" + text_ + "' must be integers like 2,3,4,5");
      check(n);
    }
    return out;
  }

 private:
  const toml::node* node_ = nullptr;
  std::string text_;
  std::string origin_;
  std::string key_;
};

std::string Orientation(const Value& v) {
  const std::string text = v.String();
  ScanOrientation parsed;
  if (!text.empty() && !ParseScanOrientation(text, &parsed)) v.Fail("= '" + text + "' is not one of " + kScanOrientationNames);
  return text;
}
std::string Model(const Value& v, bool fiducial) {
  if (fiducial) return v.Choice({"similarity", "affine"});
  return v.Choice({"similarity", "affine", "scales", "projective"});
}
TrailRequest& Trails(JobDefinition& job) {
  if (!job.measure.detect.trails) job.measure.detect.trails.emplace();
  return *job.measure.detect.trails;
}
PasspointRequest& Passpoints(JobDefinition& job) {
  if (!job.measure.detect.passpoints) job.measure.detect.passpoints.emplace();
  return *job.measure.detect.passpoints;
}
// The trail program must be one seed 001's Table 1 allows (core/duty_cycle.h).
void CheckTrails(const TrailRequest& trails, const Value& v) {
  DutyCycleScheduleOptions schedule;
  schedule.leading_dashes = trails.leading_dashes;
  schedule.break_s = trails.break_s;
  std::string why;
  if (!schedule.Check(&why)) v.Fail("gives an invalid trail program: " + why);
}
// A path in the job file is relative to the job file's folder.
std::string JobPath(const JobDefinition& job, const std::string& path) {
  if (path.empty() || job.source.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(job.source).parent_path() / path).lexically_normal().string();
}

// Every key of a job file ("table.key" inside a table) and how it sets the definition. Keys of
// [measure] are overridden by their bare name (e.g. "temperature_degC").
struct KeySetter {
  const char* key;
  void (*set)(JobDefinition& job, const Value& value);
};

const std::vector<KeySetter>& Setters() {
  static const std::vector<KeySetter> setters = {
      {"camera", [](JobDefinition& j, const Value& v) { j.measure.detect.camera = v.String(); }},
      {"grid", [](JobDefinition& j, const Value& v) { j.measure.detect.grid = v.String(); }},
      {"pixel_size_um",
       [](JobDefinition& j, const Value& v) {
         if (v.Empty()) return j.measure.detect.pixel_size_um.reset();
         j.measure.detect.pixel_size_um = v.Number(0.01, 10000.0);
       }},
      {"orientation", [](JobDefinition& j, const Value& v) { j.measure.detect.orientation = Orientation(v); }},
      {"allow_ambiguous_orientation", [](JobDefinition& j, const Value& v) { j.measure.detect.allow_ambiguous = v.Bool(); }},
      {"stars.enabled", [](JobDefinition& j, const Value& v) { j.measure.detect.stars = v.Bool(); }},
      {"stars.bright", [](JobDefinition& j, const Value& v) { j.measure.detect.stars_bright = v.Bool(); }},
      {"stars.fwhm_px", [](JobDefinition& j, const Value& v) { j.measure.detect.star_fwhm_px = v.Number(0.5, 100.0); }},
      {"trails.start_utc",
       [](JobDefinition& j, const Value& v) {
         const std::string text = v.String();
         // ISO 8601 is short; core's regex parser recurses per character (stack overflow on huge strings).
         if (text.size() > kMaxUtcLength) v.Fail("is longer than " + std::to_string(kMaxUtcLength) + " characters (not an ISO 8601 time)");
         try {
           ParseUtcIso8601(text);
         } catch (const Error& e) {
           v.Fail("= '" + text + "': " + e.reason());
         }
         Trails(j).start_utc = text;
       }},
      {"trails.leading_dashes",
       [](JobDefinition& j, const Value& v) {
         TrailRequest trails = j.measure.detect.trails.value_or(TrailRequest{});  // j unchanged on a bad value
         trails.leading_dashes = v.Integers(2, 5);  // seed 001's Table 1
         CheckTrails(trails, v);
         Trails(j) = trails;
       }},
      {"trails.break_s",
       [](JobDefinition& j, const Value& v) {
         TrailRequest trails = j.measure.detect.trails.value_or(TrailRequest{});  // j unchanged on a bad value
         trails.break_s = v.Number(0.0, 86400.0);
         CheckTrails(trails, v);
         Trails(j) = trails;
       }},
      {"trails.require_joined", [](JobDefinition& j, const Value& v) { Trails(j).require_joined = v.Bool(); }},
      {"trails.forced_dots", [](JobDefinition& j, const Value& v) { Trails(j).forced_dots = v.Bool(); }},
      {"passpoints.list_file",
       [](JobDefinition& j, const Value& v) {
         Passpoints(j).list_file = v.FromManifest() ? v.String() : JobPath(j, v.String());
       }},
      {"passpoints.shape", [](JobDefinition& j, const Value& v) { Passpoints(j).shape = v.Choice({"dot", "ring"}); }},
      {"passpoints.diameter_um", [](JobDefinition& j, const Value& v) { Passpoints(j).diameter_um = v.Number(0.1, 1e5); }},
      {"passpoints.line_width_um", [](JobDefinition& j, const Value& v) { Passpoints(j).line_width_um = v.Number(0.0, 1e5); }},
      {"passpoints.polarity", [](JobDefinition& j, const Value& v) { Passpoints(j).polarity = v.Choice({"dark", "bright"}); }},
      {"measure.temperature_degC",
       [](JobDefinition& j, const Value& v) {
         if (v.Empty()) return j.measure.temperature_degC.reset();
         j.measure.temperature_degC = v.Number(-100.0, 100.0);
       }},
      {"measure.emulsion_depth_um",
       [](JobDefinition& j, const Value& v) {
         if (v.Empty()) return j.measure.emulsion_depth_um.reset();
         j.measure.emulsion_depth_um = v.Number(0.0, 1000.0);
       }},
      {"measure.refractive_index", [](JobDefinition& j, const Value& v) { j.measure.refractive_index = v.Number(1.0, 3.0); }},
      {"measure.model", [](JobDefinition& j, const Value& v) { j.measure.model = Model(v, false); }},
      {"measure.rejection_threshold",
       [](JobDefinition& j, const Value& v) { j.measure.rejection_threshold = v.Number(1.0, 1e6); }},
      {"measure.tolerance_um", [](JobDefinition& j, const Value& v) { j.measure.tolerance_um = v.Number(0.0, 1e6); }},
      {"measure.local_reseau", [](JobDefinition& j, const Value& v) { j.measure.no_local = !v.Bool(); }},
      {"measure.fiducial_orientation", [](JobDefinition& j, const Value& v) { j.measure.fiducial_orientation = v.Bool(); }},
      {"measure.fiducial_model", [](JobDefinition& j, const Value& v) { j.measure.fiducial_model = Model(v, true); }},
      {"measure.min_cross_fraction",
       [](JobDefinition& j, const Value& v) { j.measure.min_cross_fraction = v.Number(0.0, 1.0); }},
  };
  return setters;
}

const KeySetter* FindSetter(const std::string& key) {
  for (const KeySetter& s : Setters())
    if (key == s.key) return &s;
  return nullptr;
}

// The name a manifest column uses: [measure] keys bare, the others as in the file.
std::string OverrideName(const std::string& key) { return key.rfind("measure.", 0) == 0 ? key.substr(8) : key; }

constexpr const char* kTables[] = {"stars", "trails", "passpoints", "measure"};

void ReadTable(const toml::table& table, const std::string& prefix, const std::string& origin, JobDefinition* job) {
  for (const auto& [name, node] : table) {
    const std::string key = prefix + std::string(name.str());
    const bool is_table_name = prefix.empty() && std::find_if(std::begin(kTables), std::end(kTables), [&key](const char* t) {
                                                   return key == t;
                                                 }) != std::end(kTables);
    if (is_table_name) {
      if (!node.is_table()) throw Error(origin, "line " + std::to_string(LineOf(node)) + ": '" + key + "' must be a table ([" + key + "])");
      if (key == "trails") Trails(*job);
      if (key == "passpoints") Passpoints(*job);
      ReadTable(*node.as_table(), key + ".", origin, job);
      continue;
    }
    const KeySetter* setter = FindSetter(key);
    if (!setter) {
      throw Error(origin, "line " + std::to_string(LineOf(node)) + ": unknown key '" + key + "' (docs/job.md lists the keys)");
    }
    setter->set(*job, Value(node, origin, key));
  }
}

// What only the whole file can tell: exclusive keys, tables missing their required key.
void CheckWhole(const toml::table& root, const std::string& origin, const JobDefinition& job) {
  auto fail = [&origin](const toml::node* node, const std::string& problem) {
    throw Error(origin, "line " + std::to_string(node ? LineOf(*node) : 1) + ": " + problem);
  };
  const DetectRequest& d = job.measure.detect;
  if (!d.camera.empty() && !d.grid.empty()) fail(root.get("grid"), "give camera or grid, not both");
  if (d.trails && d.trails->start_utc.empty()) fail(root.get("trails"), "[trails] needs start_utc (the plate's first shutter opening, UTC)");
  if (d.passpoints) {
    if (d.passpoints->diameter_um <= 0.0) fail(root.get("passpoints"), "[passpoints] needs diameter_um (the mark's outer diameter, um)");
    if (d.passpoints->shape == "ring" && d.passpoints->line_width_um <= 0.0) {
      fail(root.get("passpoints"), "[passpoints] shape \"ring\" needs line_width_um");
    }
  }
}

}  // namespace

JobDefinition ParseJobFile(const std::string& text, const std::string& path) {
  toml::table root;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    const int line = static_cast<int>(e.source().begin.line);
    throw Error(path, (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) + OneLine(std::string(e.description())));
  }
  JobDefinition job;
  job.source = path;
  ReadTable(root, "", path, &job);
  CheckWhole(root, path, job);
  return job;
}

JobDefinition LoadJobFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(path, "no such job file");
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "is not a file (a job file is TOML, docs/job.md)");
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in || in.bad()) throw Error(path, "cannot read the job file");
  return ParseJobFile(text.str(), path);
}

void ApplyJobOverride(JobDefinition& job, const std::string& key, const std::string& value) {
  for (const KeySetter& s : Setters()) {
    if (OverrideName(s.key) == key) return s.set(job, Value(value, key));
  }
  std::string keys;
  for (const std::string& k : JobOverrideKeys()) keys += (keys.empty() ? "" : ", ") + k;
  throw Error("manifest", "unknown column '" + key + "' (job keys: " + keys + ")");
}

const std::vector<std::string>& JobOverrideKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> out;
    for (const KeySetter& s : Setters()) out.push_back(OverrideName(s.key));
    return out;
  }();
  return keys;
}

}  // namespace platemeter::pipeline
