// One star, one flux per second (detect/src/trails/trail_pattern.cpp, OtherStarsFlux; docs/trails.md
// "Separators"): a separator trail's sibling found on its arc is the star's only where its images hold the
// star's flux per second. Another star on the same diurnal path a trail's spacing behind (Cairo's KS5615
// behind KS4270, 0.25 mag brighter: 26 % more flux) is not.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "../detect/src/trails/evidence.h"
#include "../detect/src/trails/trail_internal.h"
#include "platemeter/core/duty_cycle.h"
#include "support/trail_hand_plate.h"

namespace platemeter {
namespace {

using namespace trail_internal;

constexpr double kStarFluxPerS = 1000.0;  // DN per second of exposure
const PixelPoint kFlowVelocity_px_per_s{0.4, 0.1};

// Trail 1 of a star and trail 2 of a star scale times as bright, each image's flux off by a deterministic
// +-3 % (the measuring noise of the benchmark plate's bright images), along one uniform flow.
struct TwoTrails {
  std::vector<ShutterExposure> schedule = BuildShutterSchedule(DutyCycleScheduleOptions{});
  std::vector<DetectedStar> images;
  std::vector<std::pair<int, int>> first, second;  // (exposure in its trail, image)

  explicit TwoTrails(double scale) {
    int in_trail[2] = {0, 0};
    for (const ShutterExposure& e : schedule) {
      if (e.trail > 2) continue;
      const double noise = images.size() % 2 == 0 ? 1.03 : 0.97;
      DetectedStar d;
      d.point.status = PointStatus::kMeasured;
      d.point.position_px = {1000.0 + kFlowVelocity_px_per_s.x_px * e.mid_s, 2500.0 + kFlowVelocity_px_per_s.y_px * e.mid_s};
      d.flux_dn = kStarFluxPerS * e.duration_s * noise * (e.trail == 2 ? scale : 1.0);
      d.sigma_flux_dn = 0.02 * d.flux_dn;
      (e.trail == 1 ? first : second).push_back({in_trail[e.trail - 1]++, static_cast<int>(images.size())});
      images.push_back(d);
    }
  }
  bool Other() const {
    const test::HandContext hand(images, schedule, 2.0, kFlowVelocity_px_per_s);
    return OtherStarsFlux(hand.c, first, 0, second, 1);
  }
};

TEST(StarFlux, OneStarsTrailsHoldOneFluxPerSecondAndAnotherStarsDoNot) {
  EXPECT_FALSE(TwoTrails(1.0).Other());
  EXPECT_FALSE(TwoTrails(1.05).Other());  // a thin cloud over one trail: within kStarFluxSpread
  EXPECT_TRUE(TwoTrails(1.26).Other());   // Cairo's KS5615 against KS4270
  EXPECT_TRUE(TwoTrails(1.0 / 1.26).Other());
}

TEST(StarFlux, TooFewImagesCannotTell) {
  TwoTrails two(1.26);
  two.second.resize(kMinFluxImages - 1);
  const test::HandContext hand(two.images, two.schedule, 2.0, kFlowVelocity_px_per_s);
  EXPECT_FALSE(OtherStarsFlux(hand.c, two.first, 0, two.second, 1));
  // Clipped images and a crowd's pieces say nothing of the flux.
  TwoTrails clipped(1.26);
  for (const auto& [j, i] : clipped.second) clipped.images[i].flags |= kStarSaturated;
  const test::HandContext hand_clipped(clipped.images, clipped.schedule, 2.0, kFlowVelocity_px_per_s);
  EXPECT_FALSE(OtherStarsFlux(hand_clipped.c, clipped.first, 0, clipped.second, 1));
}

}  // namespace
}  // namespace platemeter
