#pragma once
// The distortion products of seed 000 (section 3.2-3.4) with propagated sigmas:
// the balanced symmetric radial distortion (eq. 14) and its calibrated focal
// length c', the decentering profile (eq. 15) and the decentering phase angle
// (eq. 16), for any lens of the common form (model_conversion.h:
// brown-conrady, brown-affine, brown-balanced, smac-radial-decentering).
//
// THE FORMULAS, on the common form (a0..a3, p1..p4, c) after balancing by
// lambda (model_conversion.h: c' = lambda c, 1 + a0' = lambda (1 + a0),
// ai' = lambda ai, p' = lambda p):
//   radial      delta_r'(r) = a0' r + a1' r^3 + a2' r^5 + a3' r^7        (eq. 14; k0', k1', ...)
//   decentering P(r) = |(p1' + p3' r^2, p2' + p4' r^2)| r^2              (eq. 15; seed 004: |J1 + J2 r^2| r^2)
//   phase       phi0 = atan2(-p1', p2'), in (-180, 180] deg               (eq. 16, the quadrant Table 8 prints)
// delta_r' has the sign of the models' Apply: the radial correction added to the
// measured coordinates (seeds 000 and 004 print their coefficients so; the
// values of Tables 2, 4, 7 are this function of the printed coefficients).
// The affinity b1, b2 of brown-affine belongs to the image frame, not to the
// lens: it is in neither profile.
//
// THE BALANCE (lambda):
//   kAsGiven        lambda = 1: the lens as its parameters have it (Gaussian
//                   models: k0' = 0, c' = c; brown-balanced: the published k0', c').
//   kZeroAtRadius   lambda = 1 / g(R), g(r) = 1 + a0 + a1 r^2 + a2 r^4 + a3 r^6:
//                   delta_r'(R) = 0 (seed 000 balances at R = 30 mm).
//   kEqualLobePeaks lambda with max delta_r' = -min delta_r' over [0, M]: the
//                   minimax function (the least largest |delta_r'| over [0, M]).
//   kEqualLobeAreas lambda with the integral of delta_r' over [0, M] zero:
//                   lambda = (M^2 / 2) / integral_0^M r g(r) dr (seed 001 Fig. 8:
//                   "the positive and negative lobes of the enclosed areas
//                   beneath the curve are equal").
//
// THE SIGMAS. Every product is a function of the vector [c, params...] of the
// LensEstimate; its sigma is sqrt(grad' C grad) with the gradient by automatic
// differentiation (ceres::Jet) through the balancing, so correlations of the
// full covariance (from an adjustment) count, c included. For the minimax
// balance the extremal radii are held fixed (the envelope theorem: the
// derivative of delta_r' in r is zero there, or r is the end M). Consequences:
//   - c enters c' only: balancing makes the radial function independent of the
//     scale. With a balance, delta_r'(R) = 0 whatever the parameters, so its
//     sigma is exactly 0 at R.
//   - kAsGiven evaluates eq. (14) with the coefficients and covariance as they
//     are. That is how seed 000 computed Tables 2, 4 and 7: it treats k0' as a
//     parameter of its own with sigma(k0') ~ |k0'| sigma(c') / c' (Tables 1, 3
//     and 6 all show this ratio, to 2 %), so its tables' sigma at 30 mm is 5 um, not 0.
//     Rebalancing such a lens (kZeroAtRadius) is exact and drops the k0' term.
//   - where P(r) = 0 (p1' + p3' r^2 = p2' + p4' r^2 = 0) the first-order sigma of
//     a length is undefined; the largest standard deviation over directions,
//     r^2 sqrt(largest eigenvalue of the 2 x 2 covariance), is reported, and the
//     phase angle (undefined) is NaN.
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "platemeter/calib/model_conversion.h"

namespace platemeter {

enum class RadialBalance { kAsGiven, kZeroAtRadius, kEqualLobePeaks, kEqualLobeAreas };
const char* RadialBalanceName(RadialBalance balance);  // "as-given", "zero-at-radius", "equal-lobe-peaks", "equal-lobe-areas"

struct DistortionProfileOptions {
  RadialBalance balance = RadialBalance::kAsGiven;
  double balance_radius_mm = 30.0;  // mm; kZeroAtRadius: delta_r' is zero here (> 0; seed 000: 30 mm)
  double max_radius_mm = 0.0;       // mm; equal lobes: the range [0, M] (> 0; the format's half diagonal)
  std::vector<double> radii_mm = {0, 5, 10, 15, 20, 25, 30, 35, 39};  // mm; the table's rows (>= 0, finite)
  bool Check(std::string* why) const;
};

struct ValueWithSigma {
  double value = 0.0;
  double sigma = 0.0;
};

struct DistortionProfileRow {
  double r_mm = 0.0;
  double radial_um = 0.0;              // um; delta_r'(r), eq. (14)
  double radial_sigma_um = 0.0;        // um
  double decentering_um = 0.0;         // um; P(r), eq. (15)
  double decentering_sigma_um = 0.0;   // um
};

struct DistortionProfile {
  DistortionModelId model = DistortionModelId::kNone;
  RadialBalance balance = RadialBalance::kAsGiven;
  double balance_radius_mm = std::numeric_limits<double>::quiet_NaN();  // kZeroAtRadius: R
  double max_radius_mm = std::numeric_limits<double>::quiet_NaN();      // equal lobes: M
  double scale = 1.0;                                  // lambda = c' / c
  ValueWithSigma calibrated_focal_length_mm;           // c'
  // delta_r' = k0' r + k1' r^3 + k2' r^5 + k3' r^7: k0' [-], k1' [1/mm^2], k2' [1/mm^4], k3' [1/mm^6]
  std::array<ValueWithSigma, 4> radial_coefficients;
  ValueWithSigma decentering_j1_per_mm;                // sqrt(p1'^2 + p2'^2) (seed 004's J1)
  ValueWithSigma decentering_j2_per_mm3;               // the r^4 term along phi0 (seed 004's J2; 0 for Brown)
  ValueWithSigma phase_angle_rad;                      // phi0, eq. (16); NaN if p1' = p2' = 0
  std::vector<DistortionProfileRow> rows;              // one per options.radii_mm
  std::vector<std::string> parameter_names;            // of the covariance used (LensEstimate::ParameterNames)
  std::string summary;                                 // one sentence
};

// Throws platemeter::Error("distortion profile", why) for bad options, a lens
// that fails LensEstimate::Check, a model outside the common form (orbigon-11),
// or a radial function that turns the scale over (g(r) <= 0) on [0, M].
DistortionProfile ComputeDistortionProfile(const LensEstimate& lens, const DistortionProfileOptions& options);

// The format's half diagonal (mm): the default range of the equal lobes and of
// the default table radii.
double FormatHalfDiagonal_mm(double format_width_mm, double format_height_mm);
// Table radii for a format: 0 to the half diagonal in steps of 1, 2, 5, 10, 20 or
// 50 mm (the smallest giving at most 10 steps), then the half diagonal itself
// (the format's corner).
std::vector<double> DefaultProfileRadii_mm(double format_width_mm, double format_height_mm);

}  // namespace platemeter
