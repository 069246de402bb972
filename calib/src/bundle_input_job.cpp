// ReadBundleJob (bundle_input_io.h): the bundle job file, TOML
// (docs/bundle-job.md). Every key is checked against its table's list, so a
// misspelt key is an error with its line, never a silent default.
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "toml_job_reader.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {

using job_toml::Join;
using job_toml::JobReader;
using job_toml::LineOf;


// Accepted ranges (docs/bundle-job.md, "Accepted ranges"): wide for any real
// block, narrow enough that squares and products stay finite.
constexpr double kMaxParameter = 1e12;    // camera parameters in their units (c_mm, k1_per_mm2, ...)
constexpr double kMaxFormatMm = 1000.0;   // mm
constexpr double kMaxObjectM = 1e30;      // m; as the ground points CSV
constexpr double kMaxSigmaM = 1e9;        // m
constexpr double kMaxAngleDeg = 360.0;    // deg
constexpr double kMaxSpeedMPerS = 1e8;    // m/s; below the speed of light (only its direction is used)

// ---------------------------------------------------------------------------
// [[camera]]

void ReadParameter(const JobReader& r, const toml::node& node, const std::string& key, double* value,
                   ParameterState* state) {
  if (node.is_number()) {
    *value = r.Number(node, key, -kMaxParameter, kMaxParameter);
    return;
  }
  if (node.is_string()) {
    const std::string s = node.as_string()->get();
    if (s == "free") {
      *state = ParameterState::Free();
    } else if (s == "fixed") {
      *state = ParameterState::Fixed();
    } else {
      r.FailKey(node, key, "= '" + s + "' must be \"free\" or \"fixed\" (or a number, or { value, state, sigma })");
    }
    return;
  }
  const toml::table* table = node.as_table();
  if (!table) r.FailKey(node, key, "must be a number, \"free\", \"fixed\" or { value = .., state = .., sigma = .. }");
  r.CheckKeys(*table, key + ".", {"value", "state", "sigma"});
  if (const toml::node* v = table->get("value")) *value = r.Number(*v, key + ".value", -kMaxParameter, kMaxParameter);
  const toml::node* sigma_node = table->get("sigma");
  const bool has_sigma = sigma_node != nullptr;
  const double sigma = has_sigma ? r.Number(*sigma_node, key + ".sigma", 0.0, kMaxParameter) : 0.0;
  if (const toml::node* s = table->get("state")) {
    const std::string name = r.String(*s, key + ".state");
    if (name == "free" || name == "fixed") {
      if (has_sigma) r.FailKey(*s, key + ".state", "= '" + name + "' takes no sigma (sigma goes with \"weighted\")");
      *state = name == "free" ? ParameterState::Free() : ParameterState::Fixed();
    } else if (name == "weighted") {
      if (!(sigma > 0.0)) r.FailKey(*s, key + ".state", "= 'weighted' needs a positive sigma");
      *state = ParameterState::Weighted(sigma);
    } else {
      r.FailKey(*s, key + ".state", "= '" + name + "' must be one of free, fixed, weighted");
    }
  } else if (has_sigma) {
    *state = sigma > 0.0 ? ParameterState::Weighted(sigma) : ParameterState::Fixed();
  }
}

CameraSetup ReadCamera(const JobReader& r, const toml::table& t, const DefinitionRegistry& registry,
                       std::vector<BundleWarning>* warnings) {
  std::vector<std::string> allowed = {"name", "from", "format_mm"};
  for (const char* p : kBundleCameraParamNames) allowed.push_back(p);
  r.CheckKeys(t, "camera.", allowed);
  const toml::node* name_node = t.get("name");
  if (!name_node) r.Fail(&t, "[[camera]] needs a name");
  const std::string name = r.String(*name_node, "camera.name");
  CameraSetup camera;
  camera.name = name;
  bool from_definition = false;
  if (const toml::node* from = t.get("from")) {
    const std::string definition = r.String(*from, "camera.from");
    if (definition != "none") {
      const CameraDefinition* found = registry.FindCamera(definition);
      if (!found) {
        r.FailKey(*from, "camera.from", "= '" + definition + "' is not a known camera (known: " +
                                            Join(registry.CameraNames()) + ", or \"none\")");
      }
      try {
        camera = CameraSetupFromDefinition(*found, name, warnings);
      } catch (const Error& e) {
        r.FailKey(*from, "camera.from", "= '" + definition + "': " + e.reason());
      }
      from_definition = true;
    }
  }
  if (const toml::node* format = t.get("format_mm")) {
    const std::vector<double> wh = r.Numbers(*format, "camera.format_mm", 2, -kMaxFormatMm, kMaxFormatMm);
    if (!(wh[0] > 0.0) || !(wh[1] > 0.0)) r.FailKey(*format, "camera.format_mm", "must be two positive numbers (mm)");
    camera.format_width_mm = wh[0];
    camera.format_height_mm = wh[1];
  }
  for (int i = 0; i < kBundleCameraParams; ++i) {
    const std::string key = std::string("camera.") + kBundleCameraParamNames[i];
    if (const toml::node* node = t.get(kBundleCameraParamNames[i])) {
      ReadParameter(r, *node, key, &camera.values[i], &camera.states[i]);
    }
  }
  const toml::node* c_node = t.get("c_mm");
  if (!from_definition && !c_node) {
    r.Fail(&t, "[[camera]] '" + name + "' needs c_mm (the initial principal distance) or from = a camera definition");
  }
  if (!(camera.values[0] > 0.0)) {
    r.Fail(c_node ? c_node : &t, "camera '" + name + "': c_mm must be positive");
  }
  return camera;
}

// ---------------------------------------------------------------------------
// [[frame]]

std::vector<PointKind> ReadKinds(const JobReader& r, const toml::node& node) {
  std::vector<PointKind> kinds;
  for (const auto& [name, item] : r.Strings(node, "frame.kinds")) {
    PointKind kind;
    if (!ParsePointKind(name, &kind)) {
      r.FailKey(*item, "frame.kinds", "= '" + name + "' is not a point kind (passpoint, star, trail_dot, trail_dash)");
    }
    if (kind == PointKind::kReseau || kind == PointKind::kFiducial) {
      r.FailKey(*item, "frame.kinds", "= '" + name +
                                           "': reseau crosses and fiducials are plate references (they define the "
                                           "plate frame), not object points");
    }
    kinds.push_back(kind);
  }
  return kinds;
}

struct FrameRead {
  FrameSetup frame;
  const toml::node* line = nullptr;  // for later errors
  const toml::node* camera_line = nullptr;
};

FrameRead ReadFrame(const JobReader& r, const toml::table& t, const std::vector<CameraSetup>& cameras,
                    std::vector<ImageObservation>* observations, std::vector<BundleWarning>* warnings) {
  r.CheckKeys(t, "frame.",
              {"id", "camera", "measurements", "kinds", "position_m", "angles_deg", "position_covariance_m2",
               "position_sigma_m", "in_track_sigma_m", "cross_track_sigma_m", "radial_sigma_m", "velocity_m_per_s",
               "angle_sigma_deg", "fixed"});
  FrameRead out;
  out.line = &t;
  FrameSetup& f = out.frame;
  if (const toml::node* id = t.get("id")) f.id = r.String(*id, "frame.id");
  if (const toml::node* camera = t.get("camera")) {
    f.camera = r.String(*camera, "frame.camera");
    out.camera_line = camera;
  } else if (cameras.size() == 1) {
    f.camera = cameras[0].name;
  } else {
    r.Fail(&t, "[[frame]] needs camera (there are " + std::to_string(cameras.size()) + " cameras)");
  }
  if (const toml::node* kinds = t.get("kinds"); kinds && !t.get("measurements")) {
    r.FailKey(*kinds, "frame.kinds", "goes with measurements (a measurement file)");
  }
  if (const toml::node* m = t.get("measurements")) {
    MeasurementObservationOptions options;
    options.frame_id = f.id;
    if (const toml::node* kinds = t.get("kinds")) options.kinds = ReadKinds(r, *kinds);
    const std::string path = r.Path(r.String(*m, "frame.measurements"));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path, "cannot open the measurement file (named on line " + std::to_string(LineOf(*m)) + " of " + r.path() + ")");
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();
    const MeasurementFile file = ParseMeasurementFile(text, path);
    const std::vector<ImageObservation> read = ObservationsFromMeasurementFile(file, path, options, warnings, &text);
    if (f.id.empty()) f.id = file.header.plate_id;  // checked non-empty by ObservationsFromMeasurementFile
    if (read.empty()) {
      warnings->push_back({"frame " + f.id, path + " has no measured point of the selected kinds"});
    }
    observations->insert(observations->end(), read.begin(), read.end());
  }
  if (f.id.empty()) r.Fail(&t, "[[frame]] needs an id (or measurements, whose plate_id is the id)");

  if (const toml::node* p = t.get("position_m")) f.position_m = r.Vector3(*p, "frame.position_m", -kMaxObjectM, kMaxObjectM);
  if (const toml::node* a = t.get("angles_deg")) {
    const Eigen::Vector3d deg = r.Vector3(*a, "frame.angles_deg", -kMaxAngleDeg, kMaxAngleDeg);
    f.angles = PhiOmegaKappaT{deg[0] * kRadPerDeg, deg[1] * kRadPerDeg, deg[2] * kRadPerDeg};
  }
  const toml::node* covariance = t.get("position_covariance_m2");
  const toml::node* axis_sigmas = t.get("position_sigma_m");
  const toml::node* track[3] = {t.get("in_track_sigma_m"), t.get("cross_track_sigma_m"), t.get("radial_sigma_m")};
  const toml::node* velocity = t.get("velocity_m_per_s");
  const bool any_track = track[0] || track[1] || track[2] || velocity;
  const int forms = (covariance ? 1 : 0) + (axis_sigmas ? 1 : 0) + (any_track ? 1 : 0);
  const toml::node* first_form = covariance ? covariance : axis_sigmas ? axis_sigmas : velocity;
  for (const toml::node* n : track) first_form = first_form ? first_form : n;
  if (forms > 1) {
    r.Fail(first_form, "frame '" + f.id +
                           "': give the position's sigmas one way: position_covariance_m2, position_sigma_m, or "
                           "in_track_sigma_m + cross_track_sigma_m + radial_sigma_m + velocity_m_per_s");
  }
  if (forms == 1 && !f.position_m) {
    r.Fail(first_form, "frame '" + f.id + "': position sigmas need the a-priori position (position_m)");
  }
  if (covariance) f.position_covariance_m2 = r.Matrix3(*covariance, "frame.position_covariance_m2", -kMaxSigmaM * kMaxSigmaM,
                                                          kMaxSigmaM * kMaxSigmaM);
  if (axis_sigmas) {
    const Eigen::Vector3d s = r.Vector3(*axis_sigmas, "frame.position_sigma_m", -kMaxSigmaM, kMaxSigmaM);
    if (!(s.minCoeff() > 0.0)) r.FailKey(*axis_sigmas, "frame.position_sigma_m", "must be three positive numbers (m)");
    f.position_covariance_m2 = s.cwiseProduct(s).asDiagonal();
  }
  if (any_track) {
    if (!track[0] || !track[1] || !track[2] || !velocity) {
      r.Fail(first_form, "frame '" + f.id +
                             "': the track form needs in_track_sigma_m, cross_track_sigma_m, radial_sigma_m and "
                             "velocity_m_per_s");
    }
    const double s_in = r.Number(*track[0], "frame.in_track_sigma_m", 0.0, kMaxSigmaM, false);
    const double s_cross = r.Number(*track[1], "frame.cross_track_sigma_m", 0.0, kMaxSigmaM, false);
    const double s_radial = r.Number(*track[2], "frame.radial_sigma_m", 0.0, kMaxSigmaM, false);
    const Eigen::Vector3d v = r.Vector3(*velocity, "frame.velocity_m_per_s", -kMaxSpeedMPerS, kMaxSpeedMPerS);
    try {
      f.position_covariance_m2 = StationCovarianceFromTrack(*f.position_m, v, s_in, s_cross, s_radial);
    } catch (const Error& e) {
      r.FailKey(*velocity, "frame.velocity_m_per_s", "(frame '" + f.id + "'): " + e.reason());
    }
  }
  if (const toml::node* a = t.get("angle_sigma_deg")) {
    if (!f.angles) r.FailKey(*a, "frame.angle_sigma_deg", "needs the a-priori angles (angles_deg)");
    const Eigen::Vector3d deg = r.Vector3(*a, "frame.angle_sigma_deg", -kMaxAngleDeg, kMaxAngleDeg);
    if (!(deg.minCoeff() > 0.0)) r.FailKey(*a, "frame.angle_sigma_deg", "must be three positive numbers (degrees)");
    f.angle_sigma_rad = deg * kRadPerDeg;
  }
  if (const toml::node* fixed = t.get("fixed")) {
    f.fixed = r.Bool(*fixed, "frame.fixed");
    if (f.fixed && (!f.position_m || !f.angles)) {
      r.FailKey(*fixed, "frame.fixed", "needs position_m and angles_deg (the values it is held at)");
    }
    if (f.fixed && (f.position_covariance_m2 || f.angle_sigma_rad)) {
      r.FailKey(*fixed, "frame.fixed", "= true takes no position or angle sigmas");
    }
  }
  return out;
}

// ---------------------------------------------------------------------------
// [[distance]], [adjustment], [checks], [output]

DistanceObservation ReadDistance(const JobReader& r, const toml::table& t) {
  r.CheckKeys(t, "distance.", {"from", "to", "distance_m", "sigma_m"});
  DistanceObservation d;
  for (const char* key : {"from", "to", "distance_m", "sigma_m"}) {
    if (!t.get(key)) r.Fail(&t, std::string("[[distance]] needs ") + key);
  }
  d.from = r.String(*t.get("from"), "distance.from");
  d.to = r.String(*t.get("to"), "distance.to");
  if (d.from == d.to) r.Fail(t.get("to"), "[[distance]] from and to are both '" + d.from + "'");
  d.distance_m = r.Number(*t.get("distance_m"), "distance.distance_m", 0.0, kMaxObjectM, false);
  d.sigma_m = r.Number(*t.get("sigma_m"), "distance.sigma_m", 0.0, kMaxSigmaM);
  return d;
}

void ReadAdjustment(const JobReader& r, const toml::table& t, BundleOptions* o) {
  r.CheckKeys(t, "adjustment.",
              {"datum", "robust_loss_scale", "rejection_threshold", "false_rejection_rate", "max_iterations", "function_tolerance",
               "correlation_threshold", "significance_level", "rank_tolerance", "num_threads"});
  if (const toml::node* n = t.get("datum")) {
    const std::string name = r.String(*n, "adjustment.datum");
    if (!ParseDatumKind(name, &o->datum)) {
      r.FailKey(*n, "adjustment.datum", "= '" + name + "' must be one of auto, control, fixed-frames, inner-constraints");
    }
  }
  if (const toml::node* n = t.get("robust_loss_scale")) o->adjustment.robust_loss_scale = r.Number(*n, "adjustment.robust_loss_scale", 0.0, 1e6);
  if (const toml::node* n = t.get("rejection_threshold")) o->adjustment.rejection_threshold = r.Number(*n, "adjustment.rejection_threshold", 0.0, 1e6);
  if (const toml::node* n = t.get("false_rejection_rate")) {
    o->adjustment.false_rejection_rate = r.Number(*n, "adjustment.false_rejection_rate", 0.0, 0.5, false);
  }
  if (const toml::node* n = t.get("max_iterations")) o->adjustment.max_iterations = static_cast<int>(r.Integer(*n, "adjustment.max_iterations", 1, 1000000));
  if (const toml::node* n = t.get("function_tolerance")) o->adjustment.function_tolerance = r.Number(*n, "adjustment.function_tolerance", 0.0, 0.1, false);
  if (const toml::node* n = t.get("correlation_threshold")) o->adjustment.correlation_threshold = r.Number(*n, "adjustment.correlation_threshold", 0.0, 1.0, false);
  if (const toml::node* n = t.get("significance_level")) {
    o->adjustment.significance_level = r.Number(*n, "adjustment.significance_level", 0.0, 0.5, false);
  }
  if (const toml::node* n = t.get("rank_tolerance")) o->adjustment.rank_tolerance = r.Number(*n, "adjustment.rank_tolerance", 0.0, 0.1, false);
  if (const toml::node* n = t.get("num_threads")) o->adjustment.num_threads = static_cast<int>(r.Integer(*n, "adjustment.num_threads", 0, 4096));
  std::string why;
  if (!o->Check(&why)) r.Fail(&t, "[adjustment]: " + why);
}

void ReadOutput(const JobReader& r, const toml::table& t, BundleOutputSettings* o) {
  r.CheckKeys(t, "output.", {"title", "balance_radius_mm", "export_pixel_size_um", "export_image_size_px"});
  if (const toml::node* n = t.get("title")) o->title = r.String(*n, "output.title");
  if (const toml::node* n = t.get("balance_radius_mm")) {
    o->balance_radius_mm = r.Number(*n, "output.balance_radius_mm", 0.0, 1e4, false);
  }
  const toml::node* pixel = t.get("export_pixel_size_um");
  const toml::node* size = t.get("export_image_size_px");
  if (pixel) o->export_pixel_size_um = r.Number(*pixel, "output.export_pixel_size_um", 0.0, 1e5, false);
  if (size) {
    const toml::array* array = size->as_array();
    if (!array || array->size() != 2 || !(*array)[0].is_integer() || !(*array)[1].is_integer()) {
      r.FailKey(*size, "output.export_image_size_px", "must be [width, height], two integers (px)");
    }
    o->export_image_size_px = std::array<int, 2>{
        static_cast<int>(r.Integer((*array)[0], "output.export_image_size_px", 1, 10000000)),
        static_cast<int>(r.Integer((*array)[1], "output.export_image_size_px", 1, 10000000))};
  }
  if ((pixel != nullptr) != (size != nullptr)) {
    r.Fail(pixel ? pixel : size, "the pixel camera export needs both export_pixel_size_um and export_image_size_px");
  }
}

}  // namespace

BundleJob ReadBundleJob(const std::string& path) { return ReadBundleJob(path, DefinitionRegistry()); }

BundleJob ReadBundleJob(const std::string& path, const DefinitionRegistry& registry) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(path, "no such bundle job file");
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "is not a file (a bundle job is TOML, docs/bundle-job.md)");
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    const int line = static_cast<int>(e.source().begin.line);
    throw Error(path, (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) +
                          OneLine(std::string(e.description())));
  }
  const JobReader r(path, "docs/bundle-job.md");
  r.CheckKeys(root, "", {"observations", "ground_points", "camera", "frame", "distance", "adjustment", "checks", "output"});

  BundleJob job;
  job.source = path;
  BundleInput& input = job.input;

  // Cameras.
  std::map<std::string, const toml::node*> camera_lines;
  if (const toml::array* cameras = r.Tables(root, "camera")) {
    for (const toml::node& node : *cameras) {
      CameraSetup camera = ReadCamera(r, *node.as_table(), registry, &job.warnings);
      if (!camera_lines.emplace(camera.name, &node).second) {
        r.Fail(node.as_table()->get("name"), "camera '" + camera.name + "' is defined twice (first on line " +
                                                 std::to_string(LineOf(*camera_lines[camera.name])) + ")");
      }
      input.cameras.push_back(std::move(camera));
    }
  }
  if (input.cameras.empty()) r.Fail(nullptr, "no [[camera]]: the bundle needs at least one camera");

  // Observation files first, then the frames (which may add measurement files).
  if (const toml::node* node = root.get("observations")) {
    for (const auto& [file, item] : r.Strings(*node, "observations")) {
      std::vector<ImageObservation> read = ReadObservationsCsv(r.Path(file));
      input.observations.insert(input.observations.end(), read.begin(), read.end());
    }
  }
  if (const toml::node* node = root.get("ground_points")) {
    input.ground_points = ReadGroundPointsCsv(r.Path(r.String(*node, "ground_points")));
  }
  std::map<std::string, const toml::node*> frame_lines;
  if (const toml::array* frames = r.Tables(root, "frame")) {
    for (const toml::node& node : *frames) {
      FrameRead read = ReadFrame(r, *node.as_table(), input.cameras, &input.observations, &job.warnings);
      if (!camera_lines.count(read.frame.camera)) {
        std::vector<std::string> names;
        for (const CameraSetup& c : input.cameras) names.push_back(c.name);
        r.Fail(read.camera_line ? read.camera_line : read.line,
               "frame '" + read.frame.id + "' names camera '" + read.frame.camera + "', which no [[camera]] defines (" +
                   Join(names) + ")");
      }
      if (!frame_lines.emplace(read.frame.id, read.line).second) {
        r.Fail(read.line, "frame '" + read.frame.id + "' is listed twice (first on line " +
                              std::to_string(LineOf(*frame_lines[read.frame.id])) + ")");
      }
      input.frames.push_back(std::move(read.frame));
    }
  }
  if (input.observations.empty()) {
    r.Fail(nullptr, "no observations: give observations = \"file.csv\" or measurements in [[frame]] tables");
  }
  if (const toml::array* distances = r.Tables(root, "distance")) {
    for (const toml::node& node : *distances) input.distances.push_back(ReadDistance(r, *node.as_table()));
  }
  if (const toml::table* t = r.Table(root, "adjustment")) ReadAdjustment(r, *t, &job.options);
  if (const toml::table* t = r.Table(root, "checks")) {
    r.CheckKeys(*t, "checks.", {"min_points_per_frame"});
    if (const toml::node* n = t->get("min_points_per_frame")) {
      job.check_options.min_points_per_frame = static_cast<int>(r.Integer(*n, "checks.min_points_per_frame", 1, 1000));
    }
  }
  if (const toml::table* t = r.Table(root, "output")) ReadOutput(r, *t, &job.output);
  if (job.output.title.empty()) job.output.title = std::filesystem::path(path).stem().string();
  return job;
}

}  // namespace platemeter
