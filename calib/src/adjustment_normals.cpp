// The normal equations reduced by eliminating each point block (seed 000
// section 2.2: "elimination of the ground points so as to form the reduced
// normal equations"), from the whitened Jacobians at the solution.
#include <Eigen/Eigenvalues>

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

}  // namespace

ReducedNormals BuildReducedNormals(const AdjustmentProblem::Impl& impl) {
  ReducedNormals normals;
  normals.n_gg = Eigen::MatrixXd::Zero(impl.num_global, impl.num_global);
  normals.points.resize(impl.num_points);
  for (size_t b = 0; b < impl.blocks.size(); ++b) {
    if (impl.blocks[b].kind == BlockKind::kPoint) normals.points[impl.blocks[b].point_index].block = static_cast<int>(b);
  }
  std::vector<RowMajor> jacobians;
  std::vector<double*> jacobian_pointers;
  std::vector<const double*> parameters;
  Eigen::VectorXd residual;
  for (const AdjustmentEquation& e : impl.equations) {
    if (e.status != ObservationStatus::kUsed) continue;
    const int d = e.Dimension();
    const size_t n = e.blocks.size();
    jacobians.resize(n);
    jacobian_pointers.resize(n);
    parameters.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const AdjustmentBlock& block = impl.blocks[e.blocks[i]];
      jacobians[i].resize(d, block.names.size());
      jacobian_pointers[i] = jacobians[i].data();
      parameters[i] = block.values.data();
    }
    residual.resize(d);
    if (!e.cost->Evaluate(parameters.data(), residual.data(), jacobian_pointers.data())) continue;
    normals.vtpv += residual.squaredNorm();
    (e.is_prior ? normals.prior_rows : normals.observation_rows) += d;
    int point_slot = -1;
    for (size_t i = 0; i < n; ++i) {
      const AdjustmentBlock& block = impl.blocks[e.blocks[i]];
      for (int c = 0; c < static_cast<int>(block.names.size()); ++c) {
        if (block.IsFixed(c)) jacobians[i].col(c).setZero();
      }
      if (block.kind == BlockKind::kPoint) point_slot = static_cast<int>(i);
    }
    for (size_t i = 0; i < n; ++i) {
      const AdjustmentBlock& a = impl.blocks[e.blocks[i]];
      if (a.kind == BlockKind::kPoint) continue;
      for (size_t j = 0; j < n; ++j) {
        const AdjustmentBlock& b = impl.blocks[e.blocks[j]];
        if (b.kind == BlockKind::kPoint) continue;
        normals.n_gg.block(a.global_offset, b.global_offset, a.names.size(), b.names.size()).noalias() +=
            jacobians[i].transpose() * jacobians[j];
      }
    }
    if (point_slot < 0) continue;
    PointNormals& point = normals.points[impl.blocks[e.blocks[point_slot]].point_index];
    const RowMajor& jp = jacobians[point_slot];
    point.n_pp.noalias() += jp.transpose() * jp;
    if (!e.is_prior) ++point.rays;
    for (size_t i = 0; i < n; ++i) {
      if (static_cast<int>(i) == point_slot) continue;
      const int block = e.blocks[i];
      auto it = std::find_if(point.n_pb.begin(), point.n_pb.end(), [&](const auto& p) { return p.first == block; });
      if (it == point.n_pb.end()) {
        point.n_pb.emplace_back(block, Eigen::MatrixXd::Zero(3, jacobians[i].cols()));
        it = point.n_pb.end() - 1;
      }
      it->second.noalias() += jp.transpose() * jacobians[i];
    }
  }
  // Eliminate each point: N_gg -= N_gp N_pp^-1 N_pg, with the point's blocks
  // stacked into one 3 x m matrix so that the product is one dense product.
  for (PointNormals& point : normals.points) {
    if (point.block < 0) continue;
    point.rank = PointInverse(impl.blocks[point.block], point.n_pp, &point.n_pp_inverse);
    int m = 0;
    for (const auto& [b, n_pb] : point.n_pb) m += static_cast<int>(n_pb.cols());
    Eigen::MatrixXd stack(3, m);
    m = 0;
    for (const auto& [b, n_pb] : point.n_pb) {
      stack.middleCols(m, n_pb.cols()) = n_pb;
      m += static_cast<int>(n_pb.cols());
    }
    const Eigen::MatrixXd product = stack.transpose() * (point.n_pp_inverse * stack);
    int row = 0;
    for (const auto& [a_block, n_pa] : point.n_pb) {
      const AdjustmentBlock& a = impl.blocks[a_block];
      int col = 0;
      for (const auto& [b_block, n_pb] : point.n_pb) {
        const AdjustmentBlock& b = impl.blocks[b_block];
        normals.n_gg.block(a.global_offset, b.global_offset, a.names.size(), b.names.size()) -=
            product.block(row, col, a.names.size(), b.names.size());
        col += static_cast<int>(b.names.size());
      }
      row += static_cast<int>(a.names.size());
    }
  }
  return normals;
}

}  // namespace platemeter
