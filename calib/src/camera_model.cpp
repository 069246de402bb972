#include "platemeter/calib/camera_model.h"

#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "platemeter/core/error.h"

namespace platemeter {

CameraModel::CameraModel(const InteriorOrientation& interior, DistortionModelId model,
                         std::vector<double> params)
    : interior_(interior), model_(model), params_(std::move(params)) {
  if (!(interior_.principal_distance_mm > 0.0) || !std::isfinite(interior_.principal_distance_mm)) {
    throw Error("camera model", fmt::format("principal distance must be positive, got {} mm",
                                            interior_.principal_distance_mm));
  }
  if (!std::isfinite(interior_.principal_point_x_mm) ||
      !std::isfinite(interior_.principal_point_y_mm)) {
    throw Error("camera model", "principal point is not finite");
  }
  const int expected = DistortionModelNumParams(model_);
  if (static_cast<int>(params_.size()) != expected) {
    throw Error("camera model", fmt::format("distortion model {} takes {} parameters, got {}",
                                            DistortionModelName(model_), expected, params_.size()));
  }
  for (double p : params_) {
    if (!std::isfinite(p)) throw Error("camera model", "a distortion parameter is not finite");
  }
}

std::optional<Eigen::Vector2d> CameraModel::IdealFromMeasured(const Eigen::Vector2d& point_mm) const {
  const double xb = point_mm.x() - interior_.principal_point_x_mm;
  const double yb = point_mm.y() - interior_.principal_point_y_mm;
  return VisitDistortionModel(model_, [&](auto model) -> std::optional<Eigen::Vector2d> {
    using Model = decltype(model);
    double x = 0.0, y = 0.0;
    if (!platemeter::IdealFromMeasured<Model>(params_.data(), xb, yb, &x, &y)) return std::nullopt;
    return Eigen::Vector2d(x, y);
  });
}

std::optional<Eigen::Vector2d> CameraModel::MeasuredFromIdeal(const Eigen::Vector2d& ideal_mm) const {
  return VisitDistortionModel(model_, [&](auto model) -> std::optional<Eigen::Vector2d> {
    using Model = decltype(model);
    double x = 0.0, y = 0.0;
    if (!platemeter::MeasuredFromIdeal<Model>(params_.data(), ideal_mm.x(), ideal_mm.y(), &x, &y)) {
      return std::nullopt;
    }
    return Eigen::Vector2d(x + interior_.principal_point_x_mm, y + interior_.principal_point_y_mm);
  });
}

std::optional<Eigen::Vector2d> CameraModel::ProjectDirection(
    const Eigen::Matrix3d& image_from_object, const Eigen::Vector3d& direction_in_object) const {
  const Eigen::Vector3d u = image_from_object * direction_in_object;
  if (!(u.z() > 0.0)) return std::nullopt;
  const double c = interior_.principal_distance_mm;
  return MeasuredFromIdeal(Eigen::Vector2d(c * u.x() / u.z(), c * u.y() / u.z()));
}

std::optional<Eigen::Vector3d> CameraModel::DirectionFromImage(
    const Eigen::Matrix3d& image_from_object, const Eigen::Vector2d& point_mm) const {
  const std::optional<Eigen::Vector2d> ideal = IdealFromMeasured(point_mm);
  if (!ideal) return std::nullopt;
  const Eigen::Vector3d in_image(ideal->x(), ideal->y(), interior_.principal_distance_mm);
  return (image_from_object.transpose() * in_image).normalized();
}

}  // namespace platemeter
