// Building the bundle's adjustment problem: blocks for cameras, frames and
// points, their a-priori states, the observation equations, distances, and
// the datum (bundle_adjustment.h).
#include "bundle_build.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include "bundle_collinearity.h"
#include "bundle_equations.h"
#include "platemeter/core/error.h"

namespace platemeter::bundle_internal {
namespace {

bool HasPrior(const GroundPoint& g) {
  return std::any_of(g.sigma_m.begin(), g.sigma_m.end(), [](const auto& s) { return s.has_value(); });
}

void SetPointStates(const GroundPoint& g, int block, AdjustmentProblem* problem) {
  for (int axis = 0; axis < 3; ++axis) {
    if (!g.sigma_m[axis]) continue;
    problem->SetState(block, axis, *g.sigma_m[axis] > 0.0 ? ParameterState::Weighted(*g.sigma_m[axis])
                                                          : ParameterState::Fixed());
  }
}

void AddFramePriors(const FrameSetup& frame, int block, bool hold, AdjustmentProblem* problem) {
  if (hold) {
    for (int i = 0; i < 6; ++i) problem->SetState(block, i, ParameterState::Fixed());
    return;
  }
  if (frame.position_covariance_m2 && frame.position_m) {
    problem->AddPrior(block, {0, 1, 2}, *frame.position_m, *frame.position_covariance_m2,
                      "frame " + frame.id + " station");
  }
  if (frame.angle_sigma_rad && frame.angles) {
    for (int i = 0; i < 3; ++i) {
      const double sigma = (*frame.angle_sigma_rad)[i];
      problem->SetState(block, 3 + i, sigma > 0.0 ? ParameterState::Weighted(sigma) : ParameterState::Fixed());
    }
  }
}

// The similarity transformations of the object frame (3 translations, 3
// rotations about the stations' centroid, the scale), as changes of the
// non-point parameters: a free network's gauge, or words for a datum defect.
void SetSimilarityGauge(const BuiltBundle& built, bool is_datum, AdjustmentProblem* problem) {
  const int n = problem->NumGlobalParameters();
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(n, 7);
  std::vector<bool> trace_rows(n, false);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int b : built.frame_blocks) centroid += Eigen::Vector3d(problem->Values(b).data());
  centroid /= std::max<size_t>(1, built.frame_blocks.size());
  auto fill = [&](int block, bool station) {
    const int row = problem->GlobalOffset(block);
    if (row < 0) return;
    const Eigen::Vector3d x = Eigen::Vector3d(problem->Values(block).data()) - centroid;
    for (int k = 0; k < 3; ++k) {
      g(row + k, k) = 1.0;
      trace_rows[row + k] = station;
      g.block<3, 1>(row, 3 + k) = Eigen::Vector3d::Unit(k).cross(x);
      g(row + k, 6) = x[k];
    }
    if (!station) return;
    // Angles: T' = T R(eps)^T, by central differences.
    const std::vector<double>& v = problem->Values(block);
    const Eigen::Matrix3d t = TMatrixFromAngles({v[3], v[4], v[5]});
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Matrix3d plus = Eigen::AngleAxisd(h, Eigen::Vector3d::Unit(k)).toRotationMatrix();
      const PhiOmegaKappaT a = AnglesFromTMatrix(t * plus.transpose());
      const PhiOmegaKappaT b = AnglesFromTMatrix(t * plus);
      auto wrap = [](double d) { return std::remainder(d, 2 * M_PI); };
      g(row + 3, 3 + k) = wrap(a.phi_rad - b.phi_rad) / (2 * h);
      g(row + 4, 3 + k) = wrap(a.omega_rad - b.omega_rad) / (2 * h);
      g(row + 5, 3 + k) = wrap(a.kappa_rad - b.kappa_rad) / (2 * h);
    }
  };
  for (int b : built.frame_blocks) fill(b, true);
  for (int b : built.point_blocks) fill(b, false);
  problem->SetGauge(g,
                    {"a translation along X", "a translation along Y", "a translation along Z",
                     "a rotation about X", "a rotation about Y", "a rotation about Z", "the network's scale"},
                    trace_rows, is_datum);
}

}  // namespace

DatumKind ResolveDatum(const BundleInput& input, DatumKind requested) {
  if (requested != DatumKind::kAuto) return requested;
  // A-priori coordinates of points or stations (seed 000 section 3.3's tracking) fix the datum.
  if (std::any_of(input.ground_points.begin(), input.ground_points.end(), HasPrior) ||
      std::any_of(input.frames.begin(), input.frames.end(),
                  [](const FrameSetup& f) { return f.position_covariance_m2.has_value(); })) {
    return DatumKind::kControlPoints;
  }
  if (std::any_of(input.frames.begin(), input.frames.end(), [](const FrameSetup& f) { return f.fixed; })) {
    return DatumKind::kFixedFrames;
  }
  return DatumKind::kInnerConstraints;
}

BuiltBundle BuildBundleProblem(const BundleInput& input, const BundleApproximations& approximations,
                               DatumKind requested, AdjustmentProblem* problem) {
  BuiltBundle built;
  built.datum = ResolveDatum(input, requested);
  // Hash maps: 400 000 observations look their blocks up by id.
  std::unordered_map<std::string, int> camera_index, frame_index, point_index;
  for (const CameraSetup& camera : input.cameras) {
    if (!camera_index.emplace(camera.name, static_cast<int>(built.camera_blocks.size())).second) {
      throw Error("bundle", "camera '" + camera.name + "' is defined twice");
    }
    const int block = problem->AddBlock(
        "camera " + camera.name, "camera", BlockKind::kGlobal,
        std::vector<std::string>(kBundleCameraParamNames.begin(), kBundleCameraParamNames.end()),
        std::vector<double>(camera.values.begin(), camera.values.end()));
    for (int i = 0; i < kBundleCameraParams; ++i) problem->SetState(block, i, camera.states[i]);
    built.camera_blocks.push_back(block);
  }
  // Frames: with a fixed-frames datum and none flagged, the frame with the most observations is held.
  std::unordered_map<std::string, int> observations_of;
  for (const ImageObservation& o : input.observations) ++observations_of[o.frame];
  std::string held;
  const bool any_fixed = std::any_of(input.frames.begin(), input.frames.end(), [](const auto& f) { return f.fixed; });
  if (built.datum == DatumKind::kFixedFrames && !any_fixed && !input.frames.empty()) {
    held = std::max_element(input.frames.begin(), input.frames.end(), [&](const auto& a, const auto& b) {
             return observations_of[a.id] < observations_of[b.id];
           })->id;
  }
  std::vector<std::string> fixed_names;
  for (size_t f = 0; f < input.frames.size(); ++f) {
    const FrameSetup& frame = approximations.frames[f];
    if (!frame_index.emplace(frame.id, static_cast<int>(f)).second) {
      throw Error("bundle", "frame '" + frame.id + "' is listed twice");
    }
    const PhiOmegaKappaT& a = *frame.angles;
    const int block = problem->AddBlock(
        "frame " + frame.id, "frame", BlockKind::kStation,
        std::vector<std::string>(kBundleFrameParamNames.begin(), kBundleFrameParamNames.end()),
        {frame.position_m->x(), frame.position_m->y(), frame.position_m->z(), a.phi_rad, a.omega_rad, a.kappa_rad});
    const bool hold = (frame.fixed && built.datum != DatumKind::kInnerConstraints) || frame.id == held;
    if (hold) fixed_names.push_back(frame.id);
    AddFramePriors(input.frames[f], block, hold, problem);
    built.frame_blocks.push_back(block);
  }
  // Points: those in distance equations stay in the reduced system.
  std::unordered_map<std::string, bool> in_distance;
  for (const DistanceObservation& d : input.distances) in_distance[d.from] = in_distance[d.to] = true;
  std::unordered_map<std::string, const GroundPoint*> ground;
  for (const GroundPoint& g : input.ground_points) ground[g.id] = &g;
  for (const auto& [id, position] : approximations.points) {
    const bool global = in_distance.count(id) > 0;
    const int block = problem->AddBlock("point " + id, "point", global ? BlockKind::kGlobal : BlockKind::kPoint,
                                        {"X_m", "Y_m", "Z_m"}, {position.x(), position.y(), position.z()});
    const auto g = ground.find(id);
    const bool control = g != ground.end() && HasPrior(*g->second);
    if (control && built.datum != DatumKind::kInnerConstraints) SetPointStates(*g->second, block, problem);
    point_index[id] = static_cast<int>(built.point_ids.size());
    built.point_ids.push_back(id);
    built.point_blocks.push_back(block);
    built.point_control.push_back(control);
  }
  problem->ReserveObservations(input.observations.size() + input.distances.size());
  // Observations usually come frame by frame: look the frame up when it changes.
  const std::string* last_frame = nullptr;
  int frame = -1, camera = -1;
  for (const ImageObservation& o : input.observations) {
    if (last_frame == nullptr || o.frame != *last_frame) {
      frame = frame_index.at(o.frame);
      camera = camera_index.at(input.frames[frame].camera);
      last_frame = &o.frame;
    }
    Eigen::Matrix2d covariance = Eigen::Vector2d(o.sigma_x_mm * o.sigma_x_mm, o.sigma_y_mm * o.sigma_y_mm).asDiagonal();
    problem->AddObservation(new CollinearityCost(o.x_mm, o.y_mm, frame),
                            {built.camera_blocks[camera], built.frame_blocks[frame],
                             built.point_blocks[point_index.at(o.point_id)]},
                            covariance, o.frame, o.point_id, o.origin);
  }
  for (const DistanceObservation& d : input.distances) {
    auto block_of = [&](const std::string& id) {
      if (frame_index.count(id)) return built.frame_blocks[frame_index[id]];
      if (point_index.count(id)) return built.point_blocks[point_index[id]];
      throw Error("bundle", "distance names '" + id + "', neither a frame nor an observed point");
    };
    const int a = block_of(d.from), b = block_of(d.to);
    const double sigma = d.sigma_m > 0.0 ? d.sigma_m : 1e-9 * d.distance_m;
    problem->AddObservation(CreateDistanceEquation(problem->BlockSize(a), problem->BlockSize(b), d.distance_m), {a, b},
                            Eigen::MatrixXd::Constant(1, 1, sigma * sigma), "distance", d.from + "-" + d.to, "");
  }
  const bool free_network = built.datum == DatumKind::kInnerConstraints;
  SetSimilarityGauge(built, free_network, problem);
  int control = static_cast<int>(std::count(built.point_control.begin(), built.point_control.end(), true));
  switch (built.datum) {
    case DatumKind::kControlPoints: {
      const auto stations = std::count_if(input.frames.begin(), input.frames.end(),
                                          [](const FrameSetup& f) { return f.position_covariance_m2.has_value(); });
      built.datum_words =
          fmt::format("control: {} points and {} stations with a-priori coordinates", control, stations);
      break;
    }
    case DatumKind::kFixedFrames:
      built.datum_words = fmt::format("frame{} {} held fixed{}", fixed_names.size() == 1 ? "" : "s",
                                      fmt::join(fixed_names, ", "),
                                      input.distances.empty() ? "" : fmt::format(", {} distance(s)", input.distances.size()));
      break;
    case DatumKind::kInnerConstraints:
      built.datum_words = "inner constraints (free network): minimum trace over the exposure stations";
      break;
    case DatumKind::kAuto: break;
  }
  return built;
}

}  // namespace platemeter::bundle_internal
