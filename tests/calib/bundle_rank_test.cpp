// The bundle adjustment's rank report (calib/adjustment.h RankReport) on the
// geometries of seed 000 section 2.3, and the errors of hopeless geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/core/error.h"
#include "platemeter/samples/bundle_block.h"

namespace platemeter {
namespace {

void FreeRank(BundleInput* input, std::initializer_list<int> indices) {
  for (int i : indices) input->cameras[0].states[i] = ParameterState::Free();
}

bool Names(const RankReport& rank, const std::string& word) {
  for (const NullDirection& d : rank.directions) {
    if (d.words.find(word) != std::string::npos) return true;
  }
  return false;
}

TEST(BundleRank, Apollo14GeometryNamesThePrincipalPointItCannotRecover) {
  // Seed 000 section 2.3: narrow field (500 mm), every frame at the same kappa,
  // xp and yp free, no control: x_p compensates phi (eq. 12-13), y_p omega.
  sim::SimulatedBlock block = sim::SimulateLunarBlock(sim::Apollo14Section3Options());
  FreeRank(&block.input, {0, 1, 2, 3, 6, 7});
  block.input.ground_points.clear();
  BundleOptions options;
  options.adjustment.max_iterations = 300;
  const BundleResult result = RunBundleAdjustment(block.input, options);
  const RankReport& rank = result.adjustment.rank;
  ASSERT_FALSE(rank.directions.empty()) << result.adjustment.summary;
  EXPECT_TRUE(Names(rank, "xp_mm")) << result.adjustment.summary;
  EXPECT_TRUE(Names(rank, "yp_mm")) << result.adjustment.summary;
  EXPECT_NE(result.adjustment.summary.find("poorly determined"), std::string::npos);
  // Everything else is still reported: c and k1 with sigmas, every frame.
  EXPECT_TRUE(result.cameras[0].sigmas[0].has_value());
  EXPECT_TRUE(result.cameras[0].sigmas[3].has_value());
  EXPECT_EQ(result.frames.size(), block.input.frames.size());
}

TEST(BundleRank, Apollo14GeometryWithThePrincipalPointFixedAsTheSeedDidIsDetermined) {
  // Seed 000 section 3.2: "x_p and y_p were also constrained to zero".
  sim::SimulatedBlock block = sim::SimulateLunarBlock(sim::Apollo14Section3Options());
  FreeRank(&block.input, {0, 3, 6, 7});
  block.input.ground_points.clear();
  const BundleResult result = RunBundleAdjustment(block.input, BundleOptions{});
  EXPECT_TRUE(result.adjustment.converged);
  EXPECT_FALSE(Names(result.adjustment.rank, "xp_mm"));
  EXPECT_FALSE(Names(result.adjustment.rank, "yp_mm"));
  EXPECT_EQ(result.adjustment.rank.datum_defect, 7);
}

TEST(BundleRank, Section4GeometryDeterminesTheWholeInnerCone) {
  // Seed 000 section 4: convergence and 90 deg kappa increments recover the inner cone.
  sim::SimulatedBlock block = sim::SimulateLunarBlock(sim::Seed000Table9Options(80.0));
  FreeRank(&block.input, {0, 1, 2, 3, 4, 6, 7});
  const BundleResult result = RunBundleAdjustment(block.input, BundleOptions{});
  for (const NullDirection& d : result.adjustment.rank.directions) ADD_FAILURE() << d.words;
  EXPECT_EQ(result.adjustment.rank.datum_defect, 7);
}

TEST(BundleRank, FixedFrameDatumWithoutADistanceNamesTheScale) {
  sim::SimulatedBlock block = sim::SimulateLunarBlock(sim::Seed000Table9Options(80.0));
  FreeRank(&block.input, {0, 1, 2});
  block.input.frames[4].fixed = true;  // the central exposure, as seed 000 section 3.2
  const BundleResult result = RunBundleAdjustment(block.input, BundleOptions{});
  EXPECT_EQ(result.datum, DatumKind::kFixedFrames);
  ASSERT_EQ(result.adjustment.rank.directions.size(), 1u) << result.adjustment.summary;
  EXPECT_NE(result.adjustment.rank.directions[0].words.find("scale"), std::string::npos)
      << result.adjustment.rank.directions[0].words;
  // c, xp, yp do not depend on the network's scale: still estimated.
  for (int i : {0, 1, 2}) EXPECT_TRUE(result.cameras[0].sigmas[i].has_value()) << kBundleCameraParamNames[i];
}

TEST(BundleRank, AllFramesAtOneStationIsAnError) {
  sim::SimulatedBlock block = sim::SimulateLunarBlock(sim::Seed000Table9Options(80.0));
  for (FrameSetup& f : block.input.frames) f.position_m = block.input.frames[0].position_m;
  try {
    RunBundleAdjustment(block.input, BundleOptions{});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("one station"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

}  // namespace
}  // namespace platemeter
