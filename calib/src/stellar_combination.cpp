// Pope's generalized weighted mean of stellar plates, relinearized until it is
// the simultaneous solution (stellar_combination.h).
#include "platemeter/calib/stellar_combination.h"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <boost/math/distributions/fisher_f.hpp>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter {
namespace {

using stellar_internal::CameraParameterFixed;

constexpr int kMaxRelinearizations = 20;
// Converged: the largest camera step below kConvergedStepSigma, or below
// kRoundingFloorSigma and no longer halving -- Gauss-Newton converges
// quadratically, so a step that stops shrinking there is rounding (with
// ~10 000 images per plate the floor is ~5e-10 sigma; with a few hundred ~1e-11).
constexpr double kConvergedStepSigma = 1e-10;
constexpr double kRoundingFloorSigma = 1e-7;

Eigen::VectorXd AsVector(const StellarCamera& c) {
  return Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
}
StellarCamera AsCamera(const Eigen::VectorXd& v) { return StellarCamera(v.data(), v.data() + v.size()); }

// The decentering angle (Phi_T, theta0; -1 for Brown): averaged and differenced on one branch.
int AngleIndex(const StellarOptions& options) { return StellarDecenteringSignOf(options.lens_model).angle; }

// The free parameters: the rest stay at their values with zero rows.
std::vector<int> FreeParameters(const StellarOptions& options) {
  std::vector<int> free;
  for (int i = 0; i < StellarCameraParamCount(options.lens_model); ++i) {
    if (!CameraParameterFixed(options, i)) free.push_back(i);
  }
  return free;
}

// (sum N)^-1 over the free parameters, zero elsewhere; throws if singular.
Eigen::MatrixXd InverseOverFree(const Eigen::MatrixXd& n, const std::vector<int>& free) {
  const int k = static_cast<int>(free.size());
  Eigen::MatrixXd sub(k, k);
  for (int a = 0; a < k; ++a) {
    for (int b = 0; b < k; ++b) sub(a, b) = n(free[a], free[b]);
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(sub);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 0.0)
    throw Error("stellar combination", "the plates' summed normal matrix is singular: the camera is not determined");
  const Eigen::MatrixXd inverse = ldlt.solve(Eigen::MatrixXd::Identity(k, k));
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n.rows(), n.cols());
  for (int a = 0; a < k; ++a) {
    for (int b = 0; b < k; ++b) out(free[a], free[b]) = inverse(a, b);
  }
  return out;
}

// Pope's one step: (sum N_i)^-1 sum N_i X_i, each decentering angle on the first plate's branch.
Eigen::VectorXd OneStepMean(const std::vector<StellarPlateResult>& singles, const Eigen::MatrixXd& cofactor,
                            int angle) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(cofactor.rows());
  for (const StellarPlateResult& s : singles) {
    Eigen::VectorXd x = AsVector(s.camera);
    if (angle >= 0)
      x[angle] = singles.front().camera[angle] + std::remainder(x[angle] - singles.front().camera[angle], 2 * M_PI);
    sum += s.camera_information * x;
  }
  return cofactor * sum;
}

PlateConsistency TestPlate(const StellarPlateResult& single, const StellarCombination& c, const Eigen::VectorXd& x,
                           int angle, double alpha) {
  PlateConsistency t;
  t.plate_id = single.plate_id;
  const int n = static_cast<int>(x.size());
  Eigen::VectorXd d = AsVector(single.camera) - x;
  if (angle >= 0) d[angle] = std::remainder(d[angle], 2 * M_PI);
  const std::vector<int> free = [&] {
    std::vector<int> f;
    for (int i = 0; i < n; ++i) {
      if (single.camera_row[i] >= 0) f.push_back(i);
    }
    return f;
  }();
  const Eigen::MatrixXd q_single = InverseOverFree(single.camera_information, free);
  // Unit-diagonal scaling first: the parameters' sigmas span 12 orders of magnitude.
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(n);
  for (int i : free) scale[i] = std::sqrt(q_single(i, i));
  d = d.cwiseQuotient(scale);
  const Eigen::MatrixXd difference =
      scale.cwiseInverse().asDiagonal() * (q_single - c.cofactor) * scale.cwiseInverse().asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(difference);
  const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
  double quadratic = 0.0;
  for (int i = 0; i < n; ++i) {
    const double lambda = eigen.eigenvalues()[i];
    if (!(lambda > 1e-10 * largest)) continue;
    const double projection = eigen.eigenvectors().col(i).dot(d);
    quadratic += projection * projection / lambda;
    ++t.k;
  }
  if (t.k == 0 || !(c.m_0 > 0.0)) return t;
  t.f_statistic = quadratic / (t.k * c.m_0 * c.m_0);
  const boost::math::fisher_f distribution(t.k, std::max(1.0, c.dof));
  t.p_value = boost::math::cdf(boost::math::complement(distribution, t.f_statistic));
  t.rejected = t.p_value < alpha;
  return t;
}

}  // namespace

StellarCombination CombineStellarPlates(const std::string& name, const std::vector<StellarPlate>& plates,
                                        const std::vector<StellarPlateResult>& singles,
                                        const StellarCatalog& catalog, const StellarOptions& options) {
  if (plates.empty() || plates.size() != singles.size())
    throw Error("stellar combination", "needs the plates and their single-plate results, one for one");
  std::string why;
  if (!options.Check(&why)) throw Error("stellar options", why);
  const std::vector<int> free = FreeParameters(options);
  const int n = StellarCameraParamCount(options.lens_model);
  const int angle = AngleIndex(options);
  for (const StellarPlateResult& s : singles) {
    if (static_cast<int>(s.camera.size()) != n)
      throw Error("stellar combination", fmt::format("plate {} was not adjusted with the {} lens", s.plate_id,
                                                     DistortionModelName(options.lens_model)));
  }
  StellarCombination c;
  c.name = name;
  Eigen::MatrixXd n_sum = Eigen::MatrixXd::Zero(n, n);
  double dof_sum = 0.0, vtpv_before = 0.0, unit2_sum = 0.0;
  for (const StellarPlateResult& s : singles) {
    c.plate_ids.push_back(s.plate_id);
    n_sum += s.camera_information;
    dof_sum += s.adjustment.dof;
    vtpv_before += s.adjustment.chi_square.statistic;
    unit2_sum += s.unit_sigma_um * s.unit_sigma_um * s.adjustment.dof;
  }
  const double unit_sigma_um = std::sqrt(unit2_sum / dof_sum);
  Eigen::VectorXd x = OneStepMean(singles, InverseOverFree(n_sum, free), angle);
  const Eigen::VectorXd one_step = x;

  std::vector<stellar_internal::PreparedPlate> prepared;
  std::vector<stellar_internal::PlateState> states;
  for (size_t i = 0; i < plates.size(); ++i) {
    const Eigen::Matrix3d pointing = singles[i].orientation_sets.front().camera_from_enu;
    prepared.push_back(stellar_internal::PreparePlate(plates[i], catalog, AsCamera(x), options, pointing));
    states.push_back(stellar_internal::InitialPlateState(prepared.back(), singles[i]));
  }
  // Gauss-Newton on the simultaneous problem, each plate's own parameters
  // eliminated: the camera step from the summed reduced normals, then each
  // plate's step by back-substitution.
  std::vector<stellar_internal::PlateLinearization> lin(plates.size());
  double previous = INFINITY;
  for (c.relinearizations = 1; c.relinearizations <= kMaxRelinearizations; ++c.relinearizations) {
    tbb::parallel_for(size_t{0}, plates.size(), [&](size_t i) {
      lin[i] = stellar_internal::LinearizePlate(plates[i], prepared[i], states[i], AsCamera(x), options);
    });
    n_sum.setZero();
    Eigen::VectorXd b_sum = Eigen::VectorXd::Zero(n);
    for (const auto& l : lin) n_sum += l.n, b_sum += l.b;
    c.cofactor = InverseOverFree(n_sum, free);
    const Eigen::VectorXd step = -c.cofactor * b_sum;
    for (size_t i = 0; i < plates.size(); ++i) stellar_internal::StepPlate(lin[i], step, &states[i]);
    x += step;
    double largest = 0.0;
    for (int i : free) largest = std::max(largest, std::abs(step[i]) / std::sqrt(c.cofactor(i, i)));
    if (largest < kConvergedStepSigma || (largest < kRoundingFloorSigma && largest > 0.5 * previous)) break;
    previous = largest;
  }
  if (c.relinearizations > kMaxRelinearizations)
    throw Error("stellar combination", fmt::format("the relinearized mean did not converge in {} steps",
                                                   kMaxRelinearizations));
  // The last step is at the rounding floor: the statistics at the penultimate point are those of x.
  c.camera = AsCamera(x);
  CanonicalDecentering(&c.camera, &c.cofactor, options.lens_model);
  x = AsVector(c.camera);
  c.vtpv = 0.0;
  for (const auto& l : lin) c.vtpv += l.vtpv;
  c.dof = dof_sum + static_cast<double>(free.size()) * (static_cast<double>(plates.size()) - 1.0);
  c.m_0 = std::sqrt(c.vtpv / c.dof);
  c.camera_sigma.assign(n, 0.0);
  for (int i : free) {
    c.camera_sigma[i] = c.m_0 * std::sqrt(c.cofactor(i, i));
    c.one_step_offset_sigma =
        std::max(c.one_step_offset_sigma, std::abs(one_step[i] - x[i]) / std::sqrt(c.cofactor(i, i)));
  }
  c.m_p_um = std::sqrt(vtpv_before / dof_sum) * unit_sigma_um;
  c.m_p_after_um = std::sqrt(c.vtpv / dof_sum) * unit_sigma_um;
  for (const StellarPlateResult& s : singles)
    c.consistency.push_back(TestPlate(s, c, x, angle, options.adjustment.significance_level));
  return c;
}

AdjustmentResult SolveStellarPlatesSimultaneously(const std::vector<StellarPlate>& plates,
                                                  const StellarCatalog& catalog, const StellarCamera& initial,
                                                  const StellarOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("stellar options", why);
  stellar_internal::CheckCamera(initial, options, "stellar combination");
  AdjustmentProblem problem;
  const int camera = stellar_internal::AddCameraBlock("camera", initial, options, &problem);
  for (const StellarPlate& plate : plates) {
    const stellar_internal::PreparedPlate prepared =
        stellar_internal::PreparePlate(plate, catalog, initial, options, std::nullopt);
    stellar_internal::AddPlateToProblem(plate, prepared, options, camera, &problem);
  }
  return problem.Solve(options.adjustment);
}

}  // namespace platemeter
