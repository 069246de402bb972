#pragma once
// Geometry for the bundle's approximations (bundle_initial.cpp): rays,
// forward intersection, resection (OpenCV solvePnP), relative orientation
// (OpenCV essential matrix) and the similarity onto control points.
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/rotations.h"

namespace platemeter::bundle_internal {

struct Pose {
  Eigen::Matrix3d image_from_object = Eigen::Matrix3d::Identity();  // seed 000's T
  Eigen::Vector3d station_m = Eigen::Vector3d::Zero();
};

// Unit ray in the object frame through an ideal image point (mm from the
// principal point, distortion removed) of a camera with principal distance c.
Eigen::Vector3d RayInObject(const Pose& pose, const Eigen::Vector2d& ideal_mm, double c_mm);

// Least-squares intersection of rays (station, unit direction); nullopt if the
// rays are (nearly) parallel: the smallest eigenvalue of sum(I - d d^T) below
// min_spread (about the squared sine of the largest angle between rays).
std::optional<Eigen::Vector3d> IntersectRays(const std::vector<Eigen::Vector3d>& stations,
                                             const std::vector<Eigen::Vector3d>& directions,
                                             double min_spread = 1e-8);

// Resection from known points and their ideal image points; nullopt if it
// fails or fewer than 4 points agree within threshold_mm.
std::optional<Pose> Resect(const std::vector<Eigen::Vector3d>& points_m, const std::vector<Eigen::Vector2d>& ideal_mm,
                           double c_mm, double threshold_mm);

// Relative orientation of frame b to frame a (a's pose given) from common ideal
// points; the baseline gets length baseline_m. Returns b's pose and the
// inlier count; nullopt if it fails.
struct RelativeResult {
  Pose b;
  int inliers = 0;
};
std::optional<RelativeResult> RelativeOrientation(const Pose& a, const std::vector<Eigen::Vector2d>& ideal_a_mm,
                                                  const std::vector<Eigen::Vector2d>& ideal_b_mm, double c_mm,
                                                  double threshold_mm, double baseline_m);

// Similarity (scale, rotation, translation) taking `from` onto `to` (>= 3 points).
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& x) const { return scale * rotation * x + translation; }
};
Similarity FitSimilarity(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to);

}  // namespace platemeter::bundle_internal
