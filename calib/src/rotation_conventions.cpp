#include <cmath>
#include <string>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "platemeter/calib/rotations.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

Eigen::Matrix3d FromRowMajor(const double* m) {
  Eigen::Matrix3d out;
  out << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return out;
}

}  // namespace

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m, double max_deviation) {
  const double deviation = (m.transpose() * m - Eigen::Matrix3d::Identity()).norm();
  if (!std::isfinite(deviation) || deviation > max_deviation) {
    throw Error("rotation matrix",
                fmt::format("not orthonormal (|M^T M - I| = {:.3g}, allowed {:.3g})", deviation,
                            max_deviation));
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0.0) {
    throw Error("rotation matrix", "determinant is negative (a reflection, not a rotation)");
  }
  return r;
}

Eigen::Matrix3d MatrixFromOmegaPhiKappa(const OmegaPhiKappa& angles) {
  double m[9];
  OmegaPhiKappaMatrixT(angles.omega_rad, angles.phi_rad, angles.kappa_rad, m);
  return FromRowMajor(m);
}

OmegaPhiKappa OmegaPhiKappaFromMatrix(const Eigen::Matrix3d& matrix) {
  const Eigen::Matrix3d m = NearestRotation(matrix);
  // m31 = sin(phi), m32 = -sin(omega) cos(phi), m33 = cos(omega) cos(phi),
  // m21 = -cos(phi) sin(kappa), m11 = cos(phi) cos(kappa).
  const double cos_phi = std::hypot(m(2, 1), m(2, 2));
  if (cos_phi < kGimbalLockCos) {
    throw Error("rotation matrix", "phi is +-90 deg: omega and kappa are not separable");
  }
  OmegaPhiKappa angles;
  angles.phi_rad = std::atan2(m(2, 0), cos_phi);
  angles.omega_rad = std::atan2(-m(2, 1), m(2, 2));
  angles.kappa_rad = std::atan2(-m(1, 0), m(0, 0));
  return angles;
}

Eigen::Matrix3d TMatrixFromAngles(const PhiOmegaKappaT& angles) {
  double m[9];
  TMatrixT(angles.phi_rad, angles.omega_rad, angles.kappa_rad, m);
  return FromRowMajor(m);
}

PhiOmegaKappaT AnglesFromTMatrix(const Eigen::Matrix3d& matrix) {
  const Eigen::Matrix3d t = NearestRotation(matrix);
  // T31 = -sin(phi), T32 = -sin(omega) cos(phi), T33 = cos(omega) cos(phi),
  // T21 = -cos(phi) sin(kappa), T11 = cos(phi) cos(kappa).
  const double cos_phi = std::hypot(t(2, 1), t(2, 2));
  if (cos_phi < kGimbalLockCos) {
    throw Error("rotation matrix", "phi is +-90 deg: omega and kappa are not separable");
  }
  PhiOmegaKappaT angles;
  angles.phi_rad = std::atan2(-t(2, 0), cos_phi);
  angles.omega_rad = std::atan2(-t(2, 1), t(2, 2));
  angles.kappa_rad = std::atan2(-t(1, 0), t(0, 0));
  return angles;
}

double RadiansFromDms(int sign, int degrees, int arcmin, double arcsec) {
  if (sign != 1 && sign != -1) {
    throw Error("angle", fmt::format("sign must be +1 or -1, got {}", sign));
  }
  if (degrees < 0 || arcmin < 0 || arcmin >= 60 || !(arcsec >= 0.0) || !(arcsec < 60.0)) {
    throw Error("angle", fmt::format("{} deg {}' {}\" is not a sexagesimal angle", degrees,
                                     arcmin, arcsec));
  }
  const double deg = degrees + arcmin / 60.0 + arcsec / 3600.0;
  return sign * deg * M_PI / 180.0;
}

double ArcsecFromRadians(double angle_rad) { return angle_rad * 180.0 / M_PI * 3600.0; }

}  // namespace platemeter
