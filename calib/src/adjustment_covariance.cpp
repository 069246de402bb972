// Covariance and rank of the reduced normal equations (adjustment.h): the
// diagonally scaled matrix's eigen-decomposition gives the numerical rank,
// the (near-)null space named in parameter words, and a pseudo-inverse that
// is the covariance of every estimable parameter; a free network's datum is
// applied by an S-transformation to minimum trace over the chosen rows.
#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <fmt/format.h>

#include "adjustment_internal.h"
#include "symmetric_eigen.h"

namespace platemeter {
namespace {

// Which words a parameter contributes to: "c_mm" when its group has one
// block, else "the frames' X_m" (or "frame 9515 X_m" when one block holds it).
struct ParameterWords {
  std::string single;  // block label + name
  std::string group;   // the group's plural + name, or the name alone for a one-block group
};

std::vector<ParameterWords> WordsOf(const AdjustmentProblem::Impl& impl, const std::vector<int>& free_cols) {
  std::map<std::string, int> blocks_in_group;
  for (const AdjustmentBlock& b : impl.blocks) {
    if (b.kind != BlockKind::kPoint) ++blocks_in_group[b.group];
  }
  std::vector<ParameterWords> words(impl.num_global);
  for (const AdjustmentBlock& b : impl.blocks) {
    if (b.kind == BlockKind::kPoint) continue;
    for (size_t i = 0; i < b.names.size(); ++i) {
      ParameterWords& w = words[b.global_offset + i];
      w.single = blocks_in_group[b.group] == 1 ? b.names[i] : b.label + " " + b.names[i];
      w.group = blocks_in_group[b.group] == 1 ? b.names[i] : "the " + b.group + "s' " + b.names[i];
    }
  }
  std::vector<ParameterWords> out;
  for (int c : free_cols) out.push_back(words[c]);
  return out;
}

// A unit direction in the scaled parameter space, in words: the shares of its
// squared components by parameter group, the largest first.
NullDirection Describe(const Eigen::VectorXd& direction, const std::vector<ParameterWords>& words) {
  std::map<std::string, double> by_group;
  std::map<std::string, std::map<std::string, double>> singles;
  for (int i = 0; i < direction.size(); ++i) {
    const double share = direction[i] * direction[i];
    by_group[words[i].group] += share;
    singles[words[i].group][words[i].single] += share;
  }
  NullDirection out;
  for (const auto& [group, share] : by_group) {
    std::string name = group;
    for (const auto& [single, s] : singles[group]) {
      if (s > 0.8 * share) name = single;  // one block carries it: name that block
    }
    out.shares.emplace_back(name, share);
  }
  std::sort(out.shares.begin(), out.shares.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  for (size_t i = 0; i < out.shares.size() && i < 5; ++i) {
    if (out.shares[i].second < 0.05) break;
    if (i > 0) out.words += " with ";
    out.words += fmt::format("{} ({:.0f} %)", out.shares[i].first, 100.0 * out.shares[i].second);
  }
  return out;
}

// Every non-point parameter into the result, in block order (index == global
// column); returns the columns of the adjusted (not fixed) ones.
std::vector<int> CollectParameters(const AdjustmentProblem::Impl& impl, AdjustmentResult* result) {
  std::vector<int> free_cols;
  for (const AdjustmentBlock& b : impl.blocks) {
    if (b.kind == BlockKind::kPoint) continue;
    for (size_t i = 0; i < b.names.size(); ++i) {
      ParameterEstimate p;
      p.block = b.label;
      p.group = b.group;
      p.name = b.names[i];
      p.value = b.values[i];
      p.initial = b.initial[i];
      const ParameterState& state = b.states[i];
      p.status = state.kind == ParameterState::Kind::kFixed ? EstimateStatus::kFixed
                 : b.has_prior[i]                           ? EstimateStatus::kWeighted
                                                            : EstimateStatus::kFree;
      if (state.kind == ParameterState::Kind::kWeighted && state.sigma > 0.0) p.prior_sigma = state.sigma;
      if (p.status != EstimateStatus::kFixed) free_cols.push_back(b.global_offset + static_cast<int>(i));
      result->parameters.push_back(std::move(p));
    }
  }
  return free_cols;
}

// The reduced matrix scaled to unit diagonal, S = D^-1/2 N D^-1/2, its
// eigenvalues, and what the report and the cofactor need of the rest: with no
// null direction S^-1 (Cholesky) and the eigenvectors of the weak directions
// only; with null directions every eigenvector (the pseudo-inverse). On a
// 1202-parameter block the first is 0.5 s, the full decomposition 1 s.
struct ScaledDecomposition {
  Eigen::VectorXd inv_sqrt_d;  // D^-1/2 (1 for untouched parameters)
  Eigen::VectorXd lambda;      // ascending
  Eigen::MatrixXd vectors;     // eigenvectors of lambda[0 .. vectors.cols() - 1]: the null and weak ones, or all
  Eigen::MatrixXd scaled_inverse;  // S^-1 when S has no null direction, else empty
  double lambda_max = 0.0;
  std::vector<int> null_cols, weak_cols;
};

// Null (below rank_tolerance) and weak (below weak_tolerance) eigenvalues, the rank and the condition number.
void Classify(const AdjustmentOptions& options, ScaledDecomposition* d, RankReport* rank) {
  const int n = static_cast<int>(d->lambda.size());
  d->null_cols.clear();
  d->weak_cols.clear();
  d->lambda_max = std::max(d->lambda[n - 1], 1e-300);
  double smallest_kept = d->lambda_max;
  for (int i = 0; i < n; ++i) {
    if (d->lambda[i] <= options.rank_tolerance * d->lambda_max) {
      d->null_cols.push_back(i);
    } else {
      smallest_kept = std::min(smallest_kept, d->lambda[i]);
      if (d->lambda[i] <= options.weak_tolerance * d->lambda_max) d->weak_cols.push_back(i);
    }
  }
  rank->numerical_rank = n - static_cast<int>(d->null_cols.size());
  rank->condition_number = d->lambda_max / smallest_kept;
}

ScaledDecomposition Decompose(const ReducedNormals& normals, const std::vector<int>& free_cols,
                              const std::vector<ParameterWords>& words, const AdjustmentOptions& options,
                              RankReport* rank) {
  const int n = static_cast<int>(free_cols.size());
  Eigen::MatrixXd N(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) N(i, j) = normals.n_gg(free_cols[i], free_cols[j]);
  }
  ScaledDecomposition d;
  d.inv_sqrt_d.resize(n);
  const double largest_diagonal = N.diagonal().maxCoeff();
  rank->structural_rank = n;
  for (int i = 0; i < n; ++i) {
    if (!(N(i, i) > 1e-300 * std::max(1.0, largest_diagonal))) {
      rank->untouched.push_back(words[i].single);
      --rank->structural_rank;
      d.inv_sqrt_d[i] = 1.0;
    } else {
      d.inv_sqrt_d[i] = 1.0 / std::sqrt(N(i, i));
    }
  }
  const Eigen::MatrixXd S = d.inv_sqrt_d.asDiagonal() * N * d.inv_sqrt_d.asDiagonal();
  const SymmetricEigenproblem eigen(S);
  d.lambda = eigen.Eigenvalues();
  Classify(options, &d, rank);
  const int lowest = static_cast<int>(d.null_cols.size() + d.weak_cols.size());
  if (d.null_cols.empty() && InverseOfPositiveDefinite(S, &d.scaled_inverse) &&
      eigen.LowestEigenvectors(lowest, &d.vectors)) {
    return d;
  }
  d.scaled_inverse.resize(0, 0);
  eigen.All(&d.lambda, &d.vectors);
  Classify(options, &d, rank);
  return d;
}

// Splits the null space into the datum's gauge (a free network's choice) and
// true defects, names every defect and weak direction in the rank report, and
// returns the defects (columns, scaled space).
Eigen::MatrixXd NameNullSpace(const AdjustmentProblem::Impl& impl, const std::vector<int>& free_cols,
                              const std::vector<ParameterWords>& words, const ScaledDecomposition& d,
                              RankReport* rank, bool* apply_inner_constraints) {
  const int n = static_cast<int>(free_cols.size());
  Eigen::MatrixXd V0(n, d.null_cols.size());
  for (size_t k = 0; k < d.null_cols.size(); ++k) V0.col(k) = d.vectors.col(d.null_cols[k]);
  Eigen::MatrixXd G;            // gauge rows of the free parameters, in the scaled space
  Eigen::MatrixXd gauge_basis;  // orthonormal basis of span(G)
  Eigen::MatrixXd defects = V0;
  if (impl.gauge.size() > 0) {
    G.resize(n, impl.gauge.cols());
    for (int i = 0; i < n; ++i) G.row(i) = impl.gauge.row(free_cols[i]) / d.inv_sqrt_d[i];
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(G);
    qr.setThreshold(1e-9);
    gauge_basis = Eigen::MatrixXd(qr.householderQ()).leftCols(qr.rank());
  }
  if (impl.gauge_is_datum && V0.cols() > 0) {
    const Eigen::MatrixXd outside = V0 - gauge_basis * (gauge_basis.transpose() * V0);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(outside, Eigen::ComputeThinU);
    int count = 0;
    for (int k = 0; k < svd.singularValues().size(); ++k) count += svd.singularValues()[k] > 0.5 ? 1 : 0;
    defects = svd.matrixU().leftCols(count);
    rank->datum_defect = static_cast<int>(V0.cols()) - count;
  }
  // The minimum-trace S-transformation holds only where the whole gauge is
  // free; priors that fix part of it (a-priori stations) leave the datum to them.
  *apply_inner_constraints = impl.gauge_is_datum && rank->datum_defect == gauge_basis.cols();
  for (int k = 0; k < defects.cols(); ++k) {
    NullDirection direction = Describe(defects.col(k), words);
    direction.exact = true;
    if (gauge_basis.cols() > 0 && (gauge_basis.transpose() * defects.col(k)).norm() > 0.9) {
      // A datum defect: name the network motion it is.
      const Eigen::VectorXd a = G.colPivHouseholderQr().solve(defects.col(k));
      int best = 0;
      for (int j = 1; j < a.size(); ++j) {
        if (std::abs(a[j]) * G.col(j).norm() > std::abs(a[best]) * G.col(best).norm()) best = j;
      }
      direction.words = "the datum: " + impl.gauge_names[best] + " (" + direction.words + ")";
    }
    rank->directions.push_back(std::move(direction));
  }
  for (int col : d.weak_cols) {
    NullDirection direction = Describe(d.vectors.col(col), words);
    direction.relative_eigenvalue = d.lambda[col] / d.lambda_max;
    rank->directions.push_back(std::move(direction));
  }
  return defects;
}

// The pseudo-inverse over the non-null space in parameter units, moved to
// minimum trace over the gauge's trace rows for a free network:
// P Q P^T with P = I - G (G^T W G)^-1 G^T W.
Eigen::MatrixXd Cofactor(const AdjustmentProblem::Impl& impl, const std::vector<int>& free_cols,
                         const ScaledDecomposition& d, const AdjustmentOptions& options, bool apply_inner_constraints) {
  const int n = static_cast<int>(free_cols.size());
  Eigen::MatrixXd Q;
  if (d.scaled_inverse.size() > 0) {
    Q = d.inv_sqrt_d.asDiagonal() * d.scaled_inverse * d.inv_sqrt_d.asDiagonal();
  } else {
    // V L^-1 V^T over the kept eigenvalues, as (V L^-1/2)(V L^-1/2)^T: one triangle's work.
    Eigen::MatrixXd scaled_vectors = d.vectors;
    for (int i = 0; i < n; ++i) {
      const bool kept = d.lambda[i] > options.rank_tolerance * d.lambda_max;
      scaled_vectors.col(i) *= kept ? 1.0 / std::sqrt(d.lambda[i]) : 0.0;
    }
    Eigen::MatrixXd scaled_q = Eigen::MatrixXd::Zero(n, n);
    scaled_q.selfadjointView<Eigen::Lower>().rankUpdate(scaled_vectors);
    MirrorLowerTriangle(&scaled_q);
    Q = d.inv_sqrt_d.asDiagonal() * scaled_q * d.inv_sqrt_d.asDiagonal();
  }
  if (!apply_inner_constraints) return Q;
  Eigen::MatrixXd G(n, impl.gauge.cols());
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) {
    G.row(i) = impl.gauge.row(free_cols[i]);
    w[i] = impl.gauge_trace_rows[free_cols[i]] ? 1.0 : 0.0;
  }
  const Eigen::MatrixXd GtW = G.transpose() * w.asDiagonal();
  const Eigen::MatrixXd P =
      Eigen::MatrixXd::Identity(n, n) - G * (GtW * G).completeOrthogonalDecomposition().solve(GtW);
  return P * Q * P.transpose();
}

// The diagonal of a point's cofactor Q_pp = N_pp^-1 + A Q_gg A^T, A = N_pp^-1 N_pg
// over the estimable rows of the blocks it is observed with; false if one of
// those blocks has a parameter that is not estimable. Each a_r^T Q_gg a_r reads
// one triangle of Q_gg in place: gathering the point's 130 x 130 block of it
// first was most of the time on 20 000 points.
bool PointCofactorDiagonal(const AdjustmentProblem::Impl& impl, const PointNormals& p, const AdjustmentResult& result,
                           Eigen::Vector3d* diagonal) {
  std::vector<int> rows;  // rows of result.cofactor
  std::vector<Eigen::Vector3d> a;  // columns of A
  for (const auto& [b, n_pb] : p.n_pb) {
    const AdjustmentBlock& other = impl.blocks[b];
    for (size_t i = 0; i < other.names.size(); ++i) {
      const int param = other.global_offset + static_cast<int>(i);
      const int row = result.covariance_row[param];
      if (row >= 0) {
        rows.push_back(row);
        a.push_back(p.n_pp_inverse * n_pb.col(i));
      } else if (result.parameters[param].status == EstimateStatus::kNotEstimable) {
        return false;
      }
    }
  }
  // x^T Q x = sum_j x_j (Q_jj x_j + 2 sum_{i > j} Q_ij x_i), for the three x = A's rows at once.
  Eigen::Vector3d quadratic = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < rows.size(); ++j) {
    const double* column = result.cofactor.col(rows[j]).data();
    Eigen::Vector3d sum = 0.5 * column[rows[j]] * a[j];
    for (size_t i = j + 1; i < rows.size(); ++i) sum += column[rows[i]] * a[i];
    quadratic += 2.0 * a[j].cwiseProduct(sum);
  }
  *diagonal = p.n_pp_inverse.diagonal() + quadratic;
  return true;
}

}  // namespace

void ComputeCovarianceAndRank(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                              const AdjustmentOptions& options, AdjustmentResult* result) {
  const std::vector<int> free_cols = CollectParameters(impl, result);
  const int n = static_cast<int>(free_cols.size());
  RankReport& rank = result->rank;
  rank.num_parameters = n;
  result->covariance_row.assign(result->parameters.size(), -1);
  if (n == 0) return;
  const std::vector<ParameterWords> words = WordsOf(impl, free_cols);
  const ScaledDecomposition d = Decompose(normals, free_cols, words, options, &rank);
  bool apply_inner_constraints = false;
  const Eigen::MatrixXd defects = NameNullSpace(impl, free_cols, words, d, &rank, &apply_inner_constraints);
  const Eigen::MatrixXd Q = Cofactor(impl, free_cols, d, options, apply_inner_constraints);
  // Parameters with a share of a true defect direction cannot be estimated.
  std::vector<int> rows;
  for (int i = 0; i < n; ++i) {
    if (defects.cols() > 0 && defects.row(i).norm() > 1e-3) {
      result->parameters[free_cols[i]].status = EstimateStatus::kNotEstimable;
    } else {
      rows.push_back(i);
    }
  }
  result->cofactor.resize(rows.size(), rows.size());
  for (size_t j = 0; j < rows.size(); ++j) {  // column by column: both matrices are column-major
    for (size_t i = 0; i < rows.size(); ++i) result->cofactor(i, j) = Q(rows[i], rows[j]);
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    result->covariance_index.push_back(free_cols[rows[i]]);
    result->covariance_row[free_cols[rows[i]]] = static_cast<int>(i);
    result->parameters[free_cols[rows[i]]].sigma_unscaled = std::sqrt(std::max(0.0, Q(rows[i], rows[i])));
  }
  for (const PointNormals& p : normals.points) {
    if (p.block < 0) continue;
    int free = 0;
    for (int i = 0; i < 3; ++i) free += impl.blocks[p.block].IsFixed(i) ? 0 : 1;
    if (p.rank < free) ++rank.points_undetermined;
  }
}

void ComputePointEstimates(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                           AdjustmentResult* result) {
  const double scale = result->sigma0;
  std::vector<AdjustmentResult::PointEstimate> estimates(normals.points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, normals.points.size(), 64), [&](const tbb::blocked_range<size_t>& range) {
  for (size_t index = range.begin(); index < range.end(); ++index) {
    const PointNormals& p = normals.points[index];
    if (p.block < 0) continue;
    const AdjustmentBlock& block = impl.blocks[p.block];
    AdjustmentResult::PointEstimate estimate;
    estimate.label = block.label;
    for (size_t i = 0; i < block.values.size(); ++i) estimate.value[i] = block.values[i];  // padding stays 0
    estimate.rays = p.rays;
    int free = 0;
    for (int i = 0; i < 3; ++i) free += block.IsFixed(i) ? 0 : 1;
    Eigen::Vector3d diagonal;
    if (p.rank == free && PointCofactorDiagonal(impl, p, *result, &diagonal)) {
      estimate.sigma = scale * diagonal.cwiseMax(0.0).cwiseSqrt();
    }
    estimates[index] = std::move(estimate);
  }
  });
  for (size_t index = 0; index < normals.points.size(); ++index) {
    if (normals.points[index].block >= 0) result->points.push_back(std::move(estimates[index]));
  }
}

}  // namespace platemeter
