// The self-calibrating bundle adjustment (calib/bundle_adjustment.h) on
// simulated blocks with known truth (samples/bundle_block.h).
#include <gtest/gtest.h>

#include <cmath>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/samples/bundle_block.h"

namespace platemeter {
namespace {

// Frees the named camera parameters (kBundleCameraParamNames indices).
void Free(BundleInput* input, std::initializer_list<int> indices) {
  for (int i : indices) input->cameras[0].states[i] = ParameterState::Free();
}

// Forgets every approximation: the adjustment must compute them.
void ForgetApproximations(BundleInput* input) {
  for (FrameSetup& f : input->frames) {
    f.position_m.reset();
    f.angles.reset();
  }
  input->ground_points.clear();
}

TEST(BundleAdjustment, PureSelfCalibrationOfTheLunarBlockFindsTheInnerCone) {
  sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
  options.seed = 7;
  sim::SimulatedBlock block = sim::SimulateLunarBlock(options);
  Free(&block.input, {0, 1, 2, 3, 4, 6, 7});
  ForgetApproximations(&block.input);
  // Start the inner cone away from the truth: c 1 % off, no distortion.
  block.input.cameras[0].values[0] *= 1.01;
  for (int i = 1; i < kBundleCameraParams; ++i) block.input.cameras[0].values[i] = 0.0;

  const BundleResult result = RunBundleAdjustment(block.input, BundleOptions{});
  SCOPED_TRACE(result.adjustment.summary);
  EXPECT_TRUE(result.adjustment.converged);
  EXPECT_EQ(result.datum, DatumKind::kInnerConstraints);
  EXPECT_EQ(result.adjustment.rank.datum_defect, 7);
  EXPECT_GT(result.adjustment.sigma0, 0.9);
  EXPECT_LT(result.adjustment.sigma0, 1.1);
  const auto truth = block.truth.camera.Values();
  const BundleCameraResult& camera = result.cameras[0];
  if (getenv("PLATEMETER_VERBOSE")) {
    printf("%s\n", result.adjustment.summary.c_str());
    for (int i = 0; i < kBundleCameraParams; ++i) {
      printf("%-12s %.9g +- %.3g truth %.9g\n", kBundleCameraParamNames[i], camera.values[i],
             camera.sigmas[i].value_or(0), truth[i]);
    }
    for (const auto& d : result.adjustment.rank.directions) printf("dir: %s\n", d.words.c_str());
    for (const auto& f : result.frames) printf("%s %s\n", f.id.c_str(), f.initial_values.c_str());
  }
  for (int i : {0, 1, 2, 3, 4, 6, 7}) {
    ASSERT_TRUE(camera.sigmas[i].has_value()) << kBundleCameraParamNames[i];
    EXPECT_LT(std::abs(camera.values[i] - truth[i]), 4.0 * *camera.sigmas[i])
        << kBundleCameraParamNames[i] << " = " << camera.values[i] << " +- " << *camera.sigmas[i] << ", truth "
        << truth[i];
  }
}

}  // namespace
}  // namespace platemeter
