#pragma once
// The information on a mark's centre from the normal matrix of its fit, whose
// first two parameters are the centre (x, y): the Schur complement on the other
// (nuisance) parameters. Shared by the cross and fiducial fits (not installed).
#include <Eigen/Dense>

namespace platemeter::internal {

// Pseudo-inverse of a symmetric positive semi-definite matrix, scaled to unit
// diagonal first so the tolerance (relative to the largest eigenvalue) is
// meaningful: the width and blur of a thin line are nearly interchangeable,
// which must not break the position's sigma. Zero rows (held parameters) stay zero.
inline Eigen::MatrixXd ScaledPseudoInverse(const Eigen::MatrixXd& m, double relative_tolerance) {
  const Eigen::VectorXd scale = m.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * m * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  Eigen::VectorXd inverse_values(m.rows());
  const double tolerance = relative_tolerance * eigen.eigenvalues().maxCoeff();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    inverse_values[i] = eigen.eigenvalues()[i] > tolerance ? 1.0 / eigen.eigenvalues()[i] : 0.0;
  return scale.asDiagonal() * eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose() *
         scale.asDiagonal();
}

// The 2 x 2 information on the centre: normal(centre, centre) minus the
// nuisance parameters' share, through the scaled pseudo-inverse.
inline Eigen::Matrix2d CentreInformation(const Eigen::MatrixXd& normal, double relative_tolerance = 1e-10) {
  const Eigen::Index nuisance = normal.rows() - 2;
  const Eigen::MatrixXd npn = normal.topRightCorner(2, nuisance);
  const Eigen::MatrixXd nnn_pinv = ScaledPseudoInverse(normal.bottomRightCorner(nuisance, nuisance), relative_tolerance);
  return normal.topLeftCorner<2, 2>() - npn * nnn_pinv * npn.transpose();
}

}  // namespace platemeter::internal
