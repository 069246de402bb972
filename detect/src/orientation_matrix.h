#pragma once
// The scan orientation as a 2x2 matrix taking plate axes onto pixel axes (grid assignment, fiducials).
#include <array>

#include <Eigen/Core>

#include "platemeter/core/scan_orientation.h"

namespace platemeter::detect_internal {

inline Eigen::Matrix2d OrientationMatrix(const ScanOrientation& orientation) {
  const std::array<int, 4> m = orientation.PixelAxesFromPlate();
  Eigen::Matrix2d matrix;
  matrix << m[0], m[1], m[2], m[3];
  return matrix;
}

}  // namespace platemeter::detect_internal
