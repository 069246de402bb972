// Building an adjustment (adjustment.h): blocks, states, priors, observations.
#include <fmt/format.h>

#include "adjustment_internal.h"
#include "platemeter/core/error.h"

namespace platemeter {

AdjustmentProblem::AdjustmentProblem() : impl_(std::make_unique<Impl>()) {}
AdjustmentProblem::~AdjustmentProblem() = default;

int AdjustmentProblem::AddBlock(const std::string& label, const std::string& group, BlockKind kind,
                                const std::vector<std::string>& names, const std::vector<double>& values) {
  if (names.size() != values.size() || names.empty()) {
    throw Error("adjustment", fmt::format("block '{}': {} names for {} values", label, names.size(), values.size()));
  }
  if (kind == BlockKind::kPoint && names.size() > 3) {
    throw Error("adjustment", fmt::format("point block '{}' must have 1 to 3 parameters", label));
  }
  for (double v : values) {
    if (!std::isfinite(v)) throw Error("adjustment", fmt::format("block '{}' has a non-finite value", label));
  }
  AdjustmentBlock block;
  block.label = label;
  block.group = group;
  block.kind = kind;
  block.names = names;
  block.values = values;
  block.initial = values;
  block.states.assign(names.size(), ParameterState::Free());
  block.has_prior.assign(names.size(), false);
  if (kind == BlockKind::kPoint) {
    block.point_index = impl_->num_points++;
  } else {
    block.global_offset = impl_->num_global;
    impl_->num_global += static_cast<int>(names.size());
  }
  impl_->blocks.push_back(std::move(block));
  return static_cast<int>(impl_->blocks.size()) - 1;
}

void AdjustmentProblem::SetState(int block, int index, const ParameterState& state) {
  AdjustmentBlock& b = impl_->blocks.at(block);
  if (index < 0 || index >= static_cast<int>(b.names.size())) {
    throw Error("adjustment", fmt::format("block '{}' has no parameter {}", b.label, index));
  }
  if (state.kind == ParameterState::Kind::kWeighted) {
    if (!(state.sigma > 0.0) || !std::isfinite(state.sigma)) {
      throw Error("adjustment", fmt::format("{} {}: a prior sigma must be positive", b.label, b.names[index]));
    }
    b.states[index] = state;
    AddPrior(block, {index}, Eigen::VectorXd::Constant(1, b.initial[index]),
             Eigen::MatrixXd::Constant(1, 1, state.sigma * state.sigma),
             fmt::format("{} {}", b.label, b.names[index]));
    return;
  }
  b.states[index] = state;
}

void AdjustmentProblem::AddPrior(int block, const std::vector<int>& indices, const Eigen::VectorXd& values,
                                 const Eigen::MatrixXd& covariance, const std::string& label) {
  AdjustmentBlock& b = impl_->blocks.at(block);
  if (static_cast<int>(indices.size()) != values.size() || covariance.rows() != values.size()) {
    throw Error("adjustment", fmt::format("prior '{}': sizes do not agree", label));
  }
  for (int i : indices) {
    if (i < 0 || i >= static_cast<int>(b.names.size())) {
      throw Error("adjustment", fmt::format("prior '{}': block '{}' has no parameter {}", label, b.label, i));
    }
    b.has_prior[i] = true;
    if (b.states[i].kind == ParameterState::Kind::kFree) b.states[i] = ParameterState::Weighted(0.0);
  }
  AdjustmentEquation equation;
  equation.cost = std::make_unique<PriorCost>(static_cast<int>(b.names.size()), indices, values,
                                              covariance);
  equation.blocks = {block};
  equation.is_prior = true;
  equation.label = label;
  equation.group = "prior";
  equation.item = label;
  impl_->equations.push_back(std::move(equation));
}

int AdjustmentProblem::AddObservation(ceres::CostFunction* cost, const std::vector<int>& blocks,
                                      const Eigen::MatrixXd& covariance, const std::string& group,
                                      const std::string& item, const std::string& origin) {
  std::unique_ptr<ceres::CostFunction> owned(cost);
  if (cost->parameter_block_sizes().size() != blocks.size()) {
    throw Error("adjustment", "an observation's cost names a different number of blocks");
  }
  int points = 0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const AdjustmentBlock& b = impl_->blocks.at(blocks[i]);
    if (cost->parameter_block_sizes()[i] != static_cast<int>(b.names.size())) {
      throw Error("adjustment", fmt::format("an observation's cost has the wrong size for block '{}'", b.label));
    }
    if (b.kind == BlockKind::kPoint) ++points;
  }
  // Seed 000's reduction eliminates each point on its own: an equation may
  // touch at most one point block.
  if (points > 1) throw Error("adjustment", "an observation may involve at most one point block");
  if (covariance.rows() != cost->num_residuals()) {
    throw Error("adjustment", "an observation's covariance does not match its residual count");
  }
  AdjustmentEquation equation;
  equation.cost = std::make_unique<WhitenedCost>(owned.release(),
                                                 SqrtInformation(covariance, origin.empty() ? item : origin));
  equation.blocks = blocks;
  equation.group = group;
  equation.item = item;
  equation.origin = origin;
  impl_->equations.push_back(std::move(equation));
  impl_->observation_equation.push_back(static_cast<int>(impl_->equations.size()) - 1);
  return static_cast<int>(impl_->observation_equation.size()) - 1;
}

void AdjustmentProblem::ReserveObservations(size_t count) {
  impl_->equations.reserve(impl_->equations.size() + count);
  impl_->observation_equation.reserve(impl_->observation_equation.size() + count);
}

void AdjustmentProblem::SetGauge(const Eigen::MatrixXd& basis, const std::vector<std::string>& names,
                                 const std::vector<bool>& trace_rows, bool is_datum) {
  if (basis.rows() != impl_->num_global || static_cast<int>(trace_rows.size()) != impl_->num_global ||
      static_cast<int>(names.size()) != basis.cols()) {
    throw Error("adjustment", "the gauge basis must have one row per non-point parameter and a name per column");
  }
  impl_->gauge = basis;
  impl_->gauge_names = names;
  impl_->gauge_trace_rows = trace_rows;
  impl_->gauge_is_datum = is_datum;
}

int AdjustmentProblem::NumBlocks() const { return static_cast<int>(impl_->blocks.size()); }
int AdjustmentProblem::BlockSize(int block) const {
  return static_cast<int>(impl_->blocks.at(block).names.size());
}
const std::vector<double>& AdjustmentProblem::Values(int block) const { return impl_->blocks.at(block).values; }
double* AdjustmentProblem::MutableValues(int block) { return impl_->blocks.at(block).values.data(); }
int AdjustmentProblem::GlobalOffset(int block) const { return impl_->blocks.at(block).global_offset; }
int AdjustmentProblem::NumGlobalParameters() const { return impl_->num_global; }

bool AdjustmentOptions::Check(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (!(robust_loss_scale >= 0.0)) return fail("robust_loss_scale must be 0 (none) or positive");
  if (!(rejection_threshold >= 0.0)) return fail("rejection_threshold must be 0 (from false_rejection_rate) or positive");
  if (!(false_rejection_rate > 0.0 && false_rejection_rate < 0.5)) return fail("false_rejection_rate must be in (0, 0.5)");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!(function_tolerance > 0.0)) return fail("function_tolerance must be positive");
  if (!(parameter_tolerance > 0.0)) return fail("parameter_tolerance must be positive");
  if (!(correlation_threshold > 0.0 && correlation_threshold <= 1.0)) {
    return fail("correlation_threshold must be in (0, 1]");
  }
  if (!(significance_level > 0.0 && significance_level < 0.5)) return fail("significance_level must be in (0, 0.5)");
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1e-3)) return fail("rank_tolerance must be in (0, 1e-3)");
  if (!(weak_tolerance >= rank_tolerance && weak_tolerance < 1.0)) {
    return fail("weak_tolerance must be in [rank_tolerance, 1)");
  }
  if (num_threads < 0) return fail("num_threads must be 0 (every core) or positive");
  return true;
}

const char* EstimateStatusName(EstimateStatus status) {
  switch (status) {
    case EstimateStatus::kFree: return "free";
    case EstimateStatus::kWeighted: return "weighted";
    case EstimateStatus::kFixed: return "fixed";
    case EstimateStatus::kNotEstimable: return "not-estimable";
  }
  return "?";
}

}  // namespace platemeter
