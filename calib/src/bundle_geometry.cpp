// Geometry for the bundle's approximations (bundle_geometry.h).
#include "bundle_geometry.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace platemeter::bundle_internal {
namespace {

cv::Mat CameraMatrix(double c_mm) {
  return (cv::Mat_<double>(3, 3) << c_mm, 0, 0, 0, c_mm, 0, 0, 0, 1);
}

std::vector<cv::Point2d> ToCv(const std::vector<Eigen::Vector2d>& points) {
  std::vector<cv::Point2d> out;
  for (const auto& p : points) out.emplace_back(p.x(), p.y());
  return out;
}

}  // namespace

Eigen::Vector3d RayInObject(const Pose& pose, const Eigen::Vector2d& ideal_mm, double c_mm) {
  // (u, v, w) = T d with x = c u / w: d = T^T (x, y, c).
  return (pose.image_from_object.transpose() * Eigen::Vector3d(ideal_mm.x(), ideal_mm.y(), c_mm)).normalized();
}

std::optional<Eigen::Vector3d> IntersectRays(const std::vector<Eigen::Vector3d>& stations,
                                             const std::vector<Eigen::Vector3d>& directions, double min_spread) {
  if (stations.size() < 2) return std::nullopt;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < stations.size(); ++i) {
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - directions[i] * directions[i].transpose();
    a += projector;
    b += projector * stations[i];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  if (!(eigen.eigenvalues()[0] > min_spread * double(stations.size()))) return std::nullopt;
  return Eigen::Vector3d(a.ldlt().solve(b));
}

std::optional<Pose> Resect(const std::vector<Eigen::Vector3d>& points_m, const std::vector<Eigen::Vector2d>& ideal_mm,
                           double c_mm, double threshold_mm) {
  if (points_m.size() < 4) return std::nullopt;
  // Object coordinates about their centroid: orbital coordinates are 1e6 m.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points_m) centroid += p;
  centroid /= double(points_m.size());
  std::vector<cv::Point3d> object;
  for (const auto& p : points_m) object.emplace_back(p.x() - centroid.x(), p.y() - centroid.y(), p.z() - centroid.z());
  const std::vector<cv::Point2d> image = ToCv(ideal_mm);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const cv::Mat k = CameraMatrix(c_mm);
  try {
    if (!cv::solvePnPRansac(object, image, k, cv::noArray(), rvec, tvec, false, 300, threshold_mm, 0.999, inliers,
                            cv::SOLVEPNP_EPNP) ||
        inliers.size() < 4) {
      return std::nullopt;
    }
    std::vector<cv::Point3d> object_in;
    std::vector<cv::Point2d> image_in;
    for (int i : inliers) {
      object_in.push_back(object[i]);
      image_in.push_back(image[i]);
    }
    cv::solvePnP(object_in, image_in, k, cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Pose pose;
  cv::cv2eigen(r, pose.image_from_object);
  Eigen::Vector3d t;
  cv::cv2eigen(tvec, t);
  pose.station_m = centroid - pose.image_from_object.transpose() * t;
  if (!pose.station_m.allFinite()) return std::nullopt;
  return pose;
}

std::optional<RelativeResult> RelativeOrientation(const Pose& a, const std::vector<Eigen::Vector2d>& ideal_a_mm,
                                                  const std::vector<Eigen::Vector2d>& ideal_b_mm, double c_mm,
                                                  double threshold_mm, double baseline_m) {
  if (ideal_a_mm.size() < 8) return std::nullopt;
  const std::vector<cv::Point2d> pa = ToCv(ideal_a_mm), pb = ToCv(ideal_b_mm);
  const cv::Mat k = CameraMatrix(c_mm);
  cv::Mat mask, r, t;
  try {
    const cv::Mat e = cv::findEssentialMat(pa, pb, k, cv::RANSAC, 0.999, threshold_mm, mask);
    if (e.rows != 3 || e.cols != 3) return std::nullopt;
    const int inliers = cv::recoverPose(e, pa, pb, k, r, t, mask);
    if (inliers < 8) return std::nullopt;
    // Camera b's coordinates = R (camera a's) + t, camera a's = T_a (X - C_a).
    Eigen::Matrix3d rotation;
    Eigen::Vector3d translation;
    cv::cv2eigen(r, rotation);
    cv::cv2eigen(t, translation);
    RelativeResult out;
    out.b.image_from_object = rotation * a.image_from_object;
    out.b.station_m = a.station_m - out.b.image_from_object.transpose() * translation.normalized() * baseline_m;
    out.inliers = inliers;
    return out;
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
}

Similarity FitSimilarity(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to) {
  Eigen::Matrix3Xd src(3, from.size()), dst(3, to.size());
  for (size_t i = 0; i < from.size(); ++i) {
    src.col(i) = from[i];
    dst.col(i) = to[i];
  }
  const Eigen::Matrix4d m = Eigen::umeyama(src, dst, true);
  Similarity s;
  const Eigen::Matrix3d sr = m.topLeftCorner<3, 3>();
  s.scale = std::cbrt(sr.determinant());
  s.rotation = sr / s.scale;
  s.translation = m.topRightCorner<3, 1>();
  return s;
}

}  // namespace platemeter::bundle_internal
