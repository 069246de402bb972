// The weighted pass as Gauss-Newton steps on the reduced normal equations
// (adjustment_internal.h), seed 000 section 2.2's own scheme: the points are
// eliminated, the reduced system of the globals (inner cone, frames) is solved
// by Cholesky, each point follows by back-substitution. The engine forms these
// normals anyway for the covariance; forming them per step costs about half of
// a Ceres trust-region iteration with its dense Schur complement on a large
// block (bench_bundle: 200 frames, 20 000 points), whose outer products run
// at a dynamic F-block size (frames 6, the inner cone 8 to 10 parameters).
// Anything unusual (a gauge freedom, near-singular reduced normals, no
// descent) hands the problem back to Ceres's trust region unchanged in spirit:
// the values reached so far are good starting values.
#include <algorithm>
#include <cmath>
#include <thread>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "adjustment_internal.h"

namespace platemeter {
namespace {

// Reciprocal condition number below which the reduced normals are left to
// Ceres's regularized steps (a direction the data hardly determine).
constexpr double kMinReciprocalCondition = 1e-13;
constexpr int kMaxStepHalvings = 8;
// A reference solution (polish) takes this many full steps once v'Pv can no
// longer judge them: each shrinks the error by the problem's nonlinearity,
// down to the gradient's round-off.
constexpr int kPolishSteps = 8;

struct Step {
  Eigen::VectorXd globals;                 // per global parameter (fixed: 0)
  std::vector<Eigen::Vector3d> points;     // per point block
  double predicted_decrease = 0.0;         // of v'Pv by the quadratic model
};

double Cost(ceres::Problem& problem, int threads) {
  ceres::Problem::EvaluateOptions options;
  options.num_threads = threads;
  double cost = 0.0;
  if (!problem.Evaluate(options, &cost, nullptr, nullptr, nullptr)) return NAN;
  return 2.0 * cost;  // Ceres's cost is half the sum of squares
}

// The step -N^-1 g through the reduction; false if the reduced normals of the
// free globals are not safely positive definite.
bool ComputeStep(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals, Step* step) {
  std::vector<int> free;
  for (const AdjustmentBlock& b : impl.blocks) {
    if (b.kind == BlockKind::kPoint) continue;
    for (int i = 0; i < static_cast<int>(b.names.size()); ++i) {
      if (!b.IsFixed(i)) free.push_back(b.global_offset + i);
    }
  }
  const int n = static_cast<int>(free.size());
  Eigen::MatrixXd n_ff(n, n);
  Eigen::VectorXd b_f(n);
  for (int i = 0; i < n; ++i) {
    b_f[i] = normals.b_g[free[i]];
    for (int j = 0; j < n; ++j) n_ff(i, j) = normals.n_gg(free[i], free[j]);
  }
  // Unit-diagonal scaling: the globals mix mm, rad and metres.
  const Eigen::VectorXd scale = n_ff.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * n_ff * scale.asDiagonal();
  const Eigen::LLT<Eigen::MatrixXd> llt(scaled);
  if (llt.info() != Eigen::Success || !(llt.rcond() > kMinReciprocalCondition)) return false;
  const Eigen::VectorXd scaled_b = scale.cwiseProduct(b_f);
  const Eigen::VectorXd scaled_step = -llt.solve(scaled_b);
  step->predicted_decrease = -scaled_b.dot(scaled_step);
  step->globals = Eigen::VectorXd::Zero(impl.num_global);
  for (int i = 0; i < n; ++i) step->globals[free[i]] = scale[i] * scaled_step[i];
  step->points.assign(normals.points.size(), Eigen::Vector3d::Zero());
  for (size_t p = 0; p < normals.points.size(); ++p) {
    const PointNormals& point = normals.points[p];
    if (point.block < 0) continue;
    Eigen::Vector3d rhs = point.b_p;
    for (const auto& [block, n_pb] : point.n_pb) {
      rhs.noalias() += n_pb * step->globals.segment(impl.blocks[block].global_offset, n_pb.cols());
    }
    step->points[p] = -point.n_pp_inverse * rhs;
    step->predicted_decrease += point.b_p.dot(point.n_pp_inverse * point.b_p);
  }
  return std::isfinite(step->predicted_decrease) && step->predicted_decrease >= 0.0;
}

// values += t * step over the free parameters.
void Apply(const Step& step, double t, AdjustmentProblem::Impl* impl) {
  for (AdjustmentBlock& b : impl->blocks) {
    const int size = static_cast<int>(b.names.size());
    for (int i = 0; i < size; ++i) {
      if (b.IsFixed(i)) continue;
      b.values[i] += t * (b.kind == BlockKind::kPoint ? step.points[b.point_index][i]
                                                      : step.globals[b.global_offset + i]);
    }
  }
}

}  // namespace

GaussNewtonOutcome SolveByReducedNormals(AdjustmentProblem::Impl& impl, ceres::Problem& problem,
                                         const AdjustmentOptions& options, const AdjustmentProgress& progress) {
  GaussNewtonOutcome out;
  if (impl.gauge_is_datum) {
    out.message = "a free network's gauge freedom: left to the trust region";
    return out;
  }
  const int threads = options.num_threads > 0 ? options.num_threads
                                              : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  double vtpv = Cost(problem, threads);
  if (!std::isfinite(vtpv)) {
    out.message = "the model cannot be evaluated at the starting values";
    return out;
  }
  int polish_steps = 0;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    if (progress) progress("weighted pass", std::min(1.0, double(iteration) / options.max_iterations));
    ReducedNormals normals = BuildReducedNormals(impl);
    Step step;
    if (!ComputeStep(impl, normals, &step)) {
      out.message = "the reduced normal equations are singular or nearly so: left to the trust region";
      return out;
    }
    // Converged: the quadratic model promises less than the tolerance, or a
    // reference solution has taken its full steps in the round-off regime
    // (the tolerance would stop it at ~1e-6 sigma: 1e-16 of v'Pv).
    // The normals are those of the final values (the covariance's).
    const bool round_off_regime = step.predicted_decrease <= 1e-6 * vtpv;
    polish_steps += options.polish && round_off_regime ? 1 : 0;
    const bool converged = options.polish ? polish_steps > kPolishSteps || step.predicted_decrease == 0.0
                                          : step.predicted_decrease <= options.function_tolerance * vtpv;
    if (converged) {
      out.ok = out.converged = true;
      out.normals = std::move(normals);
      return out;
    }
    out.iterations = iteration;
    if (options.polish && round_off_regime) {
      // v'Pv no longer tells better from worse (its round-off): a reference
      // solution trusts the model's full step (AdjustmentOptions::polish).
      Apply(step, 1.0, &impl);
      vtpv = Cost(problem, threads);
      continue;
    }
    // Take the step, halving it while v'Pv does not decrease.
    double t = 1.0, applied = 0.0, new_vtpv = NAN;
    for (int halving = 0; halving <= kMaxStepHalvings; ++halving, t *= 0.5) {
      Apply(step, t - applied, &impl);
      applied = t;
      new_vtpv = Cost(problem, threads);
      if (new_vtpv <= vtpv) break;
    }
    if (!(new_vtpv <= vtpv)) {
      Apply(step, -applied, &impl);  // back where the step started
      // No descent along a step that predicts almost none: the minimum to round-off.
      out.ok = out.converged = round_off_regime;
      if (out.ok) out.normals = std::move(normals);
      else out.message = "a Gauss-Newton step found no descent: left to the trust region";
      return out;
    }
    vtpv = new_vtpv;
  }
  out.ok = true;
  out.message = fmt::format("Gauss-Newton stopped after {} iterations", options.max_iterations);
  return out;
}

}  // namespace platemeter
