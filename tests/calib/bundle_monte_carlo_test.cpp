// Monte Carlo of the bundle adjustment's precision figures (DESIGN.md
// "Precision figures must be honest"): one simulated block in seed 000
// section 4's geometry, re-noised 200 times; the spread of every estimate
// against the sigma the adjustment predicts, sigma0's mean and the chi-square
// test's rejection rate.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/samples/bundle_block.h"

namespace platemeter {
namespace {

constexpr int kReplicates = 200;

struct Sample {
  double sum = 0.0, sum_squares = 0.0, predicted = 0.0;
  int n = 0;
  void Add(double error, double predicted_sigma) {
    sum += error;
    sum_squares += error * error;
    predicted += predicted_sigma;
    ++n;
  }
  double Mean() const { return sum / n; }
  // The spread: standard deviation of the estimates about their mean.
  double Spread() const { return std::sqrt((sum_squares - n * Mean() * Mean()) / (n - 1)); }
  double MeanPredicted() const { return predicted / n; }
};

// The block's noise-free observations with fresh Gaussian noise of the block's sigma.
BundleInput Renoised(const sim::SimulatedBlock& block, std::mt19937_64* rng) {
  BundleInput input = block.input;
  std::normal_distribution<double> noise(0.0, block.truth.sigma_mm);
  for (size_t i = 0; i < input.observations.size(); ++i) {
    input.observations[i].x_mm = block.truth.observations[i].x_mm + noise(*rng);
    input.observations[i].y_mm = block.truth.observations[i].y_mm + noise(*rng);
  }
  return input;
}

TEST(BundleMonteCarlo, InnerConeSpreadMatchesPredictedSigmasInSeed000Section4Geometry) {
  // Seed 000 section 4: three orbits, three exposures each, 90 deg kappa
  // increments, 80 deg convergence, 215 passpoints, 15 um; pure self-calibration.
  sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
  options.seed = 11;
  const sim::SimulatedBlock block = sim::SimulateLunarBlock(options);
  const std::vector<int> free = {0, 1, 2, 3, 4, 6, 7};  // c, xp, yp, k1, k2, p1, p2
  const auto truth = block.truth.camera.Values();
  std::vector<Sample> spread(kBundleCameraParams);
  double sigma0_sum = 0.0;
  int rejected = 0;
  std::mt19937_64 rng(20261126);
  for (int replicate = 0; replicate < kReplicates; ++replicate) {
    BundleInput input = Renoised(block, &rng);
    for (int i : free) input.cameras[0].states[i] = ParameterState::Free();
    const BundleResult result = RunBundleAdjustment(input, BundleOptions{});
    ASSERT_TRUE(result.adjustment.converged) << result.adjustment.summary;
    sigma0_sum += result.adjustment.sigma0;
    rejected += result.adjustment.chi_square.rejected ? 1 : 0;
    const BundleCameraResult& camera = result.cameras[0];
    for (int i : free) {
      const ParameterEstimate& p = result.adjustment.parameters[camera.parameter_index[i]];
      ASSERT_TRUE(p.sigma_unscaled.has_value()) << p.name;
      spread[i].Add(camera.values[i] - truth[i], *p.sigma_unscaled);
    }
  }
  for (int i : free) {
    const Sample& s = spread[i];
    const double ratio = s.Spread() / s.MeanPredicted();
    RecordProperty(kBundleCameraParamNames[i], std::to_string(ratio));
    // The mean error is printed, not asserted: least squares on a nonlinear
    // model is biased to O(sigma^2), which shows in the weakly determined
    // k1/k2 pair at 15 um (about 1 sigma, falling tenfold at 1.5 um: docs/bundle.md).
    printf("%-11s spread %.4g, predicted sigma %.4g, ratio %.3f, mean error %+.3f sigma\n",
           kBundleCameraParamNames[i], s.Spread(), s.MeanPredicted(), ratio, s.Mean() / s.MeanPredicted());
    EXPECT_GT(ratio, 0.8) << kBundleCameraParamNames[i];
    EXPECT_LT(ratio, 1.2) << kBundleCameraParamNames[i];
  }
  const double mean_sigma0 = sigma0_sum / kReplicates;
  const double rejection_rate = double(rejected) / kReplicates;
  printf("mean sigma0 %.4f, chi-square rejection rate %.3f (alpha 0.05)\n", mean_sigma0, rejection_rate);
  EXPECT_GT(mean_sigma0, 0.95);
  EXPECT_LT(mean_sigma0, 1.05);
  EXPECT_GE(rejection_rate, 0.02);
  EXPECT_LE(rejection_rate, 0.08);
}

}  // namespace
}  // namespace platemeter
