#pragma once
// The engine's inside (adjustment.h): blocks, observations and priors as the
// solver and the normal-equation reduction both see them.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "platemeter/calib/adjustment.h"

namespace platemeter {

struct AdjustmentBlock {
  std::string label;
  std::string group;
  BlockKind kind = BlockKind::kGlobal;
  std::vector<std::string> names;
  std::vector<double> values;
  std::vector<double> initial;
  std::vector<ParameterState> states;
  std::vector<bool> has_prior;  // a prior observation touches the parameter
  int global_offset = -1;       // among the non-point parameters; -1 for a point
  int point_index = -1;         // among the point blocks; -1 otherwise
  // A point block of fewer than 3 parameters is padded to 3 with fixed ones.
  bool IsFixed(int i) const {
    return i >= static_cast<int>(states.size()) || states[i].kind == ParameterState::Kind::kFixed;
  }
};

// Residuals whitened by a square root of the information matrix:
// whitened = L raw, L^T L = covariance^-1.
class WhitenedCost : public ceres::CostFunction {
 public:
  WhitenedCost(ceres::CostFunction* raw, const Eigen::MatrixXd& sqrt_information);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  const ceres::CostFunction& raw() const { return *raw_; }
  const Eigen::MatrixXd& sqrt_information() const { return sqrt_information_; }

 private:
  void Whiten(double* row_major, int cols) const;  // L times a num_residuals x cols matrix
  std::unique_ptr<ceres::CostFunction> raw_;
  Eigen::MatrixXd sqrt_information_;
  // L of an image observation (d <= 2), row-major, inside the object: read
  // at every evaluation, it is one cache miss fewer than the matrix's storage.
  std::array<double, 4> small_sqrt_information_{};
};

// A prior observation of some parameters of one block: L (x[indices] - values).
class PriorCost : public ceres::CostFunction {
 public:
  PriorCost(int block_size, std::vector<int> indices, Eigen::VectorXd values,
            const Eigen::MatrixXd& covariance);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  const std::vector<int>& indices() const { return indices_; }
  const Eigen::VectorXd& values() const { return values_; }
  const Eigen::MatrixXd& sqrt_information() const { return sqrt_information_; }

 private:
  int block_size_;
  std::vector<int> indices_;
  Eigen::VectorXd values_;
  Eigen::MatrixXd sqrt_information_;
};

// A square root of the inverse of a covariance (upper Cholesky factor of the
// information). Throws platemeter::Error if the covariance is not positive definite.
Eigen::MatrixXd SqrtInformation(const Eigen::MatrixXd& covariance, const std::string& what);

struct AdjustmentEquation {
  std::unique_ptr<ceres::CostFunction> cost;  // WhitenedCost or PriorCost
  std::vector<int> blocks;
  bool is_prior = false;
  std::string label;  // prior's label
  std::string group, item, origin;
  ObservationStatus status = ObservationStatus::kUsed;
  std::string reason;
  ceres::LossFunctionWrapper* loss = nullptr;  // owned by the problem
  ceres::ResidualBlockId id = nullptr;
  int Dimension() const { return cost->num_residuals(); }
};

struct AdjustmentProblem::Impl {
  std::vector<AdjustmentBlock> blocks;
  std::vector<AdjustmentEquation> equations;  // observations and priors, in order of addition
  std::vector<int> observation_equation;      // observation index -> equation index
  int num_global = 0;                         // non-point parameters (fixed included)
  int num_points = 0;
  Eigen::MatrixXd gauge;                      // num_global x g, empty if none
  std::vector<std::string> gauge_names;
  std::vector<bool> gauge_trace_rows;
  bool gauge_is_datum = false;
};

// --- Reduced normal equations (adjustment_normals.cpp) ---------------------
struct PointNormals {
  int block = -1;
  Eigen::Matrix3d n_pp = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d n_pp_inverse = Eigen::Matrix3d::Zero();  // pseudo-inverse over the free, determined coordinates
  int rank = 0;                                            // free coordinates determined
  std::vector<std::pair<int, Eigen::MatrixXd>> n_pb;       // (global block, 3 x size)
  Eigen::Vector3d b_p = Eigen::Vector3d::Zero();           // J_p^T v (whitened)
  int rays = 0;
};

struct ReducedNormals {
  Eigen::MatrixXd n_gg;  // num_global x num_global (fixed rows/columns zero)
  Eigen::VectorXd b_g;   // reduced J_g^T v - N_gp N_pp^-1 J_p^T v (whitened v = model - measured)
  std::vector<PointNormals> points;
  double vtpv = 0.0;     // sum of squared whitened residuals of the used equations
  long observation_rows = 0;
  long prior_rows = 0;
};

ReducedNormals BuildReducedNormals(const AdjustmentProblem::Impl& impl);

// --- Gauss-Newton on the reduced normals (adjustment_gauss_newton.cpp) -----
struct GaussNewtonOutcome {
  bool ok = false;         // false: a step could not be taken (singular or near-singular
                           // reduced normals, a gauge freedom, no descent): the caller goes on with Ceres
  bool converged = false;
  int iterations = 0;         // steps taken
  std::string message;
  std::optional<ReducedNormals> normals;  // at the final values, when converged
};
// The weighted pass by Gauss-Newton steps on the reduced normal equations,
// each point's step by back-substitution, values updated in impl.blocks;
// `problem` (the same equations) evaluates the cost.
GaussNewtonOutcome SolveByReducedNormals(AdjustmentProblem::Impl& impl, ceres::Problem& problem,
                                         const AdjustmentOptions& options, const AdjustmentProgress& progress);

// --- Covariance, rank, statistics (adjustment_covariance.cpp) --------------
void ComputeCovarianceAndRank(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                              const AdjustmentOptions& options, AdjustmentResult* result);
void ComputePointEstimates(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                           AdjustmentResult* result);
void ComputeStatistics(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                       const AdjustmentOptions& options, AdjustmentResult* result);

}  // namespace platemeter
