#pragma once
// A lens as an estimate (values and covariance), the one form every lens model
// of seeds 000 and 004 shares, and the conversions between the models: exact
// where the seeds allow, a least-squares fit of the field over the format (with
// the fit's RMS and maximum residual) otherwise. distortion_profile.h builds
// the profiles of seed 000 (eqs. 14-16) on the same form.
//
// THE COMMON FORM. brown-conrady, brown-affine, brown-balanced (seed 000) and
// smac-radial-decentering (seed 004) are all correction fields (kCorrection:
// ideal = measured + Apply(measured), and the ideal point is c times the central
// projection, seed 000 eq. 1). With m = (x, y) the measured point relative to
// the principal point and r = |m|, each is
//   ideal = m (1 + a0 + a1 r^2 + a2 r^4 + a3 r^6) + B(p1, p2; m) + r^2 B(p3, p4; m)
//           + (b1 x + b2 y, 0),
//   B(p, q; m) = (p (r^2 + 2 x^2) + 2 q x y,  2 p x y + q (r^2 + 2 y^2)),
// with
//   brown-conrady:   a1, a2, a3 = k1, k2, k3;  p1, p2;  a0 = 0
//   brown-affine:    brown-conrady plus b1, b2
//   brown-balanced:  a0, a1, a2 = k0', k1', k2';  p1, p2;  its c is c'
//   smac-radial-decentering: a1, a2, a3 = K1, K2, K3, and the decentering
//     -(J1 r^2 + J2 r^4) [(1 + 2x^2/r^2) sin(theta0) - 2xy/r^2 cos(theta0)] (dx) and
//     +(J1 r^2 + J2 r^4) [(1 + 2y^2/r^2) cos(theta0) - 2xy/r^2 sin(theta0)] (dy)
//     multiplied out is B(p1, p2) + r^2 B(p3, p4) with
//       p1 = -J1 sin(theta0),  p2 = J1 cos(theta0),  p3 = -J2 sin(theta0),  p4 = J2 cos(theta0).
//     Both seeds write corrections added to the measured coordinates, so K = k
//     with no change of sign (model_conversion_test checks this through both
//     models' Apply). Back: J1 = sqrt(p1^2 + p2^2), theta0 = atan2(-p1, p2) (the
//     phase angle phi0 of seed 000 eq. 16), J2 = (p3, p4) . (-sin theta0, cos theta0);
//     exact when (p3, p4) is parallel to (p1, p2), which it is for any smac lens.
//
// THE FOCAL LENGTH (balancing). Multiplying both sides of eq. (1) by lambda > 0
// gives the same observation equations with
//   c' = lambda c,  1 + a0' = lambda (1 + a0),  ai' = lambda ai (i >= 1),
//   p' = lambda p,  b' = lambda b,
// so the lens (c', a', p', b') is the same camera, exactly. Seed 000 balances a
// Gaussian lens (a0 = 0: brown-conrady, brown-affine, smac) to zero radial
// distortion at r = R: delta_r'(R) = R (a0' + a1' R^2 + a2' R^4 + a3' R^6) = 0 gives
//   lambda = 1 / g(R),  g(R) = 1 + k1 R^2 + k2 R^4 + k3 R^6,
//   c' = c / g(R),  k0' = 1/g(R) - 1 = -(k1 R^2 + k2 R^4 + k3 R^6) / g(R),
//   ki' = ki / g(R),  p' = p / g(R),
// so that k0' = -(k1' R^2 + k2' R^4 + k3' R^6); and back (Gaussian from balanced)
//   c = c' / (1 + k0'),  ki = ki' / (1 + k0'),  p = p' / (1 + k0').
// Seed 000 Table 1 (k0' = -0.014065, k1' = 1.5614e-5, c' = 502.630) is the
// Gaussian k1 = 1.5837e-5 1/mm^2 with c = 509.80 mm.
//
// Not in the common form: orbigon-11 (seed 001's distortion form about a point
// of symmetry, in metres); FitDistortionField compares it with any model.
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

// ---------------------------------------------------------------------------
// A lens as estimated: the principal distance, the model's parameters and the
// covariance of both (from an adjustment; or diagonal from a definition's sigmas).
struct LensEstimate {
  DistortionModelId model = DistortionModelId::kNone;
  double principal_distance_mm = 0.0;  // mm; c (for brown-balanced the c' that goes with k0')
  std::vector<double> params;          // the model's parameters, order and units as distortion_models.h
  // Covariance of [principal_distance_mm, params...], (1 + n) x (1 + n), in the
  // units of ParameterNames(). Zero rows for values taken as exact.
  Eigen::MatrixXd covariance;

  // "principal_distance_mm", then the model's kParamNames.
  std::vector<std::string> ParameterNames() const;
  // Index of a name in ParameterNames(), -1 if absent.
  int IndexOf(const std::string& name) const;
  // Sizes agree, values finite, covariance symmetric with a non-negative diagonal.
  bool Check(std::string* why) const;
};

// The lens of a camera definition: values as CameraModelFromLensCalibration
// converts them, the covariance diagonal from lens.sigmas (in the same units;
// "_um" sigmas of "_mm" parameters and "_deg" of "_rad" ones are converted).
// A parameter without a sigma gets variance 0; its name is added to
// *without_sigma when given. Throws platemeter::Error(subject, reason) as
// CameraModelFromLensCalibration does.
LensEstimate LensEstimateFromCalibration(const LensCalibration& lens, const std::string& subject,
                                         std::vector<std::string>* without_sigma = nullptr);

// Sets the covariance of parameters a and b (names as ParameterNames()) to
// rho sigma_a sigma_b. Throws platemeter::Error for an unknown name, a == b or
// |rho| > 1.
void SetCorrelation(LensEstimate* lens, const std::string& a, const std::string& b, double rho);

// First-order propagation: sqrt(g' C g) for a gradient over ParameterNames().
double PropagatedSigma(const Eigen::MatrixXd& covariance, const Eigen::VectorXd& gradient);

// ---------------------------------------------------------------------------
// The common form (header comment), templated for automatic differentiation.
template <typename T>
struct GeneralLens {
  T c_mm = T(0.0);                                 // mm; the focal length the field goes with
  std::array<T, 4> a = {T(0.0), T(0.0), T(0.0), T(0.0)};  // a0 [-], a1 [1/mm^2], a2 [1/mm^4], a3 [1/mm^6]
  std::array<T, 4> p = {T(0.0), T(0.0), T(0.0), T(0.0)};  // p1, p2 [1/mm]; p3, p4 [1/mm^3]
  std::array<T, 2> b = {T(0.0), T(0.0)};                   // b1, b2 [-]
};

// True for the models the common form holds (all but orbigon-11).
bool HasGeneralLensForm(DistortionModelId id);

// The common form of a model's parameters; false for orbigon-11.
template <typename T>
bool GeneralLensFromModel(DistortionModelId id, const T& c_mm, const T* params, GeneralLens<T>* lens) {
  using std::cos;
  using std::sin;
  GeneralLens<T> g;
  g.c_mm = c_mm;
  switch (id) {
    case DistortionModelId::kNone:
      break;
    case DistortionModelId::kBrownConrady:
    case DistortionModelId::kBrownAffine:
      g.a[1] = params[0];
      g.a[2] = params[1];
      g.a[3] = params[2];
      g.p[0] = params[3];
      g.p[1] = params[4];
      if (id == DistortionModelId::kBrownAffine) {
        g.b[0] = params[5];
        g.b[1] = params[6];
      }
      break;
    case DistortionModelId::kBrownBalanced:
      g.a[0] = params[0];
      g.a[1] = params[1];
      g.a[2] = params[2];
      g.p[0] = params[3];
      g.p[1] = params[4];
      break;
    case DistortionModelId::kSmacRadialDecentering: {
      g.a[1] = params[0];
      g.a[2] = params[1];
      g.a[3] = params[2];
      const T s = sin(params[5]);
      const T c = cos(params[5]);
      g.p[0] = -params[3] * s;
      g.p[1] = params[3] * c;
      g.p[2] = -params[4] * s;
      g.p[3] = params[4] * c;
      break;
    }
    case DistortionModelId::kSlama:
      return false;
  }
  *lens = g;
  return true;
}

// The correction of the common form at (x, y) mm from the principal point.
template <typename T>
void ApplyGeneralLens(const GeneralLens<T>& g, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
  const T r2 = x_mm * x_mm + y_mm * y_mm;
  const T radial = g.a[0] + r2 * (g.a[1] + r2 * (g.a[2] + r2 * g.a[3]));
  const T q1 = g.p[0] + r2 * g.p[2];
  const T q2 = g.p[1] + r2 * g.p[3];
  const T two_xy = T(2.0) * x_mm * y_mm;
  *dx_mm = x_mm * radial + q1 * (r2 + T(2.0) * x_mm * x_mm) + q2 * two_xy + g.b[0] * x_mm + g.b[1] * y_mm;
  *dy_mm = y_mm * radial + q1 * two_xy + q2 * (r2 + T(2.0) * y_mm * y_mm);
}

// The same camera for the focal length lambda c (header comment).
template <typename T>
GeneralLens<T> RescaledGeneralLens(const GeneralLens<T>& g, const T& lambda) {
  GeneralLens<T> out = g;
  out.c_mm = lambda * g.c_mm;
  out.a[0] = lambda * (T(1.0) + g.a[0]) - T(1.0);
  for (int i = 1; i < 4; ++i) out.a[i] = lambda * g.a[i];
  for (int i = 0; i < 4; ++i) out.p[i] = lambda * g.p[i];
  for (int i = 0; i < 2; ++i) out.b[i] = lambda * g.b[i];
  return out;
}

// The part of the common form a model holds, as its parameters (the model's
// order; c is g.c_mm). Gaussian models (brown-conrady, brown-affine, smac) hold
// no a0: rescale by 1 / (1 + a0) first. What the model cannot hold is dropped
// (brown-balanced: a3; Brown models: p3, p4; all but brown-affine: b1, b2; smac:
// the part of (p3, p4) across (p1, p2)). orbigon-11 and none: nothing is set.
template <typename T>
void ModelFromGeneralLens(DistortionModelId id, const GeneralLens<T>& g, T* params) {
  using std::atan2;
  using std::cos;
  using std::sin;
  using std::sqrt;
  switch (id) {
    case DistortionModelId::kBrownConrady:
    case DistortionModelId::kBrownAffine:
      params[0] = g.a[1];
      params[1] = g.a[2];
      params[2] = g.a[3];
      params[3] = g.p[0];
      params[4] = g.p[1];
      if (id == DistortionModelId::kBrownAffine) {
        params[5] = g.b[0];
        params[6] = g.b[1];
      }
      break;
    case DistortionModelId::kBrownBalanced:
      params[0] = g.a[0];
      params[1] = g.a[1];
      params[2] = g.a[2];
      params[3] = g.p[0];
      params[4] = g.p[1];
      break;
    case DistortionModelId::kSmacRadialDecentering: {
      params[0] = g.a[1];
      params[1] = g.a[2];
      params[2] = g.a[3];
      using distortion_internal::ScalarPart;
      // theta0 from the r^2 term, or from the r^4 term when there is none (0 without either).
      T theta0 = T(0.0);
      if (std::hypot(ScalarPart(g.p[0]), ScalarPart(g.p[1])) > 0.0) {
        theta0 = atan2(-g.p[0], g.p[1]);
      } else if (std::hypot(ScalarPart(g.p[2]), ScalarPart(g.p[3])) > 0.0) {
        theta0 = atan2(-g.p[2], g.p[3]);
      }
      const T s = sin(theta0);
      const T c = cos(theta0);
      // J1 = (p1, p2) . (-s, c) = sqrt(p1^2 + p2^2), written so that it stays differentiable at 0.
      params[3] = -g.p[0] * s + g.p[1] * c;
      params[4] = -g.p[2] * s + g.p[3] * c;
      params[5] = theta0;
      break;
    }
    case DistortionModelId::kNone:
    case DistortionModelId::kSlama:
      break;
  }
}

// ---------------------------------------------------------------------------
// The exact formulas, for a caller with plain numbers.
// Seed 004 decentering -> Brown: p1 = -J1 sin(theta0), p2 = J1 cos(theta0).
void BrownDecenteringFromSmac(double j1_per_mm, double theta0_rad, double* p1_per_mm, double* p2_per_mm);
// Brown -> seed 004: J1 = sqrt(p1^2 + p2^2) >= 0, theta0 = atan2(-p1, p2) in (-pi, pi].
void SmacDecenteringFromBrown(double p1_per_mm, double p2_per_mm, double* j1_per_mm, double* theta0_rad);

// ---------------------------------------------------------------------------
// Where two fields are compared: a grid over the format, centred on the principal point.
struct ConversionOptions {
  double format_width_mm = 0.0;     // mm; the compared region's width (> 0; a camera's format)
  double format_height_mm = 0.0;    // mm; its height (> 0)
  int grid_points_per_side = 21;    // points per side of the comparison grid (>= 3)
  double exact_tolerance_mm = 1e-12;  // mm; a conversion whose field differs less is exact (no fit)
  // Target brown-balanced only: balance to zero radial distortion at this
  // radius (mm, > 0); NaN keeps the focal length (a Gaussian source gives k0' = 0).
  double balance_radius_mm = std::numeric_limits<double>::quiet_NaN();
  bool Check(std::string* why) const;
};

struct LensConversion {
  LensEstimate lens;               // the target model, covariance propagated to first order
  bool exact = false;              // the target holds the source exactly (field within exact_tolerance_mm)
  double rms_residual_mm = 0.0;    // mm; RMS over the grid of |field(target) - field(source)|, both for lens.principal_distance_mm
  double max_residual_mm = 0.0;    // mm; the largest of them
  int num_points = 0;              // grid points compared
  std::string summary;             // one sentence
};

// The lens in another model of the common form. Exact (closed form, the
// covariance through the Jacobian) where the target holds the source; else
// the target's parameters fitted by least squares to the source's field over
// the format (the focal length fixed at the exact part's), with the covariance
// propagated through the fit's normal equations, and the fit's RMS and maximum
// residual reported. A term the target does not hold (brown-balanced: k3) takes
// its uncertainty with it even when its value is 0: the target's covariance
// then describes less than the source's. Throws platemeter::Error("lens conversion", why) for bad
// options or a model outside the common form (orbigon-11: FitDistortionField).
LensConversion ConvertLens(const LensEstimate& from, DistortionModelId to, const ConversionOptions& options);

// ---------------------------------------------------------------------------
// The generic fit: the parameters of model `to` whose field best matches model
// `from`'s over the format, both for the same focal length and principal point.
// The fields are compared as ideal coordinates of the same measured grid points
// (IdealFromMeasured), so models of either direction (kCorrection, kDistortion)
// compare correctly.
struct FieldFit {
  std::vector<double> params;     // model `to`'s parameters
  double rms_residual_mm = 0.0;   // mm; RMS over the grid of |ideal(to) - ideal(from)|
  double max_residual_mm = 0.0;   // mm; the largest
  int num_points = 0;
  bool converged = false;         // the solver converged (and every inverse did)
  std::string summary;
};
// initial_params: a start for `to` (empty: zeros; a phase angle starts at 0).
// Throws platemeter::Error("field fit", why) for bad options or sizes.
FieldFit FitDistortionField(DistortionModelId from, const std::vector<double>& from_params, DistortionModelId to,
                            const std::vector<double>& initial_params, const ConversionOptions& options);

}  // namespace platemeter
