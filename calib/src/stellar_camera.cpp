// The 11 stellar camera values from and to camera models (stellar_plate.h).
#include <cmath>

#include <fmt/format.h>

#include "platemeter/calib/stellar_plate.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// yp, ys and Phi_T change sign between the plate frame and seed 001's
// printed left-handed frame (y down): the decentering term's
// (3 dx^2 + dy^2) cos(Phi) + 2 dx dy sin(Phi) keeps its form under y -> -y
// only with Phi -> -Phi.
StellarCamera MirrorY(StellarCamera values) {
  values[2] = -values[2];
  values[4] = -values[4];
  values[10] = -values[10];
  return values;
}

}  // namespace

StellarCamera StellarCameraFromModel(const CameraModel& model, bool printed_left_handed) {
  if (model.model() != DistortionModelId::kSlama)
    throw Error("stellar camera", "the lens model must be orbigon-11 (seed 001's 11 parameters)");
  StellarCamera values{};
  values[0] = model.interior().principal_distance_mm;
  values[1] = model.interior().principal_point_x_mm;
  values[2] = model.interior().principal_point_y_mm;
  for (int i = 0; i < SlamaDistortion::kNumParams; ++i) values[3 + i] = model.params()[i];
  return printed_left_handed ? MirrorY(values) : values;
}

void CanonicalDecentering(StellarCamera* camera, Eigen::MatrixXd* matrix) {
  constexpr int kK4 = 8, kK5 = 9, kPhi = 10;
  if ((*camera)[kK4] < 0.0) {
    (*camera)[kK4] = -(*camera)[kK4];
    (*camera)[kK5] = -(*camera)[kK5];
    (*camera)[kPhi] += M_PI;
    if (matrix != nullptr && matrix->size() > 0) {
      for (int k : {kK4, kK5}) {
        matrix->row(k) *= -1.0;
        matrix->col(k) *= -1.0;
      }
    }
  }
  (*camera)[kPhi] = std::remainder((*camera)[kPhi], 2 * M_PI);
  if ((*camera)[kPhi] >= M_PI) (*camera)[kPhi] -= 2 * M_PI;
}

StellarCamera StellarCameraToPrinted(const StellarCamera& plate_frame) { return MirrorY(plate_frame); }

StellarCamera NominalStellarCamera(double principal_distance_mm) {
  StellarCamera values{};
  values[0] = principal_distance_mm;
  return values;
}

}  // namespace platemeter
