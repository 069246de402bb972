// CheckBundleInput (bundle_input_io.h, docs/bundle-job.md "Checks"): errors
// for input that cannot be adjusted, then the cleaning of what cannot be
// determined (points seen once, thin frames), repeated until stable.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include <Eigen/Cholesky>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

constexpr const char* kBundleInputSubject = "bundle input";

// Error at a record: "file:line" origins become Error(file, "line N: reason").
[[noreturn]] void FailAt(const std::string& origin, const std::string& reason) {
  const size_t colon = origin.rfind(':');
  if (colon != std::string::npos && colon + 1 < origin.size() &&
      origin.find_first_not_of("0123456789", colon + 1) == std::string::npos) {
    throw Error(origin.substr(0, colon), "line " + origin.substr(colon + 1) + ": " + reason);
  }
  throw Error(origin.empty() ? kBundleInputSubject : origin, reason);
}
[[noreturn]] void Fail(const std::string& reason) { throw Error(kBundleInputSubject, reason); }

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

std::string List(const std::vector<std::string>& items, size_t max_items = 8) {
  std::string out;
  for (size_t i = 0; i < items.size() && i < max_items; ++i) out += (i ? ", " : "") + items[i];
  if (items.size() > max_items) out += ", ... (" + std::to_string(items.size()) + " in all)";
  return out;
}

bool Finite(double value) { return std::isfinite(value); }

void CheckCameras(const std::vector<CameraSetup>& cameras) {
  std::set<std::string> names;
  for (const CameraSetup& camera : cameras) {
    if (camera.name.empty()) Fail("a camera has an empty name");
    if (!names.insert(camera.name).second) Fail("camera " + Quoted(camera.name) + " is listed twice");
    const std::string what = "camera " + Quoted(camera.name) + ": ";
    for (int i = 0; i < kBundleCameraParams; ++i) {
      if (!Finite(camera.values[i])) Fail(what + kBundleCameraParamNames[i] + " is not finite");
      const ParameterState& state = camera.states[i];
      if (state.kind == ParameterState::Kind::kWeighted && (!(state.sigma > 0.0) || !Finite(state.sigma))) {
        Fail(what + kBundleCameraParamNames[i] + " is weighted with sigma " + Number(state.sigma) +
             " (a weight needs a positive sigma; sigma 0 is fixed)");
      }
    }
    if (!(camera.values[0] > 0.0)) Fail(what + "c_mm must be positive (is " + Number(camera.values[0]) + ")");
    if (!(camera.format_width_mm >= 0.0) || !(camera.format_height_mm >= 0.0) || !Finite(camera.format_width_mm) ||
        !Finite(camera.format_height_mm)) {
      Fail(what + "the format must be finite and not negative (0 = unknown)");
    }
  }
}

void CheckFrame(const FrameSetup& frame, const std::set<std::string>& cameras,
                const std::vector<std::string>& camera_names) {
  const std::string what = "frame " + Quoted(frame.id) + ": ";
  if (!cameras.count(frame.camera)) {
    Fail(what + "camera " + Quoted(frame.camera) + " is not listed (cameras: " +
         (camera_names.empty() ? std::string("none") : List(camera_names)) + ")");
  }
  if (frame.position_m && !frame.position_m->allFinite()) Fail(what + "the position is not finite");
  if (frame.angles && (!Finite(frame.angles->phi_rad) || !Finite(frame.angles->omega_rad) ||
                       !Finite(frame.angles->kappa_rad))) {
    Fail(what + "the angles are not finite");
  }
  if (frame.position_covariance_m2) {
    const Eigen::Matrix3d& c = *frame.position_covariance_m2;
    if (!frame.position_m) Fail(what + "a position covariance needs the a-priori position");
    if (!c.allFinite()) Fail(what + "the position covariance is not finite");
    const double scale = c.cwiseAbs().maxCoeff();
    if (!((c - c.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) {
      Fail(what + "the position covariance is not symmetric");
    }
    const Eigen::LLT<Eigen::Matrix3d> llt(c);
    if (!(scale > 0.0) || llt.info() != Eigen::Success) {
      Fail(what + "the position covariance is not positive definite (every direction needs a positive variance; "
                  "hold the frame fixed instead)");
    }
  }
  if (frame.angle_sigma_rad) {
    if (!frame.angles) Fail(what + "angle sigmas need the a-priori angles");
    for (int i = 0; i < 3; ++i) {
      const double sigma = (*frame.angle_sigma_rad)[i];
      if (!(sigma > 0.0) || !Finite(sigma)) {
        Fail(what + "the angle sigmas must be positive (a fixed attitude: fixed = true)");
      }
    }
  }
  if (frame.fixed && (!frame.position_m || !frame.angles)) {
    Fail(what + "a fixed frame needs its position and angles");
  }
}

void CheckObservation(const ImageObservation& o) {
  if (o.frame.empty()) FailAt(o.origin, "an observation has an empty frame id");
  if (o.point_id.empty()) FailAt(o.origin, "an observation in frame " + Quoted(o.frame) + " has an empty point id");
  const std::string what = "observation of point " + Quoted(o.point_id) + " in frame " + Quoted(o.frame) + ": ";
  if (!Finite(o.x_mm) || !Finite(o.y_mm)) FailAt(o.origin, what + "the coordinates are not finite");
  if (!(o.sigma_x_mm > 0.0) || !(o.sigma_y_mm > 0.0) || !Finite(o.sigma_x_mm) || !Finite(o.sigma_y_mm)) {
    FailAt(o.origin, what + "the standard deviations must be positive and finite");
  }
}

void CheckGroundPoint(const GroundPoint& p) {
  if (p.id.empty()) FailAt(p.origin, "a ground point has an empty id");
  const std::string what = "ground point " + Quoted(p.id) + ": ";
  if (!p.position_m.allFinite()) FailAt(p.origin, what + "the coordinates are not finite");
  for (const auto& sigma : p.sigma_m) {
    if (sigma && (!(*sigma >= 0.0) || !Finite(*sigma))) {
      FailAt(p.origin, what + "a standard deviation must be finite and not negative (0 = fixed, none = free)");
    }
  }
}

bool IsControl(const GroundPoint* p) {
  if (p == nullptr) return false;
  return std::any_of(p->sigma_m.begin(), p->sigma_m.end(), [](const auto& s) { return s.has_value(); });
}

std::string DistanceName(const DistanceObservation& d) { return "distance " + d.from + "-" + d.to; }

}  // namespace

bool BundleInputCheckOptions::Check(std::string* why) const {
  if (min_points_per_frame < 1) {
    if (why != nullptr) *why = "min_points_per_frame must be at least 1";
    return false;
  }
  return true;
}

namespace {

// What the checks work on: the frames (listed or made), indexes, and which
// observations and frames are still in.
struct CheckContext {
  explicit CheckContext(const BundleInput& in) : input(in) {}
  const BundleInput& input;
  std::vector<FrameSetup> frames;
  std::map<std::string, size_t> frame_index;
  std::map<std::string, const GroundPoint*> ground;
  std::set<std::string> observed_ids, distance_named;
  std::vector<bool> active, frame_kept;
};

// Every error of the input (throws), and the frames made when none are listed.
void CheckErrors(CheckContext* c) {
  const BundleInput& input = c->input;
  // --- Errors --------------------------------------------------------------
  CheckCameras(input.cameras);
  std::set<std::string> camera_set;
  std::vector<std::string> camera_names;
  for (const CameraSetup& c : input.cameras) {
    camera_set.insert(c.name);
    camera_names.push_back(c.name);
  }
  if (input.observations.empty()) Fail("no image observations");
  for (const ImageObservation& o : input.observations) CheckObservation(o);

  std::vector<FrameSetup>& frames = c->frames;
  frames = input.frames;
  if (frames.empty()) {
    // Frames not listed: one per observed frame id, when the camera is unambiguous.
    if (input.cameras.size() != 1) {
      Fail("no frames are listed and there " +
           (input.cameras.empty() ? std::string("is no camera")
                                  : "are " + std::to_string(input.cameras.size()) + " cameras") +
           ": list the frames with their camera");
    }
    std::set<std::string> seen;
    for (const ImageObservation& o : input.observations) {
      if (seen.insert(o.frame).second) {
        FrameSetup frame;
        frame.id = o.frame;
        frame.camera = input.cameras[0].name;
        frames.push_back(std::move(frame));
      }
    }
  }
  std::map<std::string, size_t>& frame_index = c->frame_index;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].id.empty()) Fail("a frame has an empty id");
    if (!frame_index.emplace(frames[i].id, i).second) Fail("frame " + Quoted(frames[i].id) + " is listed twice");
    CheckFrame(frames[i], camera_set, camera_names);
  }
  {
    std::map<std::pair<std::string, std::string>, const ImageObservation*> seen;
    for (const ImageObservation& o : input.observations) {
      if (!frame_index.count(o.frame)) {
        FailAt(o.origin, "observation of point " + Quoted(o.point_id) + " names frame " + Quoted(o.frame) +
                             ", which no frame lists");
      }
      const auto [it, inserted] = seen.emplace(std::make_pair(o.frame, o.point_id), &o);
      if (!inserted) {
        FailAt(o.origin, "point " + Quoted(o.point_id) + " is observed twice in frame " + Quoted(o.frame) +
                             (it->second->origin.empty() ? std::string() : " (also at " + it->second->origin + ")"));
      }
    }
  }
  std::map<std::string, const GroundPoint*>& ground = c->ground;
  for (const GroundPoint& p : input.ground_points) {
    CheckGroundPoint(p);
    if (!ground.emplace(p.id, &p).second) {
      FailAt(p.origin, "ground point " + Quoted(p.id) + " is listed twice" +
                           (ground[p.id]->origin.empty() ? std::string() : " (also at " + ground[p.id]->origin + ")"));
    }
  }
  std::set<std::string>& observed_ids = c->observed_ids;
  for (const ImageObservation& o : input.observations) observed_ids.insert(o.point_id);
  std::set<std::string>& distance_named = c->distance_named;
  for (const DistanceObservation& d : input.distances) {
    const std::string what = DistanceName(d) + ": ";
    if (d.from.empty() || d.to.empty()) Fail(what + "an end has an empty id");
    if (d.from == d.to) Fail(what + "both ends are " + Quoted(d.from));
    if (!(d.distance_m > 0.0) || !Finite(d.distance_m)) Fail(what + "distance_m must be positive");
    if (!(d.sigma_m >= 0.0) || !Finite(d.sigma_m)) Fail(what + "sigma_m must not be negative (0 = exact)");
    for (const std::string& end : {d.from, d.to}) {
      const bool is_frame = frame_index.count(end) > 0;
      const bool is_point = observed_ids.count(end) > 0 || ground.count(end) > 0;
      if (is_frame && is_point) Fail(what + Quoted(end) + " is both a frame and a point: rename one");
      if (!is_frame && !is_point) Fail(what + Quoted(end) + " is neither a frame nor a point");
      distance_named.insert(end);
    }
  }

}

// Leaves out points seen once and thin frames, repeated until nothing changes.
void LeaveOutUntilStable(CheckContext* c, const BundleInputCheckOptions& options, std::vector<BundleWarning>* out_warnings) {
  const BundleInput& input = c->input;
  std::vector<BundleWarning>& warnings = *out_warnings;
  const std::vector<FrameSetup>& frames = c->frames;
  std::map<std::string, size_t>& frame_index = c->frame_index;
  const std::map<std::string, const GroundPoint*>& ground = c->ground;
  const std::set<std::string>& distance_named = c->distance_named;
  // --- Cleaning, until stable ---------------------------------------------
  // Leaving things out only lowers the counts, so the result does not depend
  // on the order of the steps.
  const size_t n_obs = input.observations.size();
  std::vector<bool>& active = c->active;
  std::vector<bool>& frame_kept = c->frame_kept;
  active.assign(n_obs, true);
  frame_kept.assign(frames.size(), true);
  std::map<std::string, int> initial_frames_of_point, initial_points_of_frame;
  for (const ImageObservation& o : input.observations) {
    ++initial_frames_of_point[o.point_id];
    ++initial_points_of_frame[o.frame];
  }
  bool changed = true;
  while (changed) {
    changed = false;
    // Points seen in one frame only.
    std::map<std::string, std::vector<size_t>> obs_of_point;
    std::vector<std::string> point_order;
    for (size_t i = 0; i < n_obs; ++i) {
      if (!active[i]) continue;
      auto& list = obs_of_point[input.observations[i].point_id];
      if (list.empty()) point_order.push_back(input.observations[i].point_id);
      list.push_back(i);
    }
    for (const std::string& id : point_order) {
      const std::vector<size_t>& list = obs_of_point[id];
      if (list.size() != 1) continue;
      const auto g = ground.find(id);
      if (IsControl(g == ground.end() ? nullptr : g->second) || distance_named.count(id)) continue;
      const ImageObservation& o = input.observations[list[0]];
      active[list[0]] = false;
      changed = true;
      const int before = initial_frames_of_point[id];
      warnings.push_back(
          {"point " + id,
           "seen in frame " + o.frame + " only" +
               (before > 1 ? " (its other " + std::to_string(before - 1) + " frame(s) were left out)" : std::string()) +
               " and not a control point: one ray gives 2 equations for its 3 unknowns; its observation" +
               (o.origin.empty() ? std::string() : " (" + o.origin + ")") + " is left out"});
    }
    // Thin frames.
    std::vector<int> points_of_frame(frames.size(), 0);
    for (size_t i = 0; i < n_obs; ++i) {
      if (active[i]) ++points_of_frame[frame_index[input.observations[i].frame]];
    }
    for (size_t f = 0; f < frames.size(); ++f) {
      if (!frame_kept[f]) continue;
      const FrameSetup& frame = frames[f];
      const int n = points_of_frame[f];
      const int before = initial_points_of_frame[frame.id];
      const std::string seen = "sees " + std::to_string(n) + " point(s)" +
                               (before != n ? " (" + std::to_string(before) + " before others were left out)"
                                            : std::string());
      if (!frame.fixed && n < options.min_points_per_frame) {
        warnings.push_back({"frame " + frame.id,
                            seen + ": its 6 orientation unknowns need at least " +
                                std::to_string(options.min_points_per_frame) +
                                " points (2 equations each); left out with its " + std::to_string(n) +
                                " observation(s)"});
      } else if (frame.fixed && n == 0 && !distance_named.count(frame.id)) {
        warnings.push_back({"frame " + frame.id,
                            seen + " and no distance names it: a fixed frame with nothing to hold adds nothing; "
                                   "left out"});
      } else {
        continue;
      }
      frame_kept[f] = false;
      changed = true;
      for (size_t i = 0; i < n_obs; ++i) {
        if (input.observations[i].frame == frame.id) active[i] = false;
      }
    }
  }

}

// The input that is left, with warnings for the ground points, distances and
// cameras that no longer take part.
void CollectKept(const CheckContext& c, CheckedBundleInput* out) {
  const BundleInput& input = c.input;
  std::vector<BundleWarning>& warnings = out->warnings;
  const std::vector<FrameSetup>& frames = c.frames;
  const std::set<std::string>& observed_ids = c.observed_ids;
  const std::vector<bool>& active = c.active;
  const std::vector<bool>& frame_kept = c.frame_kept;
  const size_t n_obs = input.observations.size();
  // --- What is left ---------------------------------------------------------
  std::set<std::string> kept_frames, kept_points;
  for (size_t f = 0; f < frames.size(); ++f) {
    if (frame_kept[f]) kept_frames.insert(frames[f].id);
  }
  for (size_t i = 0; i < n_obs; ++i) {
    if (active[i]) kept_points.insert(input.observations[i].point_id);
  }
  auto in_network = [&](const std::string& id) { return kept_frames.count(id) || kept_points.count(id); };

  // Ground points observed in no kept frame: kept only when a distance ties
  // them (with their a-priori coordinates) to the network.
  std::set<std::string> kept_unobserved;
  for (const GroundPoint& p : input.ground_points) {
    if (kept_points.count(p.id)) continue;
    std::string tie;
    for (const DistanceObservation& d : input.distances) {
      if (d.from == p.id && in_network(d.to)) tie = d.to;
      if (d.to == p.id && in_network(d.from)) tie = d.from;
    }
    const bool observed_before = observed_ids.count(p.id) > 0;
    const std::string head = observed_before ? "its observations were all left out" : "not observed in any frame";
    if (IsControl(&p) && !tie.empty()) {
      kept_unobserved.insert(p.id);
      warnings.push_back({"ground point " + p.id,
                          head + "; kept: the distance to " + tie +
                              " ties its a-priori coordinates to the network (it acts on the datum)"});
    } else {
      warnings.push_back({"ground point " + p.id,
                          head + "; left out: without an observation" +
                              std::string(IsControl(&p) ? " or a distance to the network"
                                                        : " (and with no a-priori coordinates)") +
                              " it has no effect on the adjustment, the datum included"});
    }
  }
  for (const DistanceObservation& d : input.distances) {
    std::vector<std::string> missing;
    for (const std::string& end : {d.from, d.to}) {
      if (!in_network(end) && !kept_unobserved.count(end)) missing.push_back(end);
    }
    if (missing.empty()) {
      out->input.distances.push_back(d);
    } else {
      warnings.push_back({DistanceName(d), List(missing) + (missing.size() == 1 ? " is" : " are") +
                                               " not in the adjustment (left out or never observed); the distance "
                                               "is left out"});
    }
  }
  std::set<std::string> used_cameras;
  for (size_t f = 0; f < frames.size(); ++f) {
    if (frame_kept[f]) {
      used_cameras.insert(frames[f].camera);
      out->input.frames.push_back(frames[f]);
    }
  }
  for (const CameraSetup& camera : input.cameras) {
    if (used_cameras.count(camera.name)) {
      out->input.cameras.push_back(camera);
    } else {
      warnings.push_back({"camera " + camera.name, "no kept frame uses it; left out"});
    }
  }
  for (size_t i = 0; i < n_obs; ++i) {
    if (active[i]) out->input.observations.push_back(input.observations[i]);
  }
  for (const GroundPoint& p : input.ground_points) {
    if (kept_points.count(p.id) || kept_unobserved.count(p.id)) out->input.ground_points.push_back(p);
  }
  if (out->input.observations.empty()) {
    Fail("no observation is left after the checks (" + std::to_string(warnings.size()) +
         " warning(s); the first: " + warnings.front().item + ": " + warnings.front().reason + ")");
  }
}

}  // namespace

CheckedBundleInput CheckBundleInput(const BundleInput& input, const BundleInputCheckOptions& options) {
  std::string why;
  if (!options.Check(&why)) Fail(why);
  CheckContext context(input);
  CheckErrors(&context);
  CheckedBundleInput out;
  LeaveOutUntilStable(&context, options, &out.warnings);
  CollectKept(context, &out);
  return out;
}

}  // namespace platemeter
