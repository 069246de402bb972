// A flow reading's seed merged from two stars' dashes (detect/src/trails/trail_flow.cpp DecodeByFlow,
// internal; docs/trails_record.md "A seed merged from two stars' dashes"). Two stars of one flux on one
// diurnal path, the second 1020 s behind the first: dashes of the two 1020 s apart (a trail's first and
// fourth separators, among others) fall on one place, one image of twice a dash's flux. Read with that
// flux, such a seed lines up the second star's dots one group early (their durations about twice the read
// ones); the decoder must not tag that (before kMergedSeedShare it did, read at 1050 s). Truth: the stars'
// own exposures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "../detect/src/trails/trail_internal.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/detect/sky_flow.h"
#include "support/trail_hand_plate.h"

namespace platemeter {
namespace {

using namespace trail_internal;

constexpr double kTwinFwhm_px = 2.0;
constexpr double kTwinFluxPerS = 1000.0;           // DN per second of exposure, both stars
const PixelPoint kTwinVelocity_px_per_s{0.05, 0.18};  // a slow star's (Denver's pair: 0.18 px/s)
constexpr double kTwinBehind_s = 1020.0;           // the second star's delay: a trail's separators 1 and 4 apart

struct TwinPlate {
  std::vector<ShutterExposure> schedule = BuildShutterSchedule(DutyCycleScheduleOptions{});
  PixelPoint origin{2000.0, 1500.0};  // the first star at the schedule's start
  std::vector<DetectedStar> images;
  std::vector<double> truth_s[2];  // per image: the mid time of its exposure for star 0 and 1 (NaN: not it)

  PixelPoint At(int star, double t_s) const {
    const double dt = t_s - schedule.front().mid_s - (star == 1 ? kTwinBehind_s : 0.0);
    return {origin.x_px + kTwinVelocity_px_per_s.x_px * dt, origin.y_px + kTwinVelocity_px_per_s.y_px * dt};
  }
  TwinPlate() {
    const double speed = std::hypot(kTwinVelocity_px_per_s.x_px, kTwinVelocity_px_per_s.y_px);
    for (int star = 0; star < 2; ++star)
      for (const ShutterExposure& e : schedule) {
        const PixelPoint p = At(star, e.mid_s);
        const double length_px = e.kind == ExposureKind::kDash ? speed * e.duration_s : 0.0;
        // Where the other star's image lies on the same place, one image holds both (a merge).
        int merged = -1;
        for (size_t i = 0; i < images.size(); ++i)
          if (Dist(images[i].point.position_px, p) < 0.5 * kTwinFwhm_px) merged = static_cast<int>(i);
        if (merged >= 0) {
          images[merged].flux_dn += kTwinFluxPerS * e.duration_s;
          images[merged].sigma_flux_dn = 0.02 * images[merged].flux_dn;
          truth_s[star][merged] = e.mid_s;
          continue;
        }
        DetectedStar d;
        d.point.position_px = p;
        d.point.status = PointStatus::kMeasured;
        d.flux_dn = kTwinFluxPerS * e.duration_s;
        d.sigma_flux_dn = 0.02 * d.flux_dn;
        d.length_px = length_px;
        d.angle_deg = std::atan2(kTwinVelocity_px_per_s.y_px, kTwinVelocity_px_per_s.x_px) * 180.0 / M_PI;
        d.flags = length_px > 0 ? kStarElongated : 0u;
        images.push_back(d);
        truth_s[star].push_back(e.mid_s);
        truth_s[1 - star].push_back(std::nan(""));
      }
  }
};

TEST(MergedSeed, ASeedOfTwoStarsDashesTagsNoStarAtAWrongTime) {
  const TwinPlate plate;
  const test::HandContext hand(plate.images, plate.schedule, kTwinFwhm_px, kTwinVelocity_px_per_s);
  ASSERT_TRUE(hand.flow_ok);
  const Context& c = hand.c;

  int merged_dashes = 0, decoded = 0;
  for (int i = 0; i < static_cast<int>(plate.images.size()); ++i) {
    if (std::isnan(plate.truth_s[0][i]) || std::isnan(plate.truth_s[1][i]) || plate.images[i].length_px <= 0) continue;
    ++merged_dashes;
    FlowStar star;
    if (!DecodeByFlow(c, hand.all, hand.flow, i, {}, &star)) continue;
    ++decoded;
    // Decoded: the reading must be one star's, at that star's time of this image, and take only its images.
    const int who = std::abs(star.seed_s - plate.truth_s[0][i]) < 1e-6 ? 0 : 1;
    EXPECT_NEAR(star.seed_s, plate.truth_s[who][i], 1e-6) << "seed " << i << " read at " << star.seed_s << " s";
    for (size_t t = 0; t < star.taken.size(); ++t)
      for (const auto& [j, k] : star.taken[t])
        EXPECT_NEAR(plate.truth_s[who][k], c.per_trail[t][j].mid_s, 1e-6) << "image " << k << " taken wrongly";
  }
  std::printf("[merged seed] %d merged dashes, %d decoded\n", merged_dashes, decoded);
  EXPECT_GE(merged_dashes, 4);  // the case exists (9 merged dashes with the default schedule)
}

}  // namespace
}  // namespace platemeter
