// StationCovarianceFromTrack (bundle_input.h): Gyer (1970) as seed 000
// section 3.3 describes it -- positional standard deviations "in terms of
// in-track, cross-track and radial components" turned into "a full covariance
// matrix in the moon-centered system".
//
// The triad, in the object frame (origin at the body's centre):
//   e_radial   = position / |position|                      (away from the centre)
//   e_in_track = velocity minus its radial part, normalized  (along the track)
//   e_cross    = e_radial x e_in_track                      (so that
//                e_in_track x e_cross = e_radial: in-track, cross-track, radial
//                is right-handed)
// and with R = [e_in_track e_cross e_radial] (columns),
//   C = R diag(s_in^2, s_cross^2, s_radial^2) R^T.
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/core/error.h"

namespace platemeter {

Eigen::Matrix3d StationCovarianceFromTrack(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity,
                                           double sigma_in_track_m, double sigma_cross_track_m,
                                           double sigma_radial_m) {
  const char* subject = "station covariance";
  if (!position_m.allFinite() || !velocity.allFinite()) {
    throw Error(subject, "the position and the velocity must be finite");
  }
  for (double sigma : {sigma_in_track_m, sigma_cross_track_m, sigma_radial_m}) {
    if (!(sigma > 0.0) || !std::isfinite(sigma)) {
      throw Error(subject, "the in-track, cross-track and radial sigmas must be positive (m)");
    }
  }
  const double distance = position_m.norm();
  if (!(distance > 0.0)) {
    throw Error(subject, "the station is at the object frame's origin (the body's centre): no radial direction");
  }
  const Eigen::Vector3d radial = position_m / distance;
  const Eigen::Vector3d along = velocity - velocity.dot(radial) * radial;
  // The velocity must have a part across the radial: a purely radial (or zero)
  // velocity gives no track direction.
  if (!(along.norm() > 1e-9 * velocity.norm()) || !(velocity.norm() > 0.0)) {
    throw Error(subject, "the velocity is zero or radial: no in-track direction");
  }
  Eigen::Matrix3d rotation;
  rotation.col(0) = along.normalized();
  rotation.col(2) = radial;
  rotation.col(1) = radial.cross(rotation.col(0));
  const Eigen::Vector3d variances(sigma_in_track_m * sigma_in_track_m, sigma_cross_track_m * sigma_cross_track_m,
                                  sigma_radial_m * sigma_radial_m);
  Eigen::Matrix3d covariance = rotation * variances.asDiagonal() * rotation.transpose();
  return 0.5 * (covariance + covariance.transpose());  // exactly symmetric
}

}  // namespace platemeter
