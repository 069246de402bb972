#pragma once
// Multi-camera interlock: the relative orientation of two cameras as seed 004's
// omega, phi, kappa, with their covariance by first-order propagation
// (docs/interlock.md). Seed 004, Table A.6 prints the terrain-to-stellar matrix
// M = R3(kappa) R2(phi) R1(omega) (the convention of rotations.h), a 3x3
// "Covariance Matrix" and the angles with their standard deviations.
//
// The maps, all exact for rotations (first order in the covariance):
//   angles(M)   = nearest rotation R = polar(M) (SVD, U V^T), then
//                 phi = atan2(r31, hypot(r32, r33)), omega = atan2(-r32, r33),
//                 kappa = atan2(-r21, r11)
//   d angles/dM = [d angles/dR]  (automatic differentiation of the atan2 forms)
//               * [dR/dM]        (derivative of the polar factor: with
//                                 M = U S V^T, X = U^T dM V,
//                                 U^T dR V = (X - X^T)_ij / (s_i + s_j)),
//                 so a perturbation that only stretches or shears M (the
//                 non-rotation part of an unconstrained 9-element estimate)
//                 moves no angle.
//   small rotations: a further rotation of the STELLAR axes by the vector d_s
//                 (same senses as omega, phi, kappa: M' = (I - [d_s]x) M), or
//                 of the TERRAIN axes before M (M' = M (I - [d_t]x)); d_s = M d_t.
//   reverse:    Cov(M elements) = J Cov(angles) J^T, J = dM/d(omega, phi, kappa)
//               (9x3, automatic differentiation of OmegaPhiKappaMatrixT); rank 3.
// Matrix elements are row-major (m11, m12, m13, m21, ..., m33) and dimensionless;
// angle and small-rotation covariances are in rad^2, in the order x, y, z
// (omega, phi, kappa).
//
// Errors (platemeter::Error, subject "interlock", one line): a matrix that is not
// within `max_orthogonality_deviation` of a proper rotation (or is a reflection),
// phi at +-90 deg (omega and kappa not separable), a covariance with non-finite
// elements, not symmetric, or not positive semi-definite.
#include <string>

#include <Eigen/Core>

#include "platemeter/calib/rotations.h"

namespace platemeter {

using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Matrix39d = Eigen::Matrix<double, 3, 9>;
using Matrix93d = Eigen::Matrix<double, 9, 3>;

// What a 3x3 covariance is the covariance of (Table A.6 prints kAngles).
enum class InterlockCovarianceKind {
  kAngles,                    // (omega, phi, kappa), rad^2
  kSmallRotationStellarAxes,  // d_s with M' = (I - [d_s]x) M, rad^2
  kSmallRotationTerrainAxes,  // d_t with M' = M (I - [d_t]x), rad^2
};
const char* InterlockCovarianceKindName(InterlockCovarianceKind kind);  // angles, stellar-axes, terrain-axes

// Where the angle VALUES come from (the covariance always goes through the
// nearest rotation, see above).
enum class InterlockAngleForm {
  kNearestRotation,  // the atan2 forms on the nearest rotation (least squares over all nine elements)
  kElementAtan2,     // the atan2 forms on the matrix as given (m11, m21, m31, m32, m33 only)
};

struct InterlockOptions {
  // kElementAtan2 reproduces Table A.6's angles digit for digit (the table's
  // matrix was rounded from its angles; docs/interlock.md); both agree to the
  // matrix's rounding for a matrix that is orthonormal to its printed digits.
  InterlockAngleForm angle_form = InterlockAngleForm::kNearestRotation;
  double max_orthogonality_deviation = 1e-4;  // unitless; largest |M^T M - I| (Frobenius) accepted
  double symmetry_tolerance = 1e-6;  // unitless; largest |C_ij - C_ji| / max_i C_ii accepted
  double psd_tolerance = 1e-9;       // unitless; most negative eigenvalue / largest eigenvalue accepted
  bool Check(std::string* why) const;
};

struct InterlockAngles {
  OmegaPhiKappa angles;              // rad; seed 004's sequence (options.angle_form)
  Eigen::Matrix3d rotation;          // the nearest proper rotation to the input matrix
  double orthogonality_deviation = 0.0;  // unitless; |M^T M - I| (Frobenius) of the input
  Eigen::Matrix3d covariance_rad2;   // of (omega, phi, kappa)
  Eigen::Matrix3d correlation;       // of (omega, phi, kappa); 0 where a sigma is 0
  double omega_sigma_arcsec = 0.0;
  double phi_sigma_arcsec = 0.0;
  double kappa_sigma_arcsec = 0.0;
  std::string summary;  // one sentence: the angles (d m s) with sigmas and where the covariance came from
};

// From the matrix and the covariance of its 9 elements (row-major, any rank;
// the part that is not a rotation is projected out, see above).
InterlockAngles InterlockAnglesFromMatrix(const Eigen::Matrix3d& matrix,
                                          const Matrix9d& element_covariance,
                                          const InterlockOptions& options = {});

// From the matrix and a 3x3 covariance of the angles or of a small rotation
// vector (`kind`); Table A.6 is InterlockCovarianceKind::kAngles.
InterlockAngles InterlockAnglesFromRotationCovariance(const Eigen::Matrix3d& matrix,
                                                      const Eigen::Matrix3d& covariance_rad2,
                                                      InterlockCovarianceKind kind,
                                                      const InterlockOptions& options = {});

// d(omega, phi, kappa) / d(m11 .. m33) at `matrix`, through the nearest rotation.
// Throws as OmegaPhiKappaFromMatrix does.
Matrix39d AnglesFromMatrixJacobian(const Eigen::Matrix3d& matrix,
                                   double max_orthogonality_deviation = 1e-4);

// d(omega, phi, kappa) / d(small rotation of `kind`) at `angles` (identity for kAngles).
Eigen::Matrix3d AnglesFromSmallRotationJacobian(const OmegaPhiKappa& angles,
                                                InterlockCovarianceKind kind);

// Reverse: d(m11 .. m33) / d(omega, phi, kappa), and the (rank-3) covariance
// of the 9 elements from the covariance of the angles (rad^2).
Matrix93d MatrixFromAnglesJacobian(const OmegaPhiKappa& angles);
Matrix9d MatrixCovarianceFromAngleCovariance(const OmegaPhiKappa& angles,
                                             const Eigen::Matrix3d& angle_covariance_rad2,
                                             const InterlockOptions& options = {});

// Reverse for small rotations: the covariance of the small rotation of `kind`
// from the covariance of the angles (rad^2).
Eigen::Matrix3d SmallRotationCovarianceFromAngleCovariance(
    const OmegaPhiKappa& angles, const Eigen::Matrix3d& angle_covariance_rad2,
    InterlockCovarianceKind kind, const InterlockOptions& options = {});

// "-96 00'06.276\"": sign, degrees, minutes, seconds with `decimals` digits.
std::string DmsFromRadians(double angle_rad, int decimals = 3);

}  // namespace platemeter
