#pragma once
// The bundle's observation equations (bundle_adjustment.cpp): seed 000 eq. (1)
// and a measured distance.
#include <ceres/ceres.h>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/rotations.h"

namespace platemeter::bundle_internal {

// Eq. (1) as the seed writes it: the measured point corrected by the inner
// cone (BrownAffine, correction form) minus the central projection, mm.
// Blocks: camera (c, xp, yp, k1, k2, k3, p1, p2, b1, b2), frame (X, Y, Z m,
// phi, omega, kappa rad), point (X, Y, Z m).
struct CollinearityEquation {
  double x_mm = 0.0;
  double y_mm = 0.0;
  template <typename T>
  bool operator()(const T* camera, const T* frame, const T* point, T* residual_mm) const {
    T rotation[9];
    TMatrixT(frame[3], frame[4], frame[5], rotation);
    const T direction[3] = {point[0] - frame[0], point[1] - frame[1], point[2] - frame[2]};
    return CollinearityResidualT<BrownAffine>(camera, camera + 3, rotation, direction, T(x_mm), T(y_mm),
                                              residual_mm);
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
