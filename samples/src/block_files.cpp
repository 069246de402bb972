// The rendered block's own files: the batch manifest, the bundle job and the
// block truth (docs/block-simulator.md).
#include <charconv>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "platemeter/core/version.h"
#include "platemeter/samples/block_render.h"
#include "platemeter/core/angles.h"

namespace platemeter::sim {
namespace {

// Shortest exact decimal, always a TOML float (a '.' or an exponent).
std::string TomlNumber(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  std::string text(buffer, result.ptr);
  if (text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}

std::string TomlString(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// RFC 4180: quoted when it holds a comma, a quote or a line break.
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string Triple(const double* v) {
  return "[" + TomlNumber(v[0]) + ", " + TomlNumber(v[1]) + ", " + TomlNumber(v[2]) + "]";
}


}  // namespace

std::string BlockManifestCsv(const BlockSpec& spec, const BlockLayout& layout, const std::vector<std::string>& scans,
                             const std::vector<std::string>& list_paths) {
  const SimulationSpec& f = spec.frame_spec;
  const SpecPasspoints& p = f.passpoints;
  std::ostringstream out;
  out << "# platemeter batch manifest of the rendered block '" << spec.name << "' (docs/batch.md):\n"
      << "#   platemeter batch " << spec.name << ".manifest.csv -o " << spec.bundle.measured_dir << "\n"
      << "# what the operator knows of each frame: camera, scan orientation, emulsion, the passpoint marks and\n"
      << "# the approximate list (by absolute path: a manifest's passpoints.list_file is taken as given)\n"
      << "scan,camera,orientation,temperature_degC,emulsion_depth_um,refractive_index,passpoints.shape,"
         "passpoints.diameter_um,passpoints.line_width_um,passpoints.polarity,passpoints.list_file\n";
  const std::string orientation = std::to_string(f.scanner.orientation_deg) + (f.scanner.mirrored ? "m" : "");
  const std::string temperature = f.thermal.temperature_degC ? TomlNumber(*f.thermal.temperature_degC) : "";
  const std::string depth = f.emulsion.depth_um > 0 ? TomlNumber(f.emulsion.depth_um) : "";
  const std::string index = f.emulsion.depth_um > 0 ? TomlNumber(f.emulsion.refractive_index) : "";
  const std::string line_width = p.shape == "ring" ? TomlNumber(p.line_width_um) : "";
  for (std::size_t i = 0; i < layout.frames.size(); ++i) {
    out << CsvField(scans.at(i)) << ',' << CsvField(layout.camera_definition) << ',' << orientation << ','
        << temperature << ',' << depth << ',' << index << ',' << p.shape << ',' << TomlNumber(p.diameter_um) << ','
        << line_width << ',' << (p.dark ? "dark" : "bright") << ',' << CsvField(list_paths.at(i)) << '\n';
  }
  return out.str();
}

std::string BlockBundleJobToml(const BlockSpec& spec, const BlockLayout& layout, const std::string& ground_points_file) {
  std::ostringstream out;
  out << "# Self-calibrating bundle adjustment of the rendered block '" << spec.name << "' (docs/bundle-job.md),\n"
      << "# written by platemeter simulate " << spec.origin << ".\n"
      << "# Frames: the measurement files of `platemeter batch " << spec.name << ".manifest.csv -o "
      << spec.bundle.measured_dir << "`\n"
      << "# (paths relative to this file); stations and angles are approximations (no sigmas).\n"
      << "ground_points = " << TomlString(ground_points_file) << "\n\n";
  const std::string title = spec.bundle.title.empty()
                                ? "Rendered block " + spec.name + ": self-calibration of " + layout.camera_definition
                                : spec.bundle.title;
  out << "[output]\ntitle = " << TomlString(title) << "\n\n";
  out << "[adjustment]\ndatum = " << TomlString(spec.bundle.datum) << "\n\n";
  out << "[[camera]]\nname = " << TomlString(layout.camera_definition) << "\nfrom = "
      << TomlString(layout.camera_definition) << "\n";
  for (int i = 0; i < kBundleCameraParams; ++i) {
    bool free = false;
    for (const std::string& name : spec.bundle.free) free = free || BundleParameterName(name) == kBundleCameraParamNames[i];
    out << kBundleCameraParamNames[i] << " = " << (free ? "\"free\"" : "\"fixed\"") << "\n";
  }
  for (std::size_t f = 0; f < layout.frames.size(); ++f) {
    const std::string& id = layout.frames[f].station.id;
    const FrameSetup& a = layout.approximations.at(f);
    out << "\n[[frame]]\nid = " << TomlString(id) << "\nmeasurements = "
        << TomlString(spec.bundle.measured_dir + "/" + id + "/" + id + ".measurements.csv") << "\n";
    if (a.position_m) out << "position_m = " << Triple(a.position_m->data()) << "\n";
    if (a.angles) {
      const double angles[3] = {a.angles->phi_rad * kDegPerRad, a.angles->omega_rad * kDegPerRad, a.angles->kappa_rad * kDegPerRad};
      out << "angles_deg = " << Triple(angles) << "\n";
    }
  }
  return out.str();
}

namespace {

nlohmann::ordered_json Vector3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::ordered_json FrameJson(const BlockLayout& layout, std::size_t f, const BlockOutputs& outputs) {
  namespace fs = std::filesystem;
  const BlockFrame& frame = layout.frames[f];
  const StationTruth& s = frame.station;
  nlohmann::ordered_json j;
  j["id"] = s.id;
  j["orbit"] = s.group + 1;
  j["exposure"] = s.index_in_group + 1;
  j["position_m"] = Vector3(s.position_m);
  j["angles_deg"] = {{"phi", s.angles.phi_rad * kDegPerRad}, {"omega", s.angles.omega_rad * kDegPerRad}, {"kappa", s.angles.kappa_rad * kDegPerRad}};
  nlohmann::ordered_json t = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) t.push_back({s.image_from_object(r, 0), s.image_from_object(r, 1), s.image_from_object(r, 2)});
  j["image_from_object"] = t;
  j["roll_deg"] = s.roll_deg;
  j["scanner_rotation_deg"] = frame.scanner_rotation_deg;
  j["film_affine_ppm"] = {frame.film_affine_ppm[0], frame.film_affine_ppm[1], frame.film_affine_ppm[2], frame.film_affine_ppm[3]};
  j["seed"] = frame.seed;
  if (f < outputs.frames.size()) {
    j["scan"] = fs::path(outputs.frames[f].image_path).filename().string();
    j["truth"] = fs::path(outputs.frames[f].truth_path).filename().string();
    j["chain"] = fs::path(outputs.frames[f].chain_path).filename().string();
    j["passpoint_list"] = fs::path(outputs.passpoint_lists[f]).filename().string();
  }
  nlohmann::ordered_json points = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    points.push_back({{"id", layout.points[frame.points[i]].id}, {"x_mm", frame.plate_mm[i].x()}, {"y_mm", frame.plate_mm[i].y()}});
  }
  j["image_points"] = points;
  return j;
}

}  // namespace

std::string BlockTruthJson(const BlockSpec& spec, const BlockLayout& layout, const BlockOutputs& outputs,
                           const BlockRenderOptions& options) {
  namespace fs = std::filesystem;
  const BundleCameraTruth& c = layout.camera;
  const LunarBlockOptions& g = spec.geometry;
  nlohmann::ordered_json j;
  j["format"] = "platemeter-block-truth";
  j["format_version"] = 1;
  j["software_version"] = std::string("platemeter ") + kVersion;
  j["name"] = spec.name;
  j["description"] = spec.description;
  j["spec"] = spec.origin;
  j["frame_spec"] = spec.frame_spec_path;
  j["seed"] = spec.seed;
  j["full_size"] = options.full_size;
  j["summary"] = layout.summary;
  j["camera"] = {{"definition", layout.camera_definition}, {"c_mm", c.c_mm}, {"xp_mm", c.xp_mm}, {"yp_mm", c.yp_mm},
                 {"k1_per_mm2", c.k1_per_mm2}, {"k2_per_mm4", c.k2_per_mm4}, {"k3_per_mm6", c.k3_per_mm6},
                 {"p1_per_mm", c.p1_per_mm}, {"p2_per_mm", c.p2_per_mm}, {"b1", c.b1}, {"b2", c.b2},
                 {"format_width_mm", c.format_width_mm}, {"format_height_mm", c.format_height_mm},
                 {"model", "seed 000 eq. 1 (BrownAffine, correction form): the projected positions carry its distortion once"}};
  j["geometry"] = {{"kind", "lunar orbits (seed 000 section 4)"}, {"body_radius_m", g.moon_radius_m},
                   {"altitude_m", g.altitude_m}, {"revolutions", g.revolutions}, {"track_spacing_m", g.track_spacing_m},
                   {"exposures_per_orbit", g.exposures_per_orbit}, {"convergence_deg", g.convergence_deg},
                   {"kappa_start_deg", g.kappa_start_deg}, {"kappa_increment_deg", g.kappa_increment_deg},
                   {"kappa_sequence", g.rolls_continue_across_orbits ? "continuous" : "per-orbit"},
                   {"relief_m", g.relief_m}, {"format_margin_mm", g.format_margin_mm},
                   {"min_separation_mm", spec.min_separation_mm}};
  j["control"] = {{"count", spec.control.count}, {"sigma_m", spec.control.sigma_m}};
  j["transfer"] = {{"sigma_px", spec.transfer.sigma_px}};
  j["approximations"] = {{"station_sigma_m", g.approximations.station_sigma_m},
                         {"angle_sigma_deg", g.approximations.angle_sigma_deg},
                         {"point_sigma_m", g.approximations.point_sigma_m}};
  j["files"] = {{"manifest", fs::path(outputs.manifest_path).filename().string()},
                {"ground_points", fs::path(outputs.ground_points_path).filename().string()},
                {"job", fs::path(outputs.job_path).filename().string()},
                {"measured_dir", spec.bundle.measured_dir}};
  nlohmann::ordered_json frames = nlohmann::ordered_json::array();
  for (std::size_t f = 0; f < layout.frames.size(); ++f) frames.push_back(FrameJson(layout, f, outputs));
  j["frames"] = frames;
  std::vector<int> seen_by(layout.points.size(), 0);
  for (const BlockFrame& frame : layout.frames) {
    for (int p : frame.points) ++seen_by[p];
  }
  nlohmann::ordered_json points = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < layout.points.size(); ++i) {
    points.push_back({{"id", layout.points[i].id}, {"position_m", Vector3(layout.points[i].position_m)},
                      {"control", static_cast<bool>(layout.control[i])}, {"frames", seen_by[i]}});
  }
  j["points"] = points;
  j["dropped_points"] = layout.dropped;
  return j.dump(2) + "\n";
}

}  // namespace platemeter::sim
