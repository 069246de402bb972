#pragma once
// The calibrated lens of a stellar calibration as seed 001's diagnostic plots
// show it (Table 4, Figs. 6-9): the distortion vector field and its radial
// symmetric and decentering components over the format, the point of symmetry
// with the axis of maximum tangential distortion, and the profile curves with
// their one-sigma envelopes -- the radial distortion at the calibrated focal
// length, the same transformed to the focal length whose positive and negative
// lobes enclose equal areas (Fig. 8), and the decentering profile.
//
// For every stellar lens model (stellar_lens.h), all in the plate frame:
//   DISTORTION is the displacement of the measured image from the true one (um).
//   orbigon-11 is a distortion model (added to the true image); the correction
//   models (smac-radial-decentering, brown-conrady) are shown as minus their
//   correction at the measured point, the same to first order.
//   RADIAL: the lens with its decentering amplitudes zeroed (K4, K5; J1, J2;
//   p1, p2); DECENTERING: the lens with its radial coefficients zeroed
//   (K1..K3; k1..k3). The point of symmetry is (xs, ys) for orbigon-11, the
//   principal point otherwise.
//   PROFILES along d, the distance from the point of symmetry:
//     radial       dr(d): the radial component at distance d (orbigon-11:
//                  K1 d^3 + K2 d^5 + K3 d^7, d in metres);
//     transformed  dr(d) - k0 d with k0 = (2 / M^2) integral_0^M dr(d) dd, i.e.
//                  the focal length C' = C (1 + k0): the integral of the curve
//                  over [0, M] is zero (seed 001 Fig. 8, "the positive and
//                  negative lobes of the enclosed areas beneath the curve are
//                  equal"); M the largest distance shown (the format's corner);
//     decentering  the largest tangential component on the circle of radius d
//                  (orbigon-11: (K4 + K5 d^2) d^2; Brown: sqrt(p1^2 + p2^2) d^2,
//                  seed 000 eq. 15), with the direction where it is largest:
//                  the axis of maximum tangential distortion.
// SIGMAS: every plotted number is a function of the camera values; its sigma
// is sqrt(g' C g) with g by central differences (steps of 1e-3 of each
// parameter's sigma) and C the camera's scaled covariance, so the
// correlations (C with K1, xs with xp, ...) count.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/stellar_combination.h"
#include "platemeter/calib/stellar_plate.h"

namespace platemeter {

// A calibrated camera with its covariance: a plate's or a combination's.
struct StellarLensEstimate {
  DistortionModelId lens = DistortionModelId::kSlama;
  StellarCamera values;          // plate frame (stellar_plate.h)
  Eigen::MatrixXd covariance;    // scaled (m_o^2 Q), n x n; zero rows for fixed parameters
};
StellarLensEstimate PlateLensEstimate(const StellarPlateResult& plate, DistortionModelId lens);
StellarLensEstimate CombinationLensEstimate(const StellarCombination& combination, DistortionModelId lens);

enum class StellarLensPart { kTotal, kRadial, kDecentering };
const char* StellarLensPartName(StellarLensPart part);  // "total", "radial symmetric", "decentering"

// The distortion (um, plate frame) of `part` at the measured plate point (mm, plate frame).
Eigen::Vector2d StellarDistortion_um(const StellarLensEstimate& estimate, StellarLensPart part, double x_mm,
                                     double y_mm);

struct StellarSymmetry {
  double x_mm = 0.0, y_mm = 0.0;   // point of symmetry, plate frame (absolute, not from the principal point)
  double axis_rad = 0.0;           // direction of maximum tangential distortion, from +x toward +y, [0, pi)
  bool has_decentering = false;    // false: no decentering, the axis is undefined
};
StellarSymmetry StellarSymmetryOf(const StellarLensEstimate& estimate);

struct StellarProfileRow {
  double d_mm = 0.0;
  double radial_um = 0.0, radial_sigma_um = 0.0;
  double transformed_um = 0.0, transformed_sigma_um = 0.0;
  double decentering_um = 0.0, decentering_sigma_um = 0.0;
};
struct StellarProfile {
  double max_distance_mm = 0.0;              // M
  double k0 = 0.0;                           // the transformation's linear term (-)
  double transformed_focal_length_mm = 0.0;  // C' = C (1 + k0)
  double transformed_focal_length_sigma_mm = 0.0;
  std::vector<StellarProfileRow> rows;       // d = 0 .. M in `samples` equal steps, or the distances given
};
// Throws platemeter::Error for max_distance_mm <= 0 or samples < 2.
StellarProfile ComputeStellarProfile(const StellarLensEstimate& estimate, double max_distance_mm, int samples);
// The same at the given distances (mm, e.g. those of field angles); M = max_distance_mm.
StellarProfile ComputeStellarProfile(const StellarLensEstimate& estimate, double max_distance_mm,
                                     const std::vector<double>& distances_mm);

}  // namespace platemeter
