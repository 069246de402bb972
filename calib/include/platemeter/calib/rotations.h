#pragma once
// Rotation conventions of the seeds, each kept as its seed prints it
// (DESIGN.md: "Rotations follow the seed they come from and say so").
//
// Seed 004 (SN-004 interlock, Table A.6): omega, phi, kappa applied in sequence
// to the axes: omega about x (positive turns +y toward +z), then phi about y'
// (positive turns +z' toward +x'), then kappa about z'' (positive turns +x''
// toward +y''). Rotating the AXES, the matrix that gives a fixed vector's
// coordinates in the final frame is
//   M = R3(kappa) R2(phi) R1(omega),
//   R1(w) = [1 0 0; 0 cw sw; 0 -sw cw], R2(p) = [cp 0 -sp; 0 1 0; sp 0 cp],
//   R3(k) = [ck sk 0; -sk ck 0; 0 0 1],
// i.e. m31 = sin(phi), m32 = -sin(omega) cos(phi), m33 = cos(omega) cos(phi),
// m21 = -cos(phi) sin(kappa), m11 = cos(phi) cos(kappa). Table A.6's matrix
// (terrain -> stellar) follows it: m31 = -0.00027269 = sin(-56.246").
//
// Seed 000 (eq. 1): T(phi, omega, kappa) as printed:
//   [ cp ck,   cw sk - sw sp ck,   sw sk + cw sp ck ]
//   [ -cp sk,  cw ck + sw sp sk,   sw ck - cw sp sk ]
//   [ -sp,     -sw cp,             cw cp            ]
// The OCR'd seed prints the (2,3) element as "sw sk - cw sp sk"; that breaks
// orthogonality, and the rest of the matrix fixes it as sw ck - cw sp sk. This T
// is R3(kappa) R2(-phi) R1(omega): seed 000's phi has the opposite sense of seed
// 004's, T000(phi, omega, kappa) = M004(omega, -phi, kappa).
//
// Both matrices map object-frame coordinates to image-frame coordinates
// (image_from_object); the collinearity equations use their rows.
#include <cmath>

#include <Eigen/Core>

namespace platemeter {

// Seed 004's angles, radians.
struct OmegaPhiKappa {
  double omega_rad = 0.0;
  double phi_rad = 0.0;
  double kappa_rad = 0.0;
};

// Seed 000's angles, radians.
struct PhiOmegaKappaT {
  double phi_rad = 0.0;
  double omega_rad = 0.0;
  double kappa_rad = 0.0;
};

// Below this cos(phi) the first and third rotations are not separable (gimbal lock).
inline constexpr double kGimbalLockCos = 1e-9;

Eigen::Matrix3d MatrixFromOmegaPhiKappa(const OmegaPhiKappa& angles);
// Angles of the nearest rotation to `m` (the printed matrices are orthogonal only
// to their 8 digits): phi in [-pi/2, pi/2], omega and kappa in (-pi, pi].
// Throws platemeter::Error if `m` is not within 1e-4 of a proper rotation, or
// if cos(phi) is too small for omega and kappa to be separable (gimbal lock).
OmegaPhiKappa OmegaPhiKappaFromMatrix(const Eigen::Matrix3d& m);

Eigen::Matrix3d TMatrixFromAngles(const PhiOmegaKappaT& angles);
PhiOmegaKappaT AnglesFromTMatrix(const Eigen::Matrix3d& t);

// The nearest proper rotation (SVD); throws platemeter::Error if `m` is further
// than `max_deviation` (Frobenius norm of M^T M - I) from one or has det < 0.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m, double max_deviation = 1e-4);

// Radians from a sexagesimal angle as the seeds print it, e.g. -96 deg 00' 06.276":
// RadiansFromDms(-1, 96, 0, 6.276). sign is -1 or +1 (needed for "-0 deg 00' 56").
double RadiansFromDms(int sign, int degrees, int arcmin, double arcsec);
double ArcsecFromRadians(double angle_rad);

// Templated forms for automatic differentiation; m is row-major 3x3.
template <typename T>
void OmegaPhiKappaMatrixT(const T& omega, const T& phi, const T& kappa, T* m) {
  using std::cos;
  using std::sin;
  const T cw = cos(omega), sw = sin(omega);
  const T cp = cos(phi), sp = sin(phi);
  const T ck = cos(kappa), sk = sin(kappa);
  m[0] = cp * ck;
  m[1] = cw * sk + sw * sp * ck;
  m[2] = sw * sk - cw * sp * ck;
  m[3] = -cp * sk;
  m[4] = cw * ck - sw * sp * sk;
  m[5] = sw * ck + cw * sp * sk;
  m[6] = sp;
  m[7] = -sw * cp;
  m[8] = cw * cp;
}

template <typename T>
void TMatrixT(const T& phi, const T& omega, const T& kappa, T* m) {
  using std::cos;
  using std::sin;
  const T cw = cos(omega), sw = sin(omega);
  const T cp = cos(phi), sp = sin(phi);
  const T ck = cos(kappa), sk = sin(kappa);
  m[0] = cp * ck;
  m[1] = cw * sk - sw * sp * ck;
  m[2] = sw * sk + cw * sp * ck;
  m[3] = -cp * sk;
  m[4] = cw * ck + sw * sp * sk;
  m[5] = sw * ck - cw * sp * sk;  // printed "sw sk - cw sp sk": OCR slip, see above
  m[6] = -sp;
  m[7] = -sw * cp;
  m[8] = cw * cp;
}

}  // namespace platemeter
