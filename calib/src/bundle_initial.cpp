// Approximations for the bundle adjustment (bundle_adjustment.h
// ComputeBundleApproximations): given values first, then resection from known
// points, relative orientation where nothing is known, forward intersection,
// repeated until every frame is oriented.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "bundle_geometry.h"
#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

using bundle_internal::Pose;

struct FrameState {
  Pose pose;
  bool oriented = false;
  std::string method;
  double c_mm = 0.0;
  double threshold_mm = 0.0;  // RANSAC threshold: the lens' unknown distortion is still in the points
  std::vector<std::pair<int, Eigen::Vector2d>> ideal;  // (point, ideal image point mm)
};

struct PointState {
  std::string id;
  std::optional<Eigen::Vector3d> known;  // a ground point's coordinates (approximate or a-priori)
  std::optional<Eigen::Vector3d> estimate;  // triangulated in the working frame
  std::vector<int> frames;
  std::vector<Eigen::Vector2d> ideal;  // per frame in `frames`: the ideal image point, mm
};

CameraModel ModelOf(const CameraSetup& camera) {
  const auto& v = camera.values;
  return CameraModel(InteriorOrientation{v[0], v[1], v[2]}, DistortionModelId::kBrownAffine,
                     std::vector<double>(v.begin() + 3, v.end()));
}

class Approximator {
 public:
  explicit Approximator(const BundleInput& input) : input_(input) { Index(); }

  BundleApproximations Run() {
    for (size_t f = 0; f < frames_.size(); ++f) {
      const FrameSetup& setup = input_.frames[f];
      if (setup.position_m && setup.angles) {
        frames_[f].pose = {TMatrixFromAngles(*setup.angles), *setup.position_m};
        frames_[f].oriented = true;
        frames_[f].method = setup.fixed ? "fixed" : "given";
      }
    }
    working_frame_is_object_ = true;
    if (NumOriented() == 0) ResectAll(/*from_known=*/true);
    if (NumOriented() == 0) StartByRelativeOrientation();
    for (int round = 0; round < 1000; ++round) {
      Triangulate();
      if (ResectAll(working_frame_is_object_) == 0) break;
    }
    if (!working_frame_is_object_) MoveOntoControl();
    for (size_t f = 0; f < frames_.size(); ++f) {
      if (!frames_[f].oriented) {
        throw Error("bundle", fmt::format("frame {} cannot be oriented: it shares fewer than 6 points with the "
                                          "oriented frames or known ground points",
                                          input_.frames[f].id));
      }
    }
    return Collect();
  }

 private:
  void Index() {
    std::map<std::string, int> camera_index, frame_index;
    for (size_t i = 0; i < input_.cameras.size(); ++i) camera_index[input_.cameras[i].name] = static_cast<int>(i);
    frames_.resize(input_.frames.size());
    for (size_t f = 0; f < input_.frames.size(); ++f) {
      frame_index[input_.frames[f].id] = static_cast<int>(f);
      if (!camera_index.count(input_.frames[f].camera)) {
        throw Error("bundle", fmt::format("frame {}: unknown camera '{}'", input_.frames[f].id, input_.frames[f].camera));
      }
    }
    std::map<std::string, int> point_index;
    for (const GroundPoint& g : input_.ground_points) {
      point_index[g.id] = static_cast<int>(points_.size());
      points_.push_back({g.id, g.position_m, std::nullopt, {}, {}});
    }
    std::map<int, std::vector<double>> sigmas, extents;
    std::vector<CameraModel> models;
    for (const CameraSetup& c : input_.cameras) models.push_back(ModelOf(c));
    for (const ImageObservation& o : input_.observations) {
      auto f = frame_index.find(o.frame);
      if (f == frame_index.end()) {
        throw Error(o.origin.empty() ? "bundle" : o.origin, fmt::format("observation of unknown frame '{}'", o.frame));
      }
      auto [p, added] = point_index.emplace(o.point_id, static_cast<int>(points_.size()));
      if (added) points_.push_back({o.point_id, std::nullopt, std::nullopt, {}, {}});
      const int camera = camera_index[input_.frames[f->second].camera];
      const auto ideal = models[camera].IdealFromMeasured(Eigen::Vector2d(o.x_mm, o.y_mm));
      if (!ideal) continue;
      frames_[f->second].ideal.emplace_back(p->second, *ideal);
      points_[p->second].frames.push_back(f->second);
      points_[p->second].ideal.push_back(*ideal);
      sigmas[f->second].push_back(std::max(o.sigma_x_mm, o.sigma_y_mm));
      extents[f->second].push_back(std::max(std::abs(o.x_mm), std::abs(o.y_mm)));
    }
    for (size_t f = 0; f < frames_.size(); ++f) {
      frames_[f].c_mm = input_.cameras[camera_index[input_.frames[f].camera]].values[0];
      double sigma = 0.0, extent = 0.0;
      for (double s : sigmas[f]) sigma = std::max(sigma, s);
      for (double e : extents[f]) extent = std::max(extent, e);
      frames_[f].threshold_mm = std::max(20.0 * sigma, 0.02 * extent);
    }
  }

  int NumOriented() const {
    return static_cast<int>(std::count_if(frames_.begin(), frames_.end(), [](const auto& f) { return f.oriented; }));
  }

  // Coordinates usable for resection in the working frame.
  std::optional<Eigen::Vector3d> Usable(const PointState& p, bool from_known) const {
    if (from_known && p.known) return p.known;
    return p.estimate;
  }

  int ResectAll(bool from_known) {
    int added = 0;
    for (FrameState& frame : frames_) {
      if (frame.oriented) continue;
      std::vector<Eigen::Vector3d> object;
      std::vector<Eigen::Vector2d> image;
      for (const auto& [p, ideal] : frame.ideal) {
        if (auto x = Usable(points_[p], from_known)) {
          object.push_back(*x);
          image.push_back(ideal);
        }
      }
      if (object.size() < 6) continue;
      if (auto pose = bundle_internal::Resect(object, image, frame.c_mm, frame.threshold_mm)) {
        frame.pose = *pose;
        frame.oriented = true;
        frame.method = "resection";
        ++added;
      }
    }
    return added;
  }

  void Triangulate() {
    for (PointState& p : points_) {
      if (working_frame_is_object_ && p.known) continue;
      std::vector<Eigen::Vector3d> stations, directions;
      for (size_t k = 0; k < p.frames.size(); ++k) {
        const FrameState& frame = frames_[p.frames[k]];
        if (!frame.oriented) continue;
        stations.push_back(frame.pose.station_m);
        directions.push_back(bundle_internal::RayInObject(frame.pose, p.ideal[k], frame.c_mm));
      }
      if (auto x = bundle_internal::IntersectRays(stations, directions)) p.estimate = *x;
    }
  }

  // No frame and no point known: the pair of frames sharing the most points
  // that gives the widest intersection angles starts an arbitrary frame.
  void StartByRelativeOrientation() {
    std::map<std::pair<int, int>, int> shared;
    for (const PointState& p : points_) {
      for (size_t i = 0; i < p.frames.size(); ++i) {
        for (size_t j = i + 1; j < p.frames.size(); ++j) ++shared[{std::min(p.frames[i], p.frames[j]), std::max(p.frames[i], p.frames[j])}];
      }
    }
    std::vector<std::pair<int, std::pair<int, int>>> pairs;
    for (const auto& [pair, count] : shared) pairs.emplace_back(count, pair);
    std::sort(pairs.rbegin(), pairs.rend());
    double best_angle = 0.0;
    std::optional<std::pair<int, Pose>> best;
    int best_a = -1;
    for (size_t k = 0; k < pairs.size() && k < 8; ++k) {
      const auto [a, b] = pairs[k].second;
      std::map<int, Eigen::Vector2d> in_b;
      for (const auto& [p, ideal] : frames_[b].ideal) in_b[p] = ideal;
      std::vector<Eigen::Vector2d> ia, ib;
      std::vector<int> common;
      for (const auto& [p, ideal] : frames_[a].ideal) {
        if (in_b.count(p)) {
          ia.push_back(ideal);
          ib.push_back(in_b[p]);
          common.push_back(p);
        }
      }
      const Pose pose_a;
      auto relative = bundle_internal::RelativeOrientation(pose_a, ia, ib, frames_[a].c_mm,
                                                           frames_[a].threshold_mm, 1.0);
      if (!relative || relative->inliers < 0.7 * double(common.size())) continue;
      // Median angle between the two rays of the common points.
      std::vector<double> angles;
      for (size_t i = 0; i < common.size(); ++i) {
        const Eigen::Vector3d da = bundle_internal::RayInObject(pose_a, ia[i], frames_[a].c_mm);
        const Eigen::Vector3d db = bundle_internal::RayInObject(relative->b, ib[i], frames_[b].c_mm);
        angles.push_back(std::acos(std::clamp(da.dot(db), -1.0, 1.0)));
      }
      std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
      if (angles[angles.size() / 2] > best_angle) {
        best_angle = angles[angles.size() / 2];
        best = std::make_pair(b, relative->b);
        best_a = a;
      }
    }
    if (!best || best_angle < 1e-4) {
      throw Error("bundle", "no pair of frames can be relatively oriented (all frames at one station, or too few "
                            "common points): give approximate orientations or control points");
    }
    frames_[best_a].pose = Pose{};
    frames_[best_a].oriented = true;
    frames_[best_a].method = "relative orientation";
    frames_[best->first].pose = best->second;
    frames_[best->first].oriented = true;
    frames_[best->first].method = "relative orientation";
    working_frame_is_object_ = false;
  }

  // A network built in an arbitrary frame, moved onto the known points.
  void MoveOntoControl() {
    std::vector<Eigen::Vector3d> from, to;
    for (const PointState& p : points_) {
      if (p.known && p.estimate) {
        from.push_back(*p.estimate);
        to.push_back(*p.known);
      }
    }
    if (from.size() < 3) return;  // a free network: the arbitrary frame stays
    const auto s = bundle_internal::FitSimilarity(from, to);
    for (FrameState& f : frames_) {
      if (!f.oriented) continue;
      f.pose.station_m = s.Apply(f.pose.station_m);
      f.pose.image_from_object = f.pose.image_from_object * s.rotation.transpose();
    }
    for (PointState& p : points_) {
      if (p.estimate) p.estimate = s.Apply(*p.estimate);
    }
    working_frame_is_object_ = true;
  }

  BundleApproximations Collect() {
    if (working_frame_is_object_) Triangulate();
    BundleApproximations out;
    for (size_t f = 0; f < frames_.size(); ++f) {
      FrameSetup setup = input_.frames[f];
      setup.position_m = frames_[f].pose.station_m;
      setup.angles = AnglesFromTMatrix(frames_[f].pose.image_from_object);
      out.frames.push_back(setup);
      out.method.push_back(frames_[f].method);
    }
    for (const PointState& p : points_) {
      if (p.frames.empty()) continue;
      const auto x = (working_frame_is_object_ && p.known) ? p.known : p.estimate;
      if (!x) {
        throw Error("bundle", fmt::format("point {}: its rays do not intersect (seen in {} frames from nearly one "
                                          "station, or its frames could not be oriented)",
                                          p.id, p.frames.size()));
      }
      out.points.emplace_back(p.id, *x);
    }
    return out;
  }

  const BundleInput& input_;
  std::vector<FrameState> frames_;
  std::vector<PointState> points_;
  bool working_frame_is_object_ = true;
};

}  // namespace

BundleApproximations ComputeBundleApproximations(const BundleInput& input) { return Approximator(input).Run(); }

}  // namespace platemeter
