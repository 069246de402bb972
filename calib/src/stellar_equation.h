#pragma once
// Inside the stellar calibration (stellar_plate.h): one image's observation
// equation for every lens model of stellar_lens.h, and its cost functions.
#include <Eigen/Core>
#include <ceres/ceres.h>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/calib/stellar_lens.h"

namespace platemeter::stellar_internal {

// A star's apparent direction at one image's mid-time in the site's local
// frame, and its derivatives with respect to the star's catalog place moved
// east and north by an arc (radians): direction(e, n) ~ enu + e d_east + n d_north.
struct ImageDirection {
  Eigen::Vector3d enu = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d d_east = Eigen::Vector3d::Zero();
  Eigen::Vector3d d_north = Eigen::Vector3d::Zero();
};

// One image: its measured position, the starting rotation of its orientation
// set and its star's direction. Residual<Lens> is the image equation, model
// minus measured, mm. Blocks: camera (3 + Lens::kNumParams: c_mm, xp_mm,
// yp_mm, the lens), r the camera's rotation after m0 (row-major; seed 004's
// omega, phi, kappa of the orientation set), deformation (s, epsilon_rad),
// star correction (east_rad, north_rad).
struct StellarImageEquation {
  double x_mm = 0.0, y_mm = 0.0;
  Eigen::Matrix3d m0 = Eigen::Matrix3d::Identity();  // camera_from_enu the set starts from
  ImageDirection direction;

  template <typename Lens, typename T>
  bool Residual(const T* camera, const T* r, const T* deformation, const T* star, T* residual_mm) const {
    T d[3];
    for (int i = 0; i < 3; ++i) {
      d[i] = T(direction.enu[i]) + T(direction.d_east[i]) * star[0] + T(direction.d_north[i]) * star[1];
    }
    T v[3];
    for (int i = 0; i < 3; ++i) v[i] = T(m0(i, 0)) * d[0] + T(m0(i, 1)) * d[1] + T(m0(i, 2)) * d[2];
    const T m = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    const T n = r[3] * v[0] + r[4] * v[1] + r[5] * v[2];
    const T q = r[6] * v[0] + r[7] * v[1] + r[8] * v[2];
    if (!(q > T(0.0))) return false;
    const T cx = camera[0] * (T(1.0) + deformation[0]);
    const T cy = camera[0] * (T(1.0) - deformation[0]);
    const T xb = cx * m / q;  // true image relative to the principal point
    const T yb = cy * n / q;
    if constexpr (Lens::kDirection == DistortionDirection::kDistortion) {
      // Seed 001: measured = ideal + Apply(ideal), the plate's shear after it
      // (SlamaImageEquation); the residual is in the measured space.
      T ex, ey;
      Lens::Apply(camera + 3, xb, yb, &ex, &ey);
      residual_mm[0] = xb + camera[1] + ex - (yb + camera[2]) * deformation[1] - T(x_mm);
      residual_mm[1] = yb + camera[2] + ey - T(y_mm);
    } else {
      // Seeds 000, 004: ideal = measured + Apply(measured), compared with the
      // central projection and the plate's shear as above; the residual is in
      // the ideal space. The image covariance is taken as is: the correction's
      // derivative is ~1e-4 to 1e-3 over the format (seed 004's terrain lens:
      // at most 3e-3 within 57 mm, 1.5e-2 in the very corners), so the
      // propagated covariance would differ by about twice that, relative; a
      // weight off by that little costs no bias and next to no precision.
      const T mx = T(x_mm) - camera[1];
      const T my = T(y_mm) - camera[2];
      T dx, dy;
      Lens::Apply(camera + 3, mx, my, &dx, &dy);
      residual_mm[0] = xb - (yb + camera[2]) * deformation[1] - (mx + dx);
      residual_mm[1] = yb - (my + dy);
    }
    return true;
  }
};

// The image of a plate adjusted on its own. Blocks: camera, orientation set
// (omega, phi, kappa rad: a small rotation after the set's m0), deformation, star.
template <typename Lens>
struct StellarImageCost {
  StellarImageEquation image;

  template <typename T>
  bool operator()(const T* camera, const T* orientation, const T* deformation, const T* star, T* residual_mm) const {
    T r[9];
    OmegaPhiKappaMatrixT(orientation[0], orientation[1], orientation[2], r);
    return image.Residual<Lens>(camera, r, deformation, star, residual_mm);
  }
};

// An image of a camera interlocked with the reference camera of its exposure
// (stellar_interlock.h): m0 and the orientation set are the reference plate's,
// and the interlock's rotation M = R3(kappa) R2(phi) R1(omega) follows them.
// Blocks: camera, reference orientation set, interlock (omega, phi, kappa
// rad), deformation, star.
template <typename Lens>
struct InterlockedImageCost {
  StellarImageEquation image;

  template <typename T>
  bool operator()(const T* camera, const T* orientation, const T* interlock, const T* deformation, const T* star,
                  T* residual_mm) const {
    T a[9], b[9], r[9];
    OmegaPhiKappaMatrixT(interlock[0], interlock[1], interlock[2], a);
    OmegaPhiKappaMatrixT(orientation[0], orientation[1], orientation[2], b);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    }
    return image.Residual<Lens>(camera, r, deformation, star, residual_mm);
  }
};

// The cost functions with the lens model's camera block size.
inline ceres::CostFunction* CreateStellarImageCost(DistortionModelId lens, const StellarImageEquation& image) {
  return VisitStellarLens(lens, [&](auto model) -> ceres::CostFunction* {
    using Lens = decltype(model);
    return new ceres::AutoDiffCostFunction<StellarImageCost<Lens>, 2, 3 + Lens::kNumParams, 3, 2, 2>(
        new StellarImageCost<Lens>{image});
  });
}
inline ceres::CostFunction* CreateInterlockedImageCost(DistortionModelId lens, const StellarImageEquation& image) {
  return VisitStellarLens(lens, [&](auto model) -> ceres::CostFunction* {
    using Lens = decltype(model);
    return new ceres::AutoDiffCostFunction<InterlockedImageCost<Lens>, 2, 3 + Lens::kNumParams, 3, 3, 2, 2>(
        new InterlockedImageCost<Lens>{image});
  });
}

}  // namespace platemeter::stellar_internal
