// The LAPACK eigen-solver of the adjustment's covariance step
// (calib/src/symmetric_eigen.h) against Eigen's SelfAdjointEigenSolver, which
// it replaced: the same eigenvalues, the same eigenvectors up to sign, on a
// well-conditioned matrix, on one with a null space and a weak direction (the
// shape of a reduced normal matrix with a datum defect), and with repeated
// eigenvalues.
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "../../calib/src/symmetric_eigen.h"

namespace platemeter {
namespace {

// A symmetric matrix with the given eigenvalues and random eigenvectors.
Eigen::MatrixXd WithEigenvalues(const Eigen::VectorXd& lambda, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(lambda.size(), lambda.size());
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = normal(random);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ();
  const Eigen::MatrixXd s = q * lambda.asDiagonal() * q.transpose();
  return 0.5 * (s + s.transpose());
}

// Column k of `a` equals column k of `b` up to sign.
void ExpectSameDirection(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, int k, double tolerance) {
  const double sign = a.col(k).dot(b.col(k)) < 0.0 ? -1.0 : 1.0;
  EXPECT_LT((a.col(k) - sign * b.col(k)).norm(), tolerance) << "column " << k;
}

TEST(SymmetricEigen, AgreesWithEigenOnAWellConditionedMatrix) {
  const int n = 120;
  Eigen::VectorXd lambda(n);
  for (int i = 0; i < n; ++i) lambda[i] = 0.1 + i;  // distinct, gaps of 1
  const Eigen::MatrixXd s = WithEigenvalues(lambda, 3);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> reference(s);
  const SymmetricEigenproblem problem(s);
  EXPECT_LT((problem.Eigenvalues() - reference.eigenvalues()).cwiseAbs().maxCoeff(), 1e-11);
  Eigen::MatrixXd lowest;
  ASSERT_TRUE(problem.LowestEigenvectors(4, &lowest));
  ASSERT_EQ(lowest.cols(), 4);
  for (int k = 0; k < 4; ++k) ExpectSameDirection(lowest, reference.eigenvectors(), k, 1e-10);
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  problem.All(&values, &vectors);
  EXPECT_LT((values - reference.eigenvalues()).cwiseAbs().maxCoeff(), 1e-11);
  EXPECT_LT((vectors * values.asDiagonal() * vectors.transpose() - s).cwiseAbs().maxCoeff(), 1e-10);
  Eigen::MatrixXd inverse;
  ASSERT_TRUE(InverseOfPositiveDefinite(s, &inverse));
  EXPECT_LT((inverse * s - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_EQ((inverse - inverse.transpose()).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SymmetricEigen, NullSpaceAndAWeakDirection) {
  const int n = 60;
  Eigen::VectorXd lambda(n);
  for (int i = 0; i < n; ++i) lambda[i] = 1.0 + 0.5 * i;
  lambda[0] = 0.0;   // two null directions (a datum defect)
  lambda[1] = 0.0;
  lambda[2] = 1e-8;  // a weak direction
  const Eigen::MatrixXd s = WithEigenvalues(lambda, 5);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> reference(s);
  const SymmetricEigenproblem problem(s);
  const Eigen::VectorXd values = problem.Eigenvalues();
  EXPECT_LT(std::abs(values[0]), 1e-13);
  EXPECT_LT(std::abs(values[1]), 1e-13);
  EXPECT_NEAR(values[2], 1e-8, 1e-13);
  Eigen::MatrixXd lowest;
  ASSERT_TRUE(problem.LowestEigenvectors(3, &lowest));
  ExpectSameDirection(lowest, reference.eigenvectors(), 2, 1e-6);  // the weak one is separated from the rest
  // The two null vectors span the reference's null space.
  const Eigen::MatrixXd null_space = reference.eigenvectors().leftCols(2);
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR((null_space.transpose() * lowest.col(k)).norm(), 1.0, 1e-10);
  }
  Eigen::MatrixXd inverse;
  EXPECT_FALSE(InverseOfPositiveDefinite(s, &inverse));
}

TEST(SymmetricEigen, RepeatedEigenvaluesGiveAnOrthonormalBasis) {
  const int n = 40;
  Eigen::VectorXd lambda = Eigen::VectorXd::Constant(n, 2.0);
  lambda.head(5).setConstant(0.5);
  const Eigen::MatrixXd s = WithEigenvalues(lambda, 7);
  const SymmetricEigenproblem problem(s);
  Eigen::MatrixXd lowest;
  ASSERT_TRUE(problem.LowestEigenvectors(5, &lowest));
  EXPECT_LT((lowest.transpose() * lowest - Eigen::MatrixXd::Identity(5, 5)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((s * lowest - 0.5 * lowest).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(SymmetricEigen, OneByOne) {
  const Eigen::MatrixXd s = Eigen::MatrixXd::Constant(1, 1, 4.0);
  const SymmetricEigenproblem problem(s);
  EXPECT_EQ(problem.Eigenvalues()[0], 4.0);
  Eigen::MatrixXd lowest;
  ASSERT_TRUE(problem.LowestEigenvectors(1, &lowest));
  EXPECT_NEAR(std::abs(lowest(0, 0)), 1.0, 1e-15);
  Eigen::MatrixXd inverse;
  ASSERT_TRUE(InverseOfPositiveDefinite(s, &inverse));
  EXPECT_EQ(inverse(0, 0), 0.25);
}

}  // namespace
}  // namespace platemeter
