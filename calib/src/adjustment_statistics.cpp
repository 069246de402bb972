// sigma0, degrees of freedom, the global chi-square test, residuals and the
// summary of an adjustment (adjustment.h); the result's covariance queries
// and significance tests.
#include <algorithm>
#include <cmath>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "adjustment_internal.h"

namespace platemeter {
namespace {

std::string RankSentence(const RankReport& rank) {
  int exact = 0, weak = 0;
  for (const NullDirection& d : rank.directions) (d.exact ? exact : weak) += 1;
  std::string s;
  if (exact > 0) {
    s += fmt::format(" The normal equations are singular (rank {} of {}): ", rank.numerical_rank + rank.datum_defect,
                     rank.num_parameters);
    int k = 0;
    for (const NullDirection& d : rank.directions) {
      if (!d.exact) continue;
      s += (k++ > 0 ? "; " : "") + d.words;
    }
    s += " cannot be separated; fix or weight one of each, or add observations that separate them."
         " Everything else is reported.";
  }
  if (weak > 0) {
    s += fmt::format(" {} poorly determined combination{} (see the rank report), the weakest: {}.", weak,
                     weak == 1 ? "" : "s", rank.directions[exact].words);
  }
  if (rank.datum_defect > 0) s += fmt::format(" Datum: inner constraints absorb {} directions.", rank.datum_defect);
  return s;
}

// One observation's residual, raw and whitened, with its labels.
ObservationResidual ObservationResidualOf(const AdjustmentProblem::Impl& impl, int equation,
                                          std::vector<const double*>* parameters) {
  const AdjustmentEquation& e = impl.equations[equation];
  const auto& whitened_cost = static_cast<const WhitenedCost&>(*e.cost);
  parameters->clear();
  for (int b : e.blocks) parameters->push_back(impl.blocks[b].values.data());
  ObservationResidual r;
  r.group = e.group;
  r.item = e.item;
  r.origin = e.origin;
  r.label = e.group + " " + e.item;
  r.status = e.status;
  r.reason = e.reason;
  Eigen::VectorXd raw(e.Dimension());
  if (!whitened_cost.raw().Evaluate(parameters->data(), raw.data(), nullptr)) raw.setConstant(0.0);
  const Eigen::VectorXd w = whitened_cost.sqrt_information() * raw;
  r.residual.assign(raw.data(), raw.data() + raw.size());
  r.normalized.assign(w.data(), w.data() + w.size());
  return r;
}

}  // namespace

void ComputeStatistics(const AdjustmentProblem::Impl& impl, const ReducedNormals& normals,
                       const AdjustmentOptions& options, AdjustmentResult* result) {
  long point_rank = 0;
  for (const PointNormals& p : normals.points) point_rank += p.rank;
  result->observation_rows = normals.observation_rows;
  result->prior_rows = normals.prior_rows;
  result->unknowns = result->rank.num_parameters + point_rank;
  // dof = n - u + d: the numerical rank already leaves out the null directions (datum included).
  result->dof = double(normals.observation_rows + normals.prior_rows) -
                double(result->rank.numerical_rank + point_rank);
  ChiSquareTest& chi = result->chi_square;
  chi.statistic = normals.vtpv;
  chi.dof = result->dof;
  const bool has_dof = result->dof >= 1.0;
  // With no redundancy sigma0 cannot be estimated: the a-priori sigmas stand (sigma0 = 1).
  result->sigma0 = has_dof ? std::sqrt(normals.vtpv / result->dof) : 1.0;
  if (has_dof) {
    boost::math::chi_squared distribution(result->dof);
    const double alpha = options.significance_level;
    chi.lower = boost::math::quantile(distribution, alpha / 2);
    chi.upper = boost::math::quantile(distribution, 1 - alpha / 2);
    const double cdf = boost::math::cdf(distribution, chi.statistic);
    chi.p_value = std::min(1.0, 2.0 * std::min(cdf, 1.0 - cdf));
    chi.rejected = chi.statistic < chi.lower || chi.statistic > chi.upper;
  }
  for (ParameterEstimate& p : result->parameters) {
    if (p.sigma_unscaled) p.sigma = *p.sigma_unscaled * result->sigma0;
  }
  // Residuals of every observation and prior; the observations in parallel
  // (400 000 of them in a large block, each with its labels).
  const size_t num_observations = impl.observation_equation.size();
  const size_t first_residual = result->residuals.size();
  result->residuals.resize(first_residual + num_observations);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_observations, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<const double*> parameters;
    for (size_t k = range.begin(); k < range.end(); ++k) {
      result->residuals[first_residual + k] = ObservationResidualOf(impl, impl.observation_equation[k], &parameters);
      result->residuals[first_residual + k].observation = static_cast<int>(k);
    }
  });
  for (const AdjustmentEquation& e : impl.equations) {
    if (!e.is_prior) continue;
    const auto& prior = static_cast<const PriorCost&>(*e.cost);
    const AdjustmentBlock& block = impl.blocks[e.blocks[0]];
    PriorResidual r;
    r.label = e.label;
    Eigen::VectorXd difference(prior.indices().size());
    for (size_t i = 0; i < prior.indices().size(); ++i) {
      difference[i] = block.values[prior.indices()[i]] - prior.values()[i];
    }
    const Eigen::VectorXd w = prior.sqrt_information() * difference;
    r.residual.assign(difference.data(), difference.data() + difference.size());
    r.normalized.assign(w.data(), w.data() + w.size());
    result->prior_residuals.push_back(std::move(r));
  }
  std::string s = fmt::format("Adjusted {} unknowns from {} observation rows and {} prior rows in {} iterations: "
                              "sigma0 = {:.4f} with {:.0f} degrees of freedom",
                              result->unknowns, result->observation_rows, result->prior_rows, result->iterations,
                              result->sigma0, result->dof);
  if (!has_dof) {
    s += " (no redundancy: sigma0 cannot be estimated and the a-priori sigmas are reported unscaled).";
  } else if (chi.rejected) {
    s += fmt::format("; the chi-square test rejects the a-priori sigmas at alpha = {} (p = {:.2g}): they are "
                     "{} by a factor of about {:.2f}, or the model misses an effect -- look at the worst residuals.",
                     options.significance_level, chi.p_value, result->sigma0 > 1 ? "too small" : "too large",
                     result->sigma0);
  } else {
    s += fmt::format("; the chi-square test accepts the a-priori sigmas (p = {:.2g}).", chi.p_value);
  }
  if (result->rejected > 0) s += fmt::format(" {} observations rejected by the robust pass.", result->rejected);
  s += RankSentence(result->rank);
  result->summary = s;
}

int AdjustmentResult::Find(const std::string& block, const std::string& name) const {
  for (size_t i = 0; i < parameters.size(); ++i) {
    if (parameters[i].block == block && parameters[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

Eigen::MatrixXd AdjustmentResult::Covariance(const std::vector<int>& which, bool scaled) const {
  const int k = static_cast<int>(which.size());
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(k, k);
  const double factor = scaled ? sigma0 * sigma0 : 1.0;
  for (int i = 0; i < k; ++i) {
    const int ri = covariance_row.at(which[i]);
    if (ri < 0) continue;
    for (int j = 0; j < k; ++j) {
      const int rj = covariance_row.at(which[j]);
      if (rj >= 0) c(i, j) = factor * cofactor(ri, rj);
    }
  }
  return c;
}

Eigen::MatrixXd AdjustmentResult::Correlation(const std::vector<int>& which) const {
  const Eigen::MatrixXd c = Covariance(which, false);
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(c.rows(), c.cols());
  for (int i = 0; i < c.rows(); ++i) {
    for (int j = 0; j < c.cols(); ++j) {
      const double d = std::sqrt(c(i, i) * c(j, j));
      r(i, j) = d > 0.0 ? c(i, j) / d : 0.0;
    }
  }
  return r;
}

std::vector<std::tuple<int, int, double>> AdjustmentResult::HighCorrelations(const std::vector<int>& which,
                                                                             double threshold) const {
  const Eigen::MatrixXd r = Correlation(which);
  std::vector<std::tuple<int, int, double>> out;
  for (int i = 0; i < r.rows(); ++i) {
    for (int j = i + 1; j < r.cols(); ++j) {
      if (std::abs(r(i, j)) >= threshold) out.emplace_back(which[i], which[j], r(i, j));
    }
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return std::abs(std::get<2>(a)) > std::abs(std::get<2>(b)); });
  return out;
}

SignificanceTest AdjustmentResult::Test(const std::vector<int>& which, double alpha) const {
  SignificanceTest test;
  for (size_t i = 0; i < which.size(); ++i) test.what += (i ? ", " : "") + parameters.at(which[i]).name;
  const int k = static_cast<int>(which.size());
  Eigen::VectorXd v(k);
  for (int i = 0; i < k; ++i) v[i] = parameters[which[i]].value;
  const Eigen::MatrixXd c = Covariance(which, true);
  const double dof_t = std::max(1.0, dof);
  for (int i = 0; i < k; ++i) {
    if (!(c(i, i) > 0.0)) return test;  // fixed or not estimable: no test
  }
  if (k == 1) {
    test.statistic = v[0] / std::sqrt(c(0, 0));
    boost::math::students_t distribution(dof_t);
    test.critical = boost::math::quantile(distribution, 1 - alpha / 2);
    test.p_value = 2 * boost::math::cdf(boost::math::complement(distribution, std::abs(test.statistic)));
    test.significant = std::abs(test.statistic) > test.critical;
  } else {
    test.statistic = v.dot(c.ldlt().solve(v)) / k;
    boost::math::fisher_f distribution(k, dof_t);
    test.critical = boost::math::quantile(distribution, 1 - alpha);
    test.p_value = boost::math::cdf(boost::math::complement(distribution, std::max(0.0, test.statistic)));
    test.significant = test.statistic > test.critical;
  }
  return test;
}

}  // namespace platemeter
