// Interlock angles with their covariance (interlock.h, docs/interlock.md).
#include "platemeter/calib/interlock.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <ceres/jet.h>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

constexpr const char* kInterlockSubject = "interlock";

void CheckOptionsOrThrow(const InterlockOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("interlock options", why);
}

// Finite, symmetric and positive semi-definite within the options' tolerances.
template <int N>
void CheckCovarianceOrThrow(const Eigen::Matrix<double, N, N>& c, const char* what,
                            const InterlockOptions& options) {
  if (!c.allFinite()) throw Error(kInterlockSubject, fmt::format("{} has non-finite elements", what));
  const double scale = c.diagonal().cwiseAbs().maxCoeff();
  const double asymmetry = (c - c.transpose()).cwiseAbs().maxCoeff();
  if (asymmetry > options.symmetry_tolerance * scale) {
    throw Error(kInterlockSubject, fmt::format("{} is not symmetric (largest |C_ij - C_ji| = {:.3g}, "
                                      "largest diagonal {:.3g})",
                                      what, asymmetry, scale));
  }
  const Eigen::Matrix<double, N, N> symmetric = 0.5 * (c + c.transpose());
  const auto eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>>(
                               symmetric, Eigen::EigenvaluesOnly)
                               .eigenvalues();
  const double largest = std::max(eigenvalues.maxCoeff(), 0.0);
  if (eigenvalues.minCoeff() < -options.psd_tolerance * largest) {
    throw Error(kInterlockSubject, fmt::format("{} is not positive semi-definite (eigenvalue {:.3g}, "
                                      "largest {:.3g})",
                                      what, eigenvalues.minCoeff(), largest));
  }
}

// NearestRotation with the interlock's subject and the gimbal-lock check.
Eigen::Matrix3d RotationOrThrow(const Eigen::Matrix3d& matrix, double max_deviation) {
  Eigen::Matrix3d r;
  try {
    r = NearestRotation(matrix, max_deviation);
  } catch (const Error& e) {
    throw Error(kInterlockSubject, "relative orientation matrix " + e.reason());
  }
  if (std::hypot(r(2, 1), r(2, 2)) < kGimbalLockCos) {
    throw Error(kInterlockSubject, "phi is +-90 deg: omega and kappa are not separable");
  }
  return r;
}

// The atan2 forms of OmegaPhiKappaFromMatrix on row-major elements.
template <typename T>
void AnglesFromElementsT(const T* m, T* angles) {
  using std::atan2;
  using std::sqrt;
  const T cos_phi = sqrt(m[7] * m[7] + m[8] * m[8]);
  angles[0] = atan2(-m[7], m[8]);       // omega: m32 = -sin w cos p, m33 = cos w cos p
  angles[1] = atan2(m[6], cos_phi);     // phi:   m31 = sin p
  angles[2] = atan2(-m[3], m[0]);       // kappa: m21 = -cos p sin k, m11 = cos p cos k
}

// d angles / d elements of an exact rotation (automatic differentiation).
Matrix39d AtanJacobian(const Eigen::Matrix3d& r) {
  using Jet = ceres::Jet<double, 9>;
  Jet m[9];
  for (int i = 0; i < 9; ++i) m[i] = Jet(r(i / 3, i % 3), i);
  Jet angles[3];
  AnglesFromElementsT(m, angles);
  Matrix39d j;
  for (int a = 0; a < 3; ++a) j.row(a) = angles[a].v.transpose();
  return j;
}

// d R / d M (row-major 9x9) of the polar factor R = U V^T of M = U S V^T.
Matrix9d PolarFactorJacobian(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  const Eigen::Vector3d& s = svd.singularValues();
  Matrix9d j;
  for (int k = 0; k < 9; ++k) {
    Eigen::Matrix3d dm = Eigen::Matrix3d::Zero();
    dm(k / 3, k % 3) = 1.0;
    const Eigen::Matrix3d x = u.transpose() * dm * v;
    Eigen::Matrix3d y;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) y(a, b) = (x(a, b) - x(b, a)) / (s(a) + s(b));
    }
    const Eigen::Matrix3d dr = u * y * v.transpose();
    for (int e = 0; e < 9; ++e) j(e, k) = dr(e / 3, e % 3);
  }
  return j;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return s;
}

// d M / d(small rotation of `kind`) at the rotation r, row-major 9x3.
Matrix93d MatrixFromSmallRotationJacobian(const Eigen::Matrix3d& r, InterlockCovarianceKind kind) {
  Matrix93d j;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Matrix3d dm = kind == InterlockCovarianceKind::kSmallRotationStellarAxes
                                   ? Eigen::Matrix3d(-Skew(Eigen::Vector3d::Unit(i)) * r)
                                   : Eigen::Matrix3d(-r * Skew(Eigen::Vector3d::Unit(i)));
    for (int e = 0; e < 9; ++e) j(e, i) = dm(e / 3, e % 3);
  }
  return j;
}

Eigen::Matrix3d SmallRotationJacobianAt(const Eigen::Matrix3d& r, InterlockCovarianceKind kind) {
  if (kind == InterlockCovarianceKind::kAngles) return Eigen::Matrix3d::Identity();
  return AtanJacobian(r) * MatrixFromSmallRotationJacobian(r, kind);
}

InterlockAngles Finish(const Eigen::Matrix3d& matrix, const Eigen::Matrix3d& r,
                       const Eigen::Matrix3d& covariance_rad2, const std::string& source,
                       const InterlockOptions& options) {
  InterlockAngles out;
  out.rotation = r;
  out.orthogonality_deviation = (matrix.transpose() * matrix - Eigen::Matrix3d::Identity()).norm();
  double angles[3];
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> row_major =
      options.angle_form == InterlockAngleForm::kElementAtan2 ? matrix : r;
  AnglesFromElementsT(row_major.data(), angles);
  out.angles = {angles[0], angles[1], angles[2]};
  out.covariance_rad2 = 0.5 * (covariance_rad2 + covariance_rad2.transpose());
  const Eigen::Vector3d sigma_rad = out.covariance_rad2.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      const double denominator = sigma_rad(a) * sigma_rad(b);
      out.correlation(a, b) = denominator > 0.0 ? out.covariance_rad2(a, b) / denominator : 0.0;
    }
  }
  out.omega_sigma_arcsec = ArcsecFromRadians(sigma_rad(0));
  out.phi_sigma_arcsec = ArcsecFromRadians(sigma_rad(1));
  out.kappa_sigma_arcsec = ArcsecFromRadians(sigma_rad(2));
  out.summary = fmt::format(
      "omega {} +- {:.1f}\", phi {} +- {:.1f}\", kappa {} +- {:.1f}\" (seed 004 sequence) from a "
      "matrix {:.1e} from orthonormal ({}) and the covariance of {}.",
      DmsFromRadians(out.angles.omega_rad), out.omega_sigma_arcsec,
      DmsFromRadians(out.angles.phi_rad), out.phi_sigma_arcsec,
      DmsFromRadians(out.angles.kappa_rad), out.kappa_sigma_arcsec, out.orthogonality_deviation,
      options.angle_form == InterlockAngleForm::kElementAtan2 ? "angles from its elements"
                                                              : "angles of the nearest rotation",
      source);
  return out;
}

}  // namespace

const char* InterlockCovarianceKindName(InterlockCovarianceKind kind) {
  switch (kind) {
    case InterlockCovarianceKind::kAngles:
      return "angles";
    case InterlockCovarianceKind::kSmallRotationStellarAxes:
      return "stellar-axes";
    case InterlockCovarianceKind::kSmallRotationTerrainAxes:
      return "terrain-axes";
  }
  return "unknown";
}

bool InterlockOptions::Check(std::string* why) const {
  auto fail = [why](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (!(max_orthogonality_deviation > 0.0) || !std::isfinite(max_orthogonality_deviation)) {
    return fail(fmt::format("max_orthogonality_deviation must be positive and finite, got {}",
                            max_orthogonality_deviation));
  }
  if (!(symmetry_tolerance >= 0.0) || !std::isfinite(symmetry_tolerance)) {
    return fail(fmt::format("symmetry_tolerance must be >= 0 and finite, got {}", symmetry_tolerance));
  }
  if (!(psd_tolerance >= 0.0) || !std::isfinite(psd_tolerance)) {
    return fail(fmt::format("psd_tolerance must be >= 0 and finite, got {}", psd_tolerance));
  }
  return true;
}

Matrix39d AnglesFromMatrixJacobian(const Eigen::Matrix3d& matrix, double max_orthogonality_deviation) {
  const Eigen::Matrix3d r = RotationOrThrow(matrix, max_orthogonality_deviation);
  return AtanJacobian(r) * PolarFactorJacobian(matrix);
}

Eigen::Matrix3d AnglesFromSmallRotationJacobian(const OmegaPhiKappa& angles,
                                                InterlockCovarianceKind kind) {
  const Eigen::Matrix3d r = MatrixFromOmegaPhiKappa(angles);
  if (std::hypot(r(2, 1), r(2, 2)) < kGimbalLockCos) {
    throw Error(kInterlockSubject, "phi is +-90 deg: omega and kappa are not separable");
  }
  return SmallRotationJacobianAt(r, kind);
}

InterlockAngles InterlockAnglesFromMatrix(const Eigen::Matrix3d& matrix,
                                          const Matrix9d& element_covariance,
                                          const InterlockOptions& options) {
  CheckOptionsOrThrow(options);
  CheckCovarianceOrThrow(element_covariance, "covariance of the matrix elements", options);
  const Eigen::Matrix3d r = RotationOrThrow(matrix, options.max_orthogonality_deviation);
  const Matrix39d j = AtanJacobian(r) * PolarFactorJacobian(matrix);
  return Finish(matrix, r, j * element_covariance * j.transpose(), "the 9 matrix elements",
                options);
}

InterlockAngles InterlockAnglesFromRotationCovariance(const Eigen::Matrix3d& matrix,
                                                      const Eigen::Matrix3d& covariance_rad2,
                                                      InterlockCovarianceKind kind,
                                                      const InterlockOptions& options) {
  CheckOptionsOrThrow(options);
  CheckCovarianceOrThrow(covariance_rad2, "covariance", options);
  const Eigen::Matrix3d r = RotationOrThrow(matrix, options.max_orthogonality_deviation);
  const Eigen::Matrix3d j = SmallRotationJacobianAt(r, kind);
  const std::string source = kind == InterlockCovarianceKind::kAngles
                                 ? std::string("the angles")
                                 : fmt::format("a small rotation of the {}",
                                               kind == InterlockCovarianceKind::kSmallRotationStellarAxes
                                                   ? "stellar axes"
                                                   : "terrain axes");
  return Finish(matrix, r, j * covariance_rad2 * j.transpose(), source, options);
}

Matrix93d MatrixFromAnglesJacobian(const OmegaPhiKappa& angles) {
  using Jet = ceres::Jet<double, 3>;
  Jet m[9];
  OmegaPhiKappaMatrixT(Jet(angles.omega_rad, 0), Jet(angles.phi_rad, 1), Jet(angles.kappa_rad, 2), m);
  Matrix93d j;
  for (int e = 0; e < 9; ++e) j.row(e) = m[e].v.transpose();
  return j;
}

Matrix9d MatrixCovarianceFromAngleCovariance(const OmegaPhiKappa& angles,
                                             const Eigen::Matrix3d& angle_covariance_rad2,
                                             const InterlockOptions& options) {
  CheckOptionsOrThrow(options);
  CheckCovarianceOrThrow(angle_covariance_rad2, "covariance of the angles", options);
  const Matrix93d j = MatrixFromAnglesJacobian(angles);
  const Matrix9d c = j * angle_covariance_rad2 * j.transpose();
  return 0.5 * (c + c.transpose());
}

Eigen::Matrix3d SmallRotationCovarianceFromAngleCovariance(
    const OmegaPhiKappa& angles, const Eigen::Matrix3d& angle_covariance_rad2,
    InterlockCovarianceKind kind, const InterlockOptions& options) {
  CheckOptionsOrThrow(options);
  CheckCovarianceOrThrow(angle_covariance_rad2, "covariance of the angles", options);
  // d rotation / d angles is the inverse of d angles / d rotation (both 3x3,
  // regular away from gimbal lock).
  const Eigen::Matrix3d k = AnglesFromSmallRotationJacobian(angles, kind).inverse();
  const Eigen::Matrix3d c = k * angle_covariance_rad2 * k.transpose();
  return 0.5 * (c + c.transpose());
}

std::string DmsFromRadians(double angle_rad, int decimals) {
  decimals = std::clamp(decimals, 0, 9);
  const double scale = std::pow(10.0, decimals);
  const double total = std::round(std::abs(ArcsecFromRadians(angle_rad)) * scale);  // units of 10^-decimals "
  const double per_minute = 60.0 * scale;
  const double per_degree = 3600.0 * scale;
  const long long degrees = static_cast<long long>(std::floor(total / per_degree));
  const double rest = total - degrees * per_degree;
  const int minutes = static_cast<int>(std::floor(rest / per_minute));
  const double seconds = (rest - minutes * per_minute) / scale;
  const char sign = angle_rad < 0.0 && total > 0.0 ? '-' : '+';
  const int width = decimals > 0 ? 3 + decimals : 2;
  return fmt::format("{}{} {:02d}'{:0{}.{}f}\"", sign, degrees, minutes, seconds, width, decimals);
}

}  // namespace platemeter
