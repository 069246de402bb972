// The stellar camera values from and to camera models, and the lens models'
// names and sign freedom (stellar_plate.h, stellar_lens.h).
#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "platemeter/calib/stellar_plate.h"
#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter {
namespace {

constexpr DistortionModelId kStellarLenses[] = {DistortionModelId::kSlama, DistortionModelId::kSmacRadialDecentering,
                                                DistortionModelId::kBrownConrady};

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

bool IsStellarLensModel(DistortionModelId lens) {
  return std::find(std::begin(kStellarLenses), std::end(kStellarLenses), lens) != std::end(kStellarLenses);
}

bool ParseStellarLensModel(const std::string& name, DistortionModelId* lens) {
  DistortionModelId id;
  if (!ParseDistortionModel(name, &id) || !IsStellarLensModel(id)) return false;
  *lens = id;
  return true;
}

std::string StellarLensModelNames() {
  std::string names;
  for (DistortionModelId id : kStellarLenses) names += (names.empty() ? "" : ", ") + std::string(DistortionModelName(id));
  return names;
}

int StellarCameraParamCount(DistortionModelId lens) {
  return VisitStellarLens(lens, [](auto model) { return 3 + decltype(model)::kNumParams; });
}

std::vector<std::string> StellarCameraParamNames(DistortionModelId lens) {
  return VisitStellarLens(lens, [](auto model) {
    std::vector<std::string> names = {"c_mm", "xp_mm", "yp_mm"};
    for (const char* name : decltype(model)::kParamNames) names.push_back(name);
    return names;
  });
}

StellarDecenteringSign StellarDecenteringSignOf(DistortionModelId lens) {
  switch (lens) {
    case DistortionModelId::kSlama: return {{8, 9}, 10};                  // K4, K5, Phi_T
    case DistortionModelId::kSmacRadialDecentering: return {{6, 7}, 8};   // J1, J2, theta0
    default: return {};                                                   // Brown's p1, p2: none
  }
}

StellarCamera StellarCameraFromModel(const CameraModel& model, bool printed_left_handed) {
  if (!IsStellarLensModel(model.model()))
    throw Error("stellar camera", fmt::format("the lens model must be one of {} (got {})", StellarLensModelNames(),
                                              DistortionModelName(model.model())));
  if (printed_left_handed && model.model() != DistortionModelId::kSlama)
    throw Error("stellar camera", "only an orbigon-11 lens has seed 001's printed left-handed frame");
  StellarCamera values = {model.interior().principal_distance_mm, model.interior().principal_point_x_mm,
                          model.interior().principal_point_y_mm};
  values.insert(values.end(), model.params().begin(), model.params().end());
  return printed_left_handed ? MirrorY(values) : values;
}

void CanonicalDecentering(StellarCamera* camera, Eigen::MatrixXd* matrix, DistortionModelId lens) {
  const StellarDecenteringSign sign = StellarDecenteringSignOf(lens);
  if (sign.angle < 0) return;
  const int angle = sign.angle;
  if ((*camera)[sign.amplitudes.front()] < 0.0) {
    for (int k : sign.amplitudes) (*camera)[k] = -(*camera)[k];
    (*camera)[angle] += M_PI;
    if (matrix != nullptr && matrix->size() > 0) {
      for (int k : sign.amplitudes) {
        matrix->row(k) *= -1.0;
        matrix->col(k) *= -1.0;
      }
    }
  }
  (*camera)[angle] = std::remainder((*camera)[angle], 2 * M_PI);
  if ((*camera)[angle] >= M_PI) (*camera)[angle] -= 2 * M_PI;
}

StellarCamera StellarCameraToPrinted(const StellarCamera& plate_frame) {
  if (plate_frame.size() != kStellarCameraParams)
    throw Error("stellar camera", "seed 001's printed frame holds orbigon-11 cameras only");
  return MirrorY(plate_frame);
}

Eigen::MatrixXd stellar_internal::InverseOverRows(const Eigen::MatrixXd& matrix, const std::vector<int>& rows) {
  Eigen::MatrixXd sub(rows.size(), rows.size());
  for (size_t a = 0; a < rows.size(); ++a) {
    for (size_t b = 0; b < rows.size(); ++b) sub(a, b) = matrix(rows[a], rows[b]);
  }
  const Eigen::MatrixXd inverse = sub.ldlt().solve(Eigen::MatrixXd::Identity(sub.rows(), sub.cols()));
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(matrix.rows(), matrix.cols());
  for (size_t a = 0; a < rows.size(); ++a) {
    for (size_t b = 0; b < rows.size(); ++b) out(rows[a], rows[b]) = inverse(a, b);
  }
  return out;
}

StellarCamera NominalStellarCamera(double principal_distance_mm, DistortionModelId lens) {
  StellarCamera values(StellarCameraParamCount(lens), 0.0);
  values[0] = principal_distance_mm;
  return values;
}

}  // namespace platemeter
