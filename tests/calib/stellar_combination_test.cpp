// Seed 001's multi-plate weighted mean (Pope) against the simultaneous solution
// of the same plates, and a Monte Carlo of the combination against the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <thread>

#include "platemeter/calib/stellar_combination.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"

namespace platemeter {
namespace {

// A North plate and a South plate (camera turned 180 deg) on two dates, as
// seed 001 exposed each aperture; Beltsville, zenith.
const std::vector<sim::StellarTruthPlate>& TwoPlates() {
  static const std::vector<sim::StellarTruthPlate> plates = [] {
    const DefinitionRegistry registry;
    std::vector<sim::StellarTruthPlate> out;
    for (const auto& [id, start, roll] : {std::tuple{"N", "1972-05-12T05:30:00Z", 0.0},
                                          std::tuple{"S", "1972-04-09T06:10:00Z", 180.0}}) {
      out.push_back(sim::SimulateStellarTruth(testing::BeltsvillePlate(id, start, roll), registry.Camera("orbigon")));
    }
    return out;
  }();
  return plates;
}

struct Replicate {
  std::vector<StellarPlate> plates;
  StellarCatalog catalog;
};
Replicate Noisy(uint64_t seed) {
  Replicate r;
  for (const sim::StellarTruthPlate& truth : TwoPlates()) {
    sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = seed * 7919 + r.plates.size()});
    r.plates.push_back(std::move(noisy.plate));
    r.catalog.insert(noisy.catalog.begin(), noisy.catalog.end());  // a star on both plates: one catalog error
  }
  return r;
}

StellarCombination Combine(const Replicate& r, const StellarOptions& options,
                           std::vector<StellarPlateResult>* singles = nullptr) {
  std::vector<StellarPlateResult> own;
  for (const StellarPlate& plate : r.plates)
    own.push_back(RunStellarPlate(plate, r.catalog, NominalStellarCamera(80.2), options));
  StellarCombination c = CombineStellarPlates("N+S", r.plates, own, r.catalog, options);
  if (singles) *singles = std::move(own);
  return c;
}

double Wrapped(int i, double difference) { return i == 10 ? std::remainder(difference, 2 * M_PI) : difference; }

TEST(StellarCombination, WeightedMeanEqualsTheSimultaneousSolution) {
  const Replicate r = Noisy(1);
  StellarOptions options;
  options.adjustment.function_tolerance = 1e-16;  // both solutions to their last digits
  options.adjustment.parameter_tolerance = 1e-16;
  options.adjustment.polish = true;
  std::vector<StellarPlateResult> singles;
  const StellarCombination c = Combine(r, options, &singles);
  const AdjustmentResult simultaneous =
      SolveStellarPlatesSimultaneously(r.plates, r.catalog, NominalStellarCamera(80.2), options);
  std::vector<int> index;
  for (const char* name : kStellarCameraParamNames) index.push_back(simultaneous.Find("camera", name));
  Eigen::MatrixXd q = simultaneous.Covariance(index, false);
  StellarCamera reference(kStellarCameraParams);
  for (int i = 0; i < kStellarCameraParams; ++i) reference[i] = simultaneous.parameters[index[i]].value;
  CanonicalDecentering(&reference, &q);
  std::printf("relinearizations %d, Pope's one step off by %.2e sigma; m_0 %.6f (simultaneous %.6f), dof %.0f (%.0f)\n",
              c.relinearizations, c.one_step_offset_sigma, c.m_0, simultaneous.sigma0, c.dof, simultaneous.dof);
  EXPECT_EQ(c.dof, simultaneous.dof);
  EXPECT_NEAR(c.m_0, simultaneous.sigma0, 1e-9 * simultaneous.sigma0);
  double worst_value = 0.0, worst_covariance = 0.0;
  for (int i = 0; i < kStellarCameraParams; ++i) {
    const double a = c.camera[i], b = reference[i];
    worst_value = std::max(worst_value, std::abs(Wrapped(i, a - b)) / std::max(std::abs(a), std::abs(b)));
    for (int j = 0; j < kStellarCameraParams; ++j) {
      const double scale = std::sqrt(q(i, i) * q(j, j));
      worst_covariance = std::max(worst_covariance, std::abs(c.cofactor(i, j) - q(i, j)) / scale);
    }
  }
  std::printf("largest relative difference: values %.2e, cofactor elements %.2e\n", worst_value, worst_covariance);
  EXPECT_LT(worst_value, 1e-9);
  EXPECT_LT(worst_covariance, 1e-9);
  // Pope's one step alone is NOT the simultaneous solution (the model is not linear).
  EXPECT_GT(c.one_step_offset_sigma, 0.0);
  for (const PlateConsistency& t : c.consistency)
    std::printf("plate %s against the combination: F = %.2f (k = %d), p = %.3f\n", t.plate_id.c_str(), t.f_statistic,
                t.k, t.p_value);
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

// 100 re-noised measurement sets (the issue asks for 50; at 50 the sample
// spread's own standard error, 10 %, makes a 25 % band too tight for 11 parameters) (images and catalog places) of the N + S pair:
// every camera parameter's spread about the truth within 25 % of its predicted
// sigma, m_0 within [0.9, 1.1], no bias beyond 3 standard errors.
TEST(StellarCombination, MonteCarloSigmasMatchTheSpread) {
  constexpr int kReplicates = 100;
  const StellarCamera truth = TwoPlates().front().camera;
  StellarOptions options;
  options.adjustment.num_threads = 1;  // the replicates run in parallel instead
  std::vector<StellarCombination> runs(kReplicates);
  std::vector<std::thread> workers;
  const int num_workers = std::max(1u, std::thread::hardware_concurrency());
  for (int w = 0; w < num_workers; ++w) {
    workers.emplace_back([&, w] {
      for (int r = w; r < kReplicates; r += num_workers) runs[r] = Combine(Noisy(100 + r), options);
    });
  }
  for (std::thread& t : workers) t.join();
  std::vector<std::array<double, kStellarCameraParams>> errors;
  std::array<double, kStellarCameraParams> predicted2{};
  for (const StellarCombination& c : runs) {
    EXPECT_GE(c.m_0, 0.9);
    EXPECT_LE(c.m_0, 1.1);
    std::array<double, kStellarCameraParams> e{};
    for (int i = 0; i < kStellarCameraParams; ++i) {
      e[i] = Wrapped(i, c.camera[i] - truth[i]);
      predicted2[i] += c.camera_sigma[i] * c.camera_sigma[i] / kReplicates;
    }
    errors.push_back(e);
  }
  for (int i = 0; i < kStellarCameraParams; ++i) {
    double mean = 0.0, sum2 = 0.0;
    for (const auto& e : errors) mean += e[i] / kReplicates;
    for (const auto& e : errors) sum2 += (e[i] - mean) * (e[i] - mean);
    const double spread = std::sqrt(sum2 / (kReplicates - 1));
    const double predicted = std::sqrt(predicted2[i]);
    std::printf("%-10s spread / predicted sigma %.3f, mean error %+.2f sigma\n", kStellarCameraParamNames[i],
                spread / predicted, mean / predicted);
    EXPECT_NEAR(spread / predicted, 1.0, 0.25) << kStellarCameraParamNames[i];
    EXPECT_LT(std::abs(mean) / predicted, 3.0 / std::sqrt(kReplicates)) << kStellarCameraParamNames[i];
  }
}

}  // namespace
}  // namespace platemeter
