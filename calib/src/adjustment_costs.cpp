// The engine's whitened observation and prior equations (adjustment_internal.h).
#include <Eigen/Cholesky>

#include "adjustment_internal.h"
#include "platemeter/core/error.h"

namespace platemeter {

Eigen::MatrixXd SqrtInformation(const Eigen::MatrixXd& covariance, const std::string& what) {
  if (covariance.rows() != covariance.cols() || covariance.rows() == 0 || !covariance.allFinite()) {
    throw Error(what, "the covariance must be a finite square matrix");
  }
  // L^T L = C^-1 with L = chol(C)^-1 (upper triangular from the lower factor of C).
  Eigen::LLT<Eigen::MatrixXd> llt(covariance);
  if (llt.info() != Eigen::Success) throw Error(what, "the covariance is not positive definite");
  const Eigen::MatrixXd lower = llt.matrixL();
  return lower.triangularView<Eigen::Lower>().solve(
      Eigen::MatrixXd::Identity(covariance.rows(), covariance.cols()));
}

WhitenedCost::WhitenedCost(ceres::CostFunction* raw, const Eigen::MatrixXd& sqrt_information)
    : raw_(raw), sqrt_information_(sqrt_information) {
  set_num_residuals(raw->num_residuals());
  *mutable_parameter_block_sizes() = raw->parameter_block_sizes();
}

bool WhitenedCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  if (!raw_->Evaluate(parameters, residuals, jacobians)) return false;
  const int d = num_residuals();
  Eigen::Map<Eigen::VectorXd> r(residuals, d);
  r = sqrt_information_ * r;
  if (jacobians != nullptr) {
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (size_t b = 0; b < sizes.size(); ++b) {
      if (jacobians[b] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(jacobians[b], d,
                                                                                          sizes[b]);
      j = sqrt_information_ * j;
    }
  }
  return true;
}

PriorCost::PriorCost(int block_size, std::vector<int> indices, Eigen::VectorXd values,
                     const Eigen::MatrixXd& covariance)
    : block_size_(block_size), indices_(std::move(indices)), values_(std::move(values)) {
  sqrt_information_ = SqrtInformation(covariance, "prior observation");
  set_num_residuals(static_cast<int>(indices_.size()));
  mutable_parameter_block_sizes()->push_back(block_size_);
}

bool PriorCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int d = static_cast<int>(indices_.size());
  Eigen::VectorXd difference(d);
  for (int i = 0; i < d; ++i) difference[i] = parameters[0][indices_[i]] - values_[i];
  Eigen::Map<Eigen::VectorXd>(residuals, d) = sqrt_information_ * difference;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(jacobians[0], d,
                                                                                        block_size_);
    j.setZero();
    for (int i = 0; i < d; ++i) j.col(indices_[i]) = sqrt_information_.col(i);
  }
  return true;
}

}  // namespace platemeter
