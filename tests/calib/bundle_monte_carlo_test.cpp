// Monte Carlo of the bundle adjustment's precision figures (DESIGN.md
// "Precision figures must be honest"): one simulated block in seed 000
// section 4's geometry, re-noised 200 times; the spread of every estimate
// against the sigma the adjustment predicts, sigma0's mean and the chi-square
// test's rejection rate.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
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

namespace platemeter {
namespace {

// The frames' and points' sigmas, whose values depend on the datum: control
// points (every 10th passpoint, fixed) fix it, so every estimate has a truth.
TEST(BundleMonteCarlo, FrameAndPointSpreadMatchesPredictedSigmasWithControlPoints) {
  sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
  options.seed = 13;
  const sim::SimulatedBlock block = sim::SimulateLunarBlock(options);
  std::mt19937_64 rng(4711);
  const int frames = static_cast<int>(block.input.frames.size());
  std::vector<Sample> frame_spread(frames * 6);
  std::map<std::string, Sample> point_spread[3];
  for (int replicate = 0; replicate < kReplicates; ++replicate) {
    BundleInput input = Renoised(block, &rng);
    for (int i : {0, 1, 2, 3, 6, 7}) input.cameras[0].states[i] = ParameterState::Free();
    for (size_t p = 0; p < input.ground_points.size(); p += 10) input.ground_points[p].sigma_m = {0.0, 0.0, 0.0};
    const BundleResult result = RunBundleAdjustment(input, BundleOptions{});
    ASSERT_EQ(result.datum, DatumKind::kControlPoints);
    for (int f = 0; f < frames; ++f) {
      const sim::StationTruth& truth = block.truth.stations[f];
      const BundleFrameResult& frame = result.frames[f];
      const double errors[6] = {frame.position_m.x() - truth.position_m.x(), frame.position_m.y() - truth.position_m.y(),
                                frame.position_m.z() - truth.position_m.z(),
                                std::remainder(frame.angles.phi_rad - truth.angles.phi_rad, 2 * M_PI),
                                std::remainder(frame.angles.omega_rad - truth.angles.omega_rad, 2 * M_PI),
                                std::remainder(frame.angles.kappa_rad - truth.angles.kappa_rad, 2 * M_PI)};
      for (int k = 0; k < 6; ++k) {
        ASSERT_TRUE(frame.sigmas[k].has_value());
        frame_spread[f * 6 + k].Add(errors[k], *frame.sigmas[k] / result.adjustment.sigma0);
      }
    }
    for (size_t p = 0; p < result.points.size(); p += 7) {  // every 7th point: a sample of free ones
      const BundlePointResult& point = result.points[p];
      if (point.control || !point.sigma_m) continue;
      const Eigen::Vector3d& truth = block.truth.points[p].position_m;
      ASSERT_EQ(block.truth.points[p].id, point.id);
      for (int k = 0; k < 3; ++k) {
        point_spread[k][point.id].Add(point.position_m[k] - truth[k], (*point.sigma_m)[k] / result.adjustment.sigma0);
      }
    }
  }
  double worst = 1.0;
  auto check = [&](const Sample& s, const std::string& what) {
    const double ratio = s.Spread() / s.MeanPredicted();
    if (std::abs(ratio - 1.0) > std::abs(worst - 1.0)) worst = ratio;
    EXPECT_GT(ratio, 0.8) << what;
    EXPECT_LT(ratio, 1.2) << what;
  };
  for (int f = 0; f < frames; ++f) {
    for (int k = 0; k < 6; ++k) check(frame_spread[f * 6 + k], block.input.frames[f].id + " " + kBundleFrameParamNames[k]);
  }
  int points = 0;
  for (int k = 0; k < 3; ++k) {
    for (const auto& [id, s] : point_spread[k]) {
      check(s, "point " + id + " axis " + std::to_string(k));
      ++points;
    }
  }
  printf("%d frame parameters and %d point coordinates: spread / predicted sigma, the farthest from 1: %.3f\n",
         frames * 6, points, worst);
}

}  // namespace
}  // namespace platemeter
