// The normal equations reduced by eliminating each point block (seed 000
// section 2.2: "elimination of the ground points so as to form the reduced
// normal equations"), from the whitened Jacobians at the solution.
#include <algorithm>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "adjustment_internal.h"

namespace platemeter {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Pseudo-inverse of a point's 3x3 normal block over its free coordinates;
// returns the number of coordinates it determines.
int PointInverse(const AdjustmentBlock& block, const Eigen::Matrix3d& n_pp, Eigen::Matrix3d* inverse) {
  std::vector<int> free;
  for (int i = 0; i < 3; ++i) {
    if (!block.IsFixed(i)) free.push_back(i);
  }
  inverse->setZero();
  const int k = static_cast<int>(free.size());
  if (k == 0) return 0;
  Eigen::MatrixXd sub(k, k);
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) sub(i, j) = n_pp(free[i], free[j]);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(sub);
  const Eigen::VectorXd& lambda = eigen.eigenvalues();
  const double largest = lambda.maxCoeff();
  if (!(largest > 0.0)) return 0;
  int rank = 0;
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < k; ++i) {
    if (lambda[i] > 1e-10 * largest) {
      pinv += eigen.eigenvectors().col(i) * eigen.eigenvectors().col(i).transpose() / lambda[i];
      ++rank;
    }
  }
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) (*inverse)(free[i], free[j]) = pinv(i, j);
  }
  return rank;
}

// One equation's whitened residual and Jacobians (fixed columns zeroed).
struct EvaluatedEquation {
  std::vector<RowMajor> jacobians;
  Eigen::VectorXd residual;
  int point_slot = -1;  // which block is the point, -1 if none
  // Reused from equation to equation: no allocation per observation.
  std::vector<double*> jacobian_pointers;
  std::vector<const double*> parameters;
};

bool Evaluate(const AdjustmentProblem::Impl& impl, const AdjustmentEquation& e, EvaluatedEquation* out) {
  const size_t n = e.blocks.size();
  out->jacobians.resize(n);
  out->jacobian_pointers.resize(n);
  out->parameters.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const AdjustmentBlock& block = impl.blocks[e.blocks[i]];
    out->jacobians[i].resize(e.Dimension(), block.names.size());
    out->jacobian_pointers[i] = out->jacobians[i].data();
    out->parameters[i] = block.values.data();
  }
  out->residual.resize(e.Dimension());
  if (!e.cost->Evaluate(out->parameters.data(), out->residual.data(), out->jacobian_pointers.data())) return false;
  out->point_slot = -1;
  for (size_t i = 0; i < n; ++i) {
    const AdjustmentBlock& block = impl.blocks[e.blocks[i]];
    for (int c = 0; c < static_cast<int>(block.names.size()); ++c) {
      if (block.IsFixed(c)) out->jacobians[i].col(c).setZero();
    }
    if (block.kind == BlockKind::kPoint) {
      out->point_slot = static_cast<int>(i);
      if (block.names.size() < 3) {  // padded to 3 columns (fixed, zero), as PointNormals holds 3 x 3
        RowMajor padded = RowMajor::Zero(e.Dimension(), 3);
        padded.leftCols(block.names.size()) = out->jacobians[i];
        out->jacobians[i] = std::move(padded);
      }
    }
  }
  return true;
}

// What one thread accumulates: the reduced matrix and the sums.
struct Accumulator {
  Eigen::MatrixXd n_gg;
  Eigen::VectorXd b_g;
  double vtpv = 0.0;
  long observation_rows = 0, prior_rows = 0;
};

// J_a^T J_b of every pair of non-point blocks of the equation, into the lower
// triangle of N_gg only (the upper one is mirrored at the end: half the
// memory traffic on a reduced matrix of a few megabytes per thread).
void AddGlobalTerms(const AdjustmentProblem::Impl& impl, const AdjustmentEquation& e, const EvaluatedEquation& x,
                    Accumulator* sum) {
  sum->vtpv += x.residual.squaredNorm();
  (e.is_prior ? sum->prior_rows : sum->observation_rows) += e.Dimension();
  for (size_t i = 0; i < e.blocks.size(); ++i) {
    const AdjustmentBlock& a = impl.blocks[e.blocks[i]];
    if (a.kind == BlockKind::kPoint) continue;
    for (size_t j = 0; j < e.blocks.size(); ++j) {
      const AdjustmentBlock& b = impl.blocks[e.blocks[j]];
      if (b.kind == BlockKind::kPoint || a.global_offset < b.global_offset) continue;
      sum->n_gg.block(a.global_offset, b.global_offset, a.names.size(), b.names.size()).noalias() +=
          x.jacobians[i].transpose() * x.jacobians[j];
    }
    sum->b_g.segment(a.global_offset, a.names.size()).noalias() += x.jacobians[i].transpose() * x.residual;
  }
}

// N_gg's block at (row, col) -= left^T right, left and right the 3-row column
// ranges of the point's stacked blocks. Nearly every block of a bundle is a
// frame's 6 x 6: those at fixed size, unrolled (20 000 points touch 4.6
// million of them).
void SubtractProduct(const Eigen::MatrixXd& left_stack, int left_col, int rows, const Eigen::MatrixXd& right_stack,
                     int right_col, int cols, int row, int col, Eigen::MatrixXd* n_gg) {
  if (rows == 6 && cols == 6) {
    Eigen::Map<Eigen::Matrix<double, 6, 6>, 0, Eigen::OuterStride<>> target(&(*n_gg)(row, col),
                                                                           Eigen::OuterStride<>(n_gg->outerStride()));
    const Eigen::Map<const Eigen::Matrix<double, 3, 6>> left(left_stack.data() + 3 * left_col);
    const Eigen::Map<const Eigen::Matrix<double, 3, 6>> right(right_stack.data() + 3 * right_col);
    target.noalias() -= left.transpose() * right;
    return;
  }
  n_gg->block(row, col, rows, cols).noalias() -=
      left_stack.middleCols(left_col, rows).transpose() * right_stack.middleCols(right_col, cols);
}

// A point's own normal blocks from its equations, then its elimination:
// N_gg -= N_gp N_pp^-1 N_pg, its blocks stacked so the product is one product.
void ReducePoint(const AdjustmentProblem::Impl& impl, const std::vector<int>& equations, PointNormals* point,
                 Accumulator* sum) {
  EvaluatedEquation x;
  for (int index : equations) {
    const AdjustmentEquation& e = impl.equations[index];
    if (!Evaluate(impl, e, &x)) continue;
    AddGlobalTerms(impl, e, x, sum);
    const RowMajor& jp = x.jacobians[x.point_slot];
    point->n_pp.noalias() += jp.transpose() * jp;
    point->b_p.noalias() += jp.transpose() * x.residual;
    if (!e.is_prior) ++point->rays;
    for (size_t i = 0; i < e.blocks.size(); ++i) {
      if (static_cast<int>(i) == x.point_slot) continue;
      const int block = e.blocks[i];
      auto it = std::find_if(point->n_pb.begin(), point->n_pb.end(), [&](const auto& p) { return p.first == block; });
      if (it == point->n_pb.end()) {
        point->n_pb.emplace_back(block, Eigen::MatrixXd::Zero(3, x.jacobians[i].cols()));
        it = point->n_pb.end() - 1;
      }
      it->second.noalias() += jp.transpose() * x.jacobians[i];
    }
  }
  point->rank = PointInverse(impl.blocks[point->block], point->n_pp, &point->n_pp_inverse);
  int m = 0;
  for (const auto& [b, n_pb] : point->n_pb) m += static_cast<int>(n_pb.cols());
  Eigen::MatrixXd stack(3, m);
  m = 0;
  for (const auto& [b, n_pb] : point->n_pb) {
    stack.middleCols(m, n_pb.cols()) = n_pb;
    m += static_cast<int>(n_pb.cols());
  }
  // The lower triangle's blocks of N_gp N_pp^-1 N_pg (see AddGlobalTerms),
  // and b_g -= N_gp N_pp^-1 b_p.
  const Eigen::MatrixXd inverse_times_stack = point->n_pp_inverse * stack;
  const Eigen::Vector3d inverse_times_b = point->n_pp_inverse * point->b_p;
  for (const auto& [a_block, n_pa] : point->n_pb) {
    const AdjustmentBlock& a = impl.blocks[a_block];
    sum->b_g.segment(a.global_offset, a.names.size()).noalias() -= n_pa.transpose() * inverse_times_b;
  }
  int row = 0;
  for (const auto& [a_block, n_pa] : point->n_pb) {
    const AdjustmentBlock& a = impl.blocks[a_block];
    int col = 0;
    for (const auto& [b_block, n_pb] : point->n_pb) {
      const AdjustmentBlock& b = impl.blocks[b_block];
      if (a.global_offset >= b.global_offset) {
        SubtractProduct(stack, row, static_cast<int>(a.names.size()), inverse_times_stack, col,
                        static_cast<int>(b.names.size()), a.global_offset, b.global_offset, &sum->n_gg);
      }
      col += static_cast<int>(b.names.size());
    }
    row += static_cast<int>(a.names.size());
  }
}

}  // namespace

ReducedNormals BuildReducedNormals(const AdjustmentProblem::Impl& impl) {
  ReducedNormals normals;
  normals.points.resize(impl.num_points);
  std::vector<std::vector<int>> point_equations(impl.num_points);
  std::vector<int> other_equations;
  for (size_t b = 0; b < impl.blocks.size(); ++b) {
    if (impl.blocks[b].kind == BlockKind::kPoint) normals.points[impl.blocks[b].point_index].block = static_cast<int>(b);
  }
  for (size_t k = 0; k < impl.equations.size(); ++k) {
    const AdjustmentEquation& e = impl.equations[k];
    if (e.status != ObservationStatus::kUsed) continue;
    int point = -1;
    for (int b : e.blocks) {
      if (impl.blocks[b].kind == BlockKind::kPoint) point = impl.blocks[b].point_index;
    }
    (point >= 0 ? point_equations[point] : other_equations).push_back(static_cast<int>(k));
  }
  // Points in parallel, each thread with its own reduced matrix, summed at the end.
  tbb::enumerable_thread_specific<Accumulator> sums([&] {
    Accumulator a;
    a.n_gg = Eigen::MatrixXd::Zero(impl.num_global, impl.num_global);
    a.b_g = Eigen::VectorXd::Zero(impl.num_global);
    return a;
  });
  tbb::parallel_for(tbb::blocked_range<int>(0, impl.num_points, 64), [&](const tbb::blocked_range<int>& range) {
    Accumulator& sum = sums.local();
    for (int p = range.begin(); p < range.end(); ++p) {
      if (normals.points[p].block >= 0) ReducePoint(impl, point_equations[p], &normals.points[p], &sum);
    }
  });
  Accumulator total;
  total.n_gg = Eigen::MatrixXd::Zero(impl.num_global, impl.num_global);
  total.b_g = Eigen::VectorXd::Zero(impl.num_global);
  EvaluatedEquation x;
  for (int index : other_equations) {
    if (Evaluate(impl, impl.equations[index], &x)) AddGlobalTerms(impl, impl.equations[index], x, &total);
  }
  for (const Accumulator& sum : sums) {
    total.n_gg += sum.n_gg;
    total.b_g += sum.b_g;
    total.vtpv += sum.vtpv;
    total.observation_rows += sum.observation_rows;
    total.prior_rows += sum.prior_rows;
  }
  for (Eigen::Index j = 1; j < total.n_gg.cols(); ++j) {  // the upper triangle from the lower
    for (Eigen::Index i = 0; i < j; ++i) total.n_gg(i, j) = total.n_gg(j, i);
  }
  normals.n_gg = std::move(total.n_gg);
  normals.b_g = std::move(total.b_g);
  normals.vtpv = total.vtpv;
  normals.observation_rows = total.observation_rows;
  normals.prior_rows = total.prior_rows;
  return normals;
}

}  // namespace platemeter
