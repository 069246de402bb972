// The engine's whitened observation and prior equations (adjustment_internal.h).
#include <algorithm>
#include <vector>

#include <Eigen/Cholesky>

#include "adjustment_internal.h"
#include "platemeter/core/error.h"

namespace platemeter {

Eigen::MatrixXd SqrtInformation(const Eigen::MatrixXd& covariance, const std::string& what) {
  if (covariance.rows() != covariance.cols() || covariance.rows() == 0 || !covariance.allFinite()) {
    throw Error(what, "the covariance must be a finite square matrix");
  }
  // Independent components (every image observation): L = diag(1 / sigma),
  // what the factorisation below gives, without its allocations.
  if (covariance.isDiagonal(0.0) && (covariance.diagonal().array() > 0.0).all()) {
    return covariance.diagonal().cwiseSqrt().cwiseInverse().asDiagonal();
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
  const int d = raw->num_residuals();
  if (d <= 2) {
    for (int i = 0; i < d; ++i) {
      for (int k = 0; k < d; ++k) small_sqrt_information_[i * d + k] = sqrt_information_(i, k);
    }
  }
}

bool WhitenedCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  if (!raw_->Evaluate(parameters, residuals, jacobians)) return false;
  Whiten(residuals, 1);
  if (jacobians != nullptr) {
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (size_t b = 0; b < sizes.size(); ++b) {
      if (jacobians[b] != nullptr) Whiten(jacobians[b], sizes[b]);
    }
  }
  return true;
}

// In place, without the temporary an aliased Eigen product allocates: this
// runs for every observation at every iteration (400 000 on a large block).
// The sums run over k in order, as Eigen's product takes them.
void WhitenedCost::Whiten(double* m, int cols) const {
  const int d = num_residuals();
  const std::array<double, 4>& l = small_sqrt_information_;
  if (d == 1) {  // a distance
    for (int c = 0; c < cols; ++c) m[c] *= l[0];
    return;
  }
  if (d == 2) {  // an image observation: in place, column by column
    for (int c = 0; c < cols; ++c) {
      const double first = m[c], second = m[cols + c];
      m[c] = l[0] * first + l[1] * second;
      m[cols + c] = l[2] * first + l[3] * second;
    }
    return;
  }
  const int size = d * cols;
  constexpr int kOnStack = 64;  // a 2 x 10 Jacobian block and more
  double on_stack[kOnStack];
  std::vector<double> on_heap;
  double* raw = on_stack;
  if (size > kOnStack) {
    on_heap.resize(size);
    raw = on_heap.data();
  }
  std::copy(m, m + size, raw);
  for (int i = 0; i < d; ++i) {
    for (int c = 0; c < cols; ++c) {
      double sum = 0.0;
      for (int k = 0; k < d; ++k) sum += sqrt_information_(i, k) * raw[k * cols + c];
      m[i * cols + c] = sum;
    }
  }
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
