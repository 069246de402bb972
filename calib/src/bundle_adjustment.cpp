// The self-calibrating bundle adjustment (bundle_adjustment.h): checks,
// approximations, the problem, the engine, and the result in the bundle's words.
#include "platemeter/calib/bundle_adjustment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include "bundle_build.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// All frames at one station: no ray intersects another, nothing can be determined.
void CheckStations(const BundleApproximations& approximations) {
  if (approximations.frames.size() < 2 || approximations.points.empty()) return;
  double baseline = 0.0, range = 0.0;
  const Eigen::Vector3d first = *approximations.frames[0].position_m;
  for (const FrameSetup& f : approximations.frames) baseline = std::max(baseline, (*f.position_m - first).norm());
  for (const auto& [id, x] : approximations.points) range = std::max(range, (x - first).norm());
  if (!(baseline > 1e-6 * range)) {
    throw Error("bundle", "all frames are at one station: their rays do not intersect, so neither the points nor "
                          "the inner cone can be determined");
  }
}

BundleCameraResult CollectCamera(const CameraSetup& setup, const AdjustmentResult& a,
                                 double alpha) {
  BundleCameraResult camera;
  camera.name = setup.name;
  camera.format_width_mm = setup.format_width_mm;
  camera.format_height_mm = setup.format_height_mm;
  camera.definition = setup.definition;
  const std::string label = "camera " + setup.name;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    const int index = a.Find(label, kBundleCameraParamNames[i]);
    camera.parameter_index.push_back(index);
    camera.values[i] = a.parameters[index].value;
    camera.sigmas[i] = a.parameters[index].sigma;
    camera.status[i] = a.parameters[index].status;
  }
  auto adjusted = [&](int i) { return camera.sigmas[i].has_value(); };
  for (int i : {3, 4, 5}) {
    if (adjusted(i)) camera.tests.push_back(a.Test({camera.parameter_index[i]}, alpha));
  }
  if (adjusted(6) && adjusted(7)) camera.tests.push_back(a.Test({camera.parameter_index[6], camera.parameter_index[7]}, alpha));
  if (adjusted(8) && adjusted(9)) camera.tests.push_back(a.Test({camera.parameter_index[8], camera.parameter_index[9]}, alpha));
  return camera;
}

// Where each block's parameters start in a.parameters, by block label: the
// lookups below are by label, and AdjustmentResult::Find's linear search made
// them quadratic in the number of blocks (seconds on 20 000 points).
std::unordered_map<std::string, int> FirstParameterOfBlock(const AdjustmentResult& a) {
  std::unordered_map<std::string, int> first;
  for (size_t i = 0; i < a.parameters.size(); ++i) first.emplace(a.parameters[i].block, static_cast<int>(i));
  return first;
}

// The index of block/name in a.parameters, -1 if absent.
int FindParameter(const AdjustmentResult& a, const std::unordered_map<std::string, int>& first,
                  const std::string& block, const std::string& name) {
  const auto it = first.find(block);
  if (it == first.end()) return -1;
  for (size_t i = it->second; i < a.parameters.size() && a.parameters[i].block == block; ++i) {
    if (a.parameters[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

BundleResult RunBundleAdjustment(const BundleInput& input, const BundleOptions& options,
                                 const AdjustmentProgress& progress) {
  std::string why;
  if (!options.Check(&why)) throw Error("bundle options", why);
  if (input.cameras.empty()) throw Error("bundle", "no camera is defined");
  if (input.frames.size() < 2) throw Error("bundle", "a bundle needs at least two frames");
  BundleResult result;
  result.options = options;
  const auto start = std::chrono::steady_clock::now();
  if (progress) progress("approximations", 0.0);
  const BundleApproximations approximations = ComputeBundleApproximations(input);
  CheckStations(approximations);
  result.initial_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  AdjustmentProblem problem;
  const bundle_internal::BuiltBundle built =
      bundle_internal::BuildBundleProblem(input, approximations, options.datum, &problem);
  result.datum = built.datum;
  result.datum_words = built.datum_words;
  const bool arbitrary = std::count(approximations.method.begin(), approximations.method.end(),
                                    "relative orientation") > 0 &&
                         input.ground_points.empty() && input.distances.empty();
  if (arbitrary) {
    result.datum_words += "; object coordinates in the frame of the relative orientation (the first pair's "
                          "baseline is 1 unit): give a distance or control points for metres";
  }
  result.adjustment = problem.Solve(options.adjustment, progress);
  const AdjustmentResult& a = result.adjustment;

  for (size_t c = 0; c < input.cameras.size(); ++c) {
    result.cameras.push_back(CollectCamera(input.cameras[c], a, options.adjustment.significance_level));
    BundleCameraResult& camera = result.cameras.back();
    if (camera.format_width_mm <= 0.0 || camera.format_height_mm <= 0.0) {
      // No format given: the smallest centred one holding every observation (profiles, plots).
      std::map<std::string, bool> of_camera;
      for (const FrameSetup& f : input.frames) of_camera[f.id] = f.camera == camera.name;
      double half_x = 0.0, half_y = 0.0;
      for (const ImageObservation& o : input.observations) {
        if (!of_camera[o.frame]) continue;
        half_x = std::max(half_x, std::abs(o.x_mm));
        half_y = std::max(half_y, std::abs(o.y_mm));
      }
      camera.format_width_mm = 2.0 * half_x;
      camera.format_height_mm = 2.0 * half_y;
      camera.format_from_observations = true;
    }
  }
  // Residual RMS per frame and per point from the used observations.
  std::unordered_map<std::string, std::array<double, 3>> by_frame, by_point;  // sum x^2, sum y^2, count
  for (const ObservationResidual& r : a.residuals) {
    if (r.status != ObservationStatus::kUsed || r.residual.size() != 2 || r.group == "distance") continue;
    for (auto* m : {&by_frame[r.group], &by_point[r.item]}) {
      (*m)[0] += r.residual[0] * r.residual[0];
      (*m)[1] += r.residual[1] * r.residual[1];
      (*m)[2] += 1;
    }
  }
  const std::unordered_map<std::string, int> first_parameter = FirstParameterOfBlock(a);
  std::unordered_map<std::string, const AdjustmentResult::PointEstimate*> eliminated;
  for (const AdjustmentResult::PointEstimate& e : a.points) eliminated.emplace(e.label, &e);
  for (size_t f = 0; f < input.frames.size(); ++f) {
    BundleFrameResult frame;
    frame.id = input.frames[f].id;
    frame.camera = input.frames[f].camera;
    frame.initial_values = approximations.method[f];
    const std::string label = "frame " + frame.id;
    std::array<double, 6> v{};
    for (int i = 0; i < 6; ++i) {
      const ParameterEstimate& p = a.parameters[FindParameter(a, first_parameter, label, kBundleFrameParamNames[i])];
      v[i] = p.value;
      frame.sigmas[i] = p.sigma;
    }
    frame.position_m = Eigen::Vector3d(v[0], v[1], v[2]);
    frame.angles = {v[3], v[4], v[5]};
    const auto& m = by_frame[frame.id];
    frame.observations = static_cast<int>(m[2]);
    if (m[2] > 0) {
      frame.rms_x_um = 1e3 * std::sqrt(m[0] / m[2]);
      frame.rms_y_um = 1e3 * std::sqrt(m[1] / m[2]);
    }
    result.frames.push_back(frame);
  }
  for (size_t p = 0; p < built.point_ids.size(); ++p) {
    BundlePointResult point;
    point.id = built.point_ids[p];
    point.control = built.point_control[p];
    const std::string label = "point " + point.id;
    const int global = FindParameter(a, first_parameter, label, "X_m");
    if (global >= 0) {
      for (int k = 0; k < 3; ++k) point.position_m[k] = a.parameters[global + k].value;
      if (a.parameters[global].sigma) {
        point.sigma_m = Eigen::Vector3d(*a.parameters[global].sigma, a.parameters[global + 1].sigma.value_or(0),
                                        a.parameters[global + 2].sigma.value_or(0));
      }
    } else {
      const auto e = eliminated.find(label);
      if (e != eliminated.end()) {
        point.position_m = e->second->value;
        point.sigma_m = e->second->sigma;
        point.rays = e->second->rays;
      }
    }
    const auto& m = by_point[point.id];
    if (m[2] > 0) point.rms_um = 1e3 * std::sqrt((m[0] + m[1]) / (2 * m[2]));
    if (point.rays == 0) point.rays = static_cast<int>(m[2]);
    result.points.push_back(point);
  }
  return result;
}

}  // namespace platemeter
