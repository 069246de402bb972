// Solving an adjustment (adjustment.h): an optional robust pass that rejects
// gross errors, then the plain weighted pass whose statistics are reported.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include <boost/math/distributions/normal.hpp>
#include <fmt/format.h>

#include "adjustment_internal.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const AdjustmentProgress& progress, std::string stage, int max_iterations)
      : progress_(progress), stage_(std::move(stage)), max_iterations_(max_iterations) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (progress_) progress_(stage_, std::min(1.0, double(summary.iteration) / max_iterations_));
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const AdjustmentProgress& progress_;
  std::string stage_;
  int max_iterations_;
};

// The whitened residual vector of one equation at the current values.
Eigen::VectorXd Whitened(const AdjustmentProblem::Impl& impl, const AdjustmentEquation& equation) {
  std::vector<const double*> parameters;
  for (int b : equation.blocks) parameters.push_back(impl.blocks[b].values.data());
  Eigen::VectorXd r(equation.Dimension());
  if (!equation.cost->Evaluate(parameters.data(), r.data(), nullptr)) r.setConstant(NAN);
  return r;
}

void ConfigureSolver(const AdjustmentProblem::Impl& impl, const AdjustmentOptions& options,
                     ceres::Solver::Options* solver) {
  solver->max_num_iterations = options.max_iterations;
  solver->function_tolerance = options.function_tolerance;
  solver->gradient_tolerance = 1e-14;
  solver->parameter_tolerance = options.parameter_tolerance;
  if (options.polish) {
    // Near the minimum v'Pv changes below its own round-off and the trust
    // region rejects good Gauss-Newton steps; non-monotonic steps keep taking them.
    solver->use_nonmonotonic_steps = true;
    solver->max_consecutive_nonmonotonic_steps = options.max_iterations;
    solver->min_relative_decrease = 0.0;
  }
  solver->num_threads = options.num_threads > 0 ? options.num_threads
                                                : std::max(1u, std::thread::hardware_concurrency());
  solver->logging_type = ceres::SILENT;
  // Powell's dogleg takes the Gauss-Newton step whenever it lies inside the
  // trust region; Levenberg-Marquardt's damping crawls along weakly determined
  // directions (a fixed frame's attitude holding a block's rotation): on the
  // 200-frame benchmark block 15 iterations instead of 31.
  solver->trust_region_strategy_type = ceres::DOGLEG;
  int free_global = 0;
  for (const AdjustmentBlock& b : impl.blocks) {
    if (b.kind == BlockKind::kPoint) continue;
    for (size_t i = 0; i < b.names.size(); ++i) free_global += b.IsFixed(static_cast<int>(i)) ? 0 : 1;
  }
  if (impl.num_points > 0) {
    // Points first (seed 000's reduction), the inner cone and the frames in the reduced system.
    auto* ordering = new ceres::ParameterBlockOrdering;
    for (const AdjustmentBlock& b : impl.blocks) {
      ordering->AddElementToGroup(const_cast<double*>(b.values.data()), b.kind == BlockKind::kPoint ? 0 : 1);
    }
    solver->linear_solver_ordering.reset(ordering);
    solver->linear_solver_type = free_global <= 3000 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  } else {
    solver->linear_solver_type = free_global <= 1000 ? ceres::DENSE_QR : ceres::SPARSE_NORMAL_CHOLESKY;
  }
}

// The rejection level: given, or where a Gaussian residual component is
// exceeded with probability false_rejection_rate over all `components` (Bonferroni).
double RejectionThreshold(const AdjustmentOptions& options, size_t components) {
  if (options.rejection_threshold > 0.0) return options.rejection_threshold;
  const double per_component = options.false_rejection_rate / std::max<size_t>(1, components);
  return boost::math::quantile(boost::math::complement(boost::math::normal(), per_component / 2));
}

}  // namespace

AdjustmentResult AdjustmentProblem::Solve(const AdjustmentOptions& options, const AdjustmentProgress& progress) {
  std::string why;
  if (!options.Check(&why)) throw Error("adjustment options", why);
  Impl& impl = *impl_;
  AdjustmentResult result;
  const auto solve_start = std::chrono::steady_clock::now();

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (AdjustmentBlock& b : impl.blocks) {
    const int size = static_cast<int>(b.names.size());
    problem.AddParameterBlock(b.values.data(), size);
    std::vector<int> fixed;
    for (int i = 0; i < size; ++i) {
      if (b.IsFixed(i)) fixed.push_back(i);
    }
    if (static_cast<int>(fixed.size()) == size) {
      problem.SetParameterBlockConstant(b.values.data());
    } else if (!fixed.empty()) {
      problem.SetManifold(b.values.data(), new ceres::SubsetManifold(size, fixed));
    }
  }
  const bool robust = options.robust_loss_scale > 0.0;
  for (AdjustmentEquation& equation : impl.equations) {
    if (equation.status != ObservationStatus::kUsed) continue;
    std::vector<double*> parameters;
    for (int b : equation.blocks) parameters.push_back(impl.blocks[b].values.data());
    equation.loss = nullptr;
    ceres::LossFunction* loss = nullptr;
    // Only the robust pass needs a loss (a wrapper it can reset to none
    // afterwards); without one Ceres skips the loss's correction of every
    // residual and Jacobian.
    if (!equation.is_prior && robust) {
      equation.loss = new ceres::LossFunctionWrapper(
          new ceres::CauchyLoss(options.robust_loss_scale), ceres::TAKE_OWNERSHIP);
      loss = equation.loss;
    }
    equation.id = problem.AddResidualBlock(equation.cost.get(), loss, parameters);
  }

  ceres::Solver::Options solver;
  ConfigureSolver(impl, options, &solver);
  int iterations = 0;
  if (robust) {
    ProgressCallback callback(progress, "robust pass", options.max_iterations);
    solver.callbacks = {&callback};
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    iterations += static_cast<int>(summary.iterations.size());
    // Gross errors: whitened components far beyond a robust scale of them.
    std::vector<double> magnitudes;
    for (const AdjustmentEquation& e : impl.equations) {
      if (e.is_prior || e.status != ObservationStatus::kUsed) continue;
      const Eigen::VectorXd w = Whitened(impl, e);
      for (int i = 0; i < w.size(); ++i) magnitudes.push_back(std::abs(w[i]));
    }
    double scale = 1.0;
    if (!magnitudes.empty()) {
      std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() / 2, magnitudes.end());
      scale = std::max(1e-12, 1.4826 * magnitudes[magnitudes.size() / 2]);
    }
    const double threshold = RejectionThreshold(options, magnitudes.size());
    for (AdjustmentEquation& e : impl.equations) {
      if (e.is_prior || e.status != ObservationStatus::kUsed) continue;
      const double worst = Whitened(impl, e).cwiseAbs().maxCoeff();
      if (!(worst <= threshold * scale)) {
        e.status = ObservationStatus::kRejected;
        e.reason = fmt::format("robust pass: normalized residual {:.1f} > {:.1f} (robust sigma0 {:.3f})",
                               worst / scale, threshold, scale);
        problem.RemoveResidualBlock(e.id);
        e.id = nullptr;
        e.loss = nullptr;
        ++result.rejected;
      } else if (e.loss != nullptr) {
        e.loss->Reset(nullptr, ceres::TAKE_OWNERSHIP);
      }
    }
  }
  // The weighted pass: Gauss-Newton on the reduced normals, or Ceres's trust
  // region where that cannot step (adjustment_gauss_newton.cpp).
  GaussNewtonOutcome gauss_newton = SolveByReducedNormals(impl, problem, options, progress);
  iterations += gauss_newton.iterations;
  std::string stop_message = gauss_newton.message;
  if (gauss_newton.ok) {
    result.converged = gauss_newton.converged;
  } else {
    ProgressCallback callback(progress, "weighted pass", options.max_iterations);
    solver.callbacks = {&callback};
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    iterations += static_cast<int>(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    stop_message = summary.message;
    if (summary.termination_type == ceres::FAILURE) {
      throw Error("adjustment", "the solver failed: " + summary.message);
    }
    // Where the start was too far for Gauss-Newton (the stellar camera's
    // point of symmetry and decentering angle do nothing while the distortion
    // is zero), its steps now finish what the trust region began: to the
    // stationary point, whatever the threads' order of summation did to
    // Ceres's last iterations.
    GaussNewtonOutcome finish = SolveByReducedNormals(impl, problem, options, progress);
    if (finish.ok) {
      iterations += finish.iterations;
      result.converged = finish.converged;
      stop_message = finish.message;
      gauss_newton.normals = std::move(finish.normals);
    }
  }
  result.iterations = iterations;
  result.solve_seconds = SecondsSince(solve_start);

  const auto covariance_start = std::chrono::steady_clock::now();
  if (progress) progress("normal equations", 0.0);
  const ReducedNormals normals =
      gauss_newton.normals ? std::move(*gauss_newton.normals) : BuildReducedNormals(impl);
  if (progress) progress("covariance", 0.0);
  ComputeCovarianceAndRank(impl, normals, options, &result);
  ComputeStatistics(impl, normals, options, &result);
  ComputePointEstimates(impl, normals, &result);
  result.covariance_seconds = SecondsSince(covariance_start);
  if (!result.converged) {
    result.summary = fmt::format("The solver stopped without converging ({}): {} ", stop_message, result.summary);
  }
  return result;
}

}  // namespace platemeter
