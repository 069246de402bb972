#pragma once
// The bundle's observation equations (bundle_adjustment.cpp): seed 000 eq. (1)
// and a measured distance.
#include <ceres/ceres.h>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/rotations.h"

namespace platemeter::bundle_internal {

// I + d(correction)/d(x, y) at the measured point (x_mm, y_mm), row-major, by
// central differences on the camera's values (c, xp, yp, then BrownAffine's
// seven): the slope that carries eq. (1)'s residual back to the measured plane.
inline void CorrectionSlope(const double* camera, double x_mm, double y_mm, double* j) {
  const double* p = camera + 3;
  const double xb = x_mm - camera[1];
  const double yb = y_mm - camera[2];
  const double h = 1e-3;  // mm
  double ax, ay, bx, by, cx, cy, dx, dy;
  BrownAffine::Apply(p, xb + h, yb, &ax, &ay);
  BrownAffine::Apply(p, xb - h, yb, &bx, &by);
  BrownAffine::Apply(p, xb, yb + h, &cx, &cy);
  BrownAffine::Apply(p, xb, yb - h, &dx, &dy);
  j[0] = 1.0 + (ax - bx) / (2 * h);
  j[1] = (cx - dx) / (2 * h);
  j[2] = (ay - by) / (2 * h);
  j[3] = 1.0 + (cy - dy) / (2 * h);
}

// Eq. (1) as the seed writes it: the measured point corrected by the inner
// cone (BrownAffine, correction form) minus the central projection, mm;
// carried back to the measured plane by the inverse of the correction's slope
// (I + dD/dx at the measured point), so that the measurement's covariance
// weights it: with 0.9 mm of radial correction at a 500 mm lens' corner the
// slope is 1.07, and weighting the ideal-plane residual directly would
// understate the corner's sigmas by 7 %. The slope is taken on the values
// only (a weight, as in iteratively reweighted least squares).
// Blocks: camera (c, xp, yp, k1, k2, k3, p1, p2, b1, b2), frame (X, Y, Z m,
// phi, omega, kappa rad), point (X, Y, Z m).
// The bundle adjusts with the same residual's analytic form
// (bundle_collinearity.h CollinearityCost); this automatic one is the
// reference its Jacobians are tested against.
struct CollinearityEquation {
  double x_mm = 0.0;
  double y_mm = 0.0;
  template <typename T>
  bool operator()(const T* camera, const T* frame, const T* point, T* residual_mm) const {
    T rotation[9];
    TMatrixT(frame[3], frame[4], frame[5], rotation);
    const T direction[3] = {point[0] - frame[0], point[1] - frame[1], point[2] - frame[2]};
    T ideal_plane[2];
    if (!CollinearityResidualT<BrownAffine>(camera, camera + 3, rotation, direction, T(x_mm), T(y_mm),
                                            ideal_plane)) {
      return false;
    }
    double camera_values[10];
    for (int i = 0; i < 10; ++i) camera_values[i] = distortion_internal::ScalarPart(camera[i]);
    double j[4];
    CorrectionSlope(camera_values, x_mm, y_mm, j);
    const double det = j[0] * j[3] - j[1] * j[2];
    residual_mm[0] = (j[3] * ideal_plane[0] - j[1] * ideal_plane[1]) / det;
    residual_mm[1] = (-j[2] * ideal_plane[0] + j[0] * ideal_plane[1]) / det;
    return true;
  }
  static ceres::CostFunction* Create(double x_mm, double y_mm) {
    return new ceres::AutoDiffCostFunction<CollinearityEquation, 2, 10, 6, 3>(new CollinearityEquation{x_mm, y_mm});
  }
};

// A distance between the first three parameters of two blocks (points or stations), m.
template <int kSizeA, int kSizeB>
struct DistanceEquation {
  double distance_m = 0.0;
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual_m) const {
    using std::sqrt;
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    residual_m[0] = sqrt(dx * dx + dy * dy + dz * dz) - T(distance_m);
    return true;
  }
};

inline ceres::CostFunction* CreateDistanceEquation(int size_a, int size_b, double distance_m) {
  if (size_a == 3 && size_b == 3) {
    return new ceres::AutoDiffCostFunction<DistanceEquation<3, 3>, 1, 3, 3>(new DistanceEquation<3, 3>{distance_m});
  }
  if (size_a == 3) {
    return new ceres::AutoDiffCostFunction<DistanceEquation<3, 6>, 1, 3, 6>(new DistanceEquation<3, 6>{distance_m});
  }
  if (size_b == 3) {
    return new ceres::AutoDiffCostFunction<DistanceEquation<6, 3>, 1, 6, 3>(new DistanceEquation<6, 3>{distance_m});
  }
  return new ceres::AutoDiffCostFunction<DistanceEquation<6, 6>, 1, 6, 6>(new DistanceEquation<6, 6>{distance_m});
}

}  // namespace platemeter::bundle_internal
