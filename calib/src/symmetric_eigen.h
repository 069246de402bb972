#pragma once
// Eigenvalues and eigenvectors of the scaled reduced normal matrix
// (adjustment_covariance.cpp) through LAPACK, the library Ceres links. On a
// 200-frame block the matrix is 1202 x 1202; Eigen's SelfAdjointEigenSolver
// (unblocked tridiagonalisation, then implicit QR accumulating every
// eigenvector) took 1.2 s. LAPACK's blocked tridiagonalisation is done once
// here, and from it come all the eigenvalues (O(n^2)), the eigenvectors of the
// few smallest (inverse iteration) when only they are named in the rank
// report, or every eigenvector (divide and conquer) when the pseudo-inverse
// needs them.
#include <Eigen/Core>

namespace platemeter {

class SymmetricEigenproblem {
 public:
  // Reads the lower triangle of `s`. Throws platemeter::Error if LAPACK fails.
  explicit SymmetricEigenproblem(const Eigen::MatrixXd& s);

  int size() const { return static_cast<int>(diagonal_.size()); }
  // All eigenvalues, ascending.
  Eigen::VectorXd Eigenvalues() const;
  // Eigenvectors (unit columns, ascending eigenvalue) of the `count` smallest
  // eigenvalues; false if inverse iteration does not converge for one of them.
  bool LowestEigenvectors(int count, Eigen::MatrixXd* vectors) const;
  // Every eigenpair, eigenvalues ascending. Throws platemeter::Error if LAPACK fails.
  void All(Eigen::VectorXd* values, Eigen::MatrixXd* vectors) const;

 private:
  // Columns of the tridiagonal's eigenvectors turned into the matrix's (Q z).
  void BackTransform(Eigen::MatrixXd* vectors) const;

  Eigen::MatrixXd reflectors_;  // dsytrd's Householder vectors below the diagonal
  Eigen::VectorXd diagonal_;    // the tridiagonal matrix T = Q^T S Q
  Eigen::VectorXd off_diagonal_;
  Eigen::VectorXd tau_;
};

// The inverse of a symmetric positive definite matrix by its Cholesky factor
// (LAPACK dpotrf, dpotri); false if the factorisation finds it is not
// positive definite.
bool InverseOfPositiveDefinite(const Eigen::MatrixXd& s, Eigen::MatrixXd* inverse);

// Copies the lower triangle of a square matrix onto its upper triangle.
void MirrorLowerTriangle(Eigen::MatrixXd* m);

}  // namespace platemeter
