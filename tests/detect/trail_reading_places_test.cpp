// A reading's dash places (detect/src/trails/reading_places.cpp, internal; docs/trails.md "Empty dash
// places"), on one star built by hand along a uniform flow: its right reading finds every dash place held,
// a reading one exposure off finds many empty and is refused; a dash hidden beside a bright star says
// nothing, one measured beside it as a blended point at a fraction of its flux holds its place.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "../detect/src/trails/evidence.h"
#include "../detect/src/trails/trail_internal.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/detect/sky_flow.h"
#include "support/trail_hand_plate.h"

namespace platemeter {
namespace {

using namespace trail_internal;

constexpr double kFwhm_px = 2.0;
constexpr double kFluxPerS = 1000.0;          // DN per second of exposure
const PixelPoint kVelocity_px_per_s{0.4, 0.1};

// One star's images, every exposure of the default program, the star at kOrigin at the first dash's mid time.
struct HandStar {
  std::vector<ShutterExposure> schedule = BuildShutterSchedule(DutyCycleScheduleOptions{});
  PixelPoint origin{1000.0, 2500.0};
  double t0_s = schedule.front().mid_s;
  std::vector<DetectedStar> images;
  std::vector<int> trail_of;  // the image's trail number (its right reading's tag)

  PixelPoint At(double t_s) const {
    return {origin.x_px + kVelocity_px_per_s.x_px * (t_s - t0_s), origin.y_px + kVelocity_px_per_s.y_px * (t_s - t0_s)};
  }
  HandStar() {
    for (const ShutterExposure& e : schedule) Add(At(e.mid_s), kFluxPerS * e.duration_s, e, 0);
  }
  void Add(const PixelPoint& p, double flux_dn, const ShutterExposure& e, unsigned flags) {
    DetectedStar d;
    d.point.position_px = p;
    d.point.status = PointStatus::kMeasured;
    d.flux_dn = flux_dn;
    d.sigma_flux_dn = 0.02 * flux_dn;
    d.length_px = e.kind == ExposureKind::kDash ? std::hypot(kVelocity_px_per_s.x_px, kVelocity_px_per_s.y_px) * e.duration_s : 0.0;
    d.angle_deg = std::atan2(kVelocity_px_per_s.y_px, kVelocity_px_per_s.x_px) * 180.0 / M_PI;
    d.flags = flags | (d.length_px > 0 ? kStarElongated : 0u);
    images.push_back(d);
    trail_of.push_back(e.trail);
  }
  int ImageOf(int trail, int dash_index) const {  // the star's image of that dash
    for (size_t i = 0; i < schedule.size(); ++i)
      if (schedule[i].trail == trail && schedule[i].dash_index == dash_index) return static_cast<int>(i);
    return -1;
  }
};

// The places of the star's readings: the seed (its first dash) read at seed_s.
DashPlaces Places(const HandStar& star, double seed_s) {
  const test::HandContext hand(star.images, star.schedule, kFwhm_px, kVelocity_px_per_s);
  EXPECT_TRUE(hand.flow_ok);
  const double span_s = star.schedule.back().mid_s - star.schedule.front().mid_s;
  const FlowPath path(hand.flow, star.origin, span_s);
  return ReadingPlaces(hand.c, hand.all, path, star.origin, seed_s, kFluxPerS, [&](int i) { return star.trail_of[i]; });
}

TEST(ReadingPlaces, ARightReadingFindsItsDashPlacesHeld) {
  const HandStar star;
  const DashPlaces right = Places(star, star.t0_s);
  EXPECT_EQ(right.inside, 2 + 3 + 4 + 5 + 4 * 4);  // leading dashes and four separators per trail
  EXPECT_EQ(right.empty, 0);
  EXPECT_LT(EmptyPlacesLogOdds(right), 0.0);
}

TEST(ReadingPlaces, AReadingAnExposureOffFindsManyEmptyAndIsRefused) {
  const HandStar star;
  // The seed read as the next dash (30 s later) and as the dash before a whole trail's shift (one group).
  for (const double shift_s : {30.0, -30.0, 120.0}) {
    const DashPlaces wrong = Places(star, star.t0_s + shift_s);
    std::printf("[reading places] seed read %+.0f s off: %d of %d places empty, log odds %.1f\n", shift_s, wrong.empty,
                wrong.inside, EmptyPlacesLogOdds(wrong));
    EXPECT_GE(wrong.empty, 6) << "shift " << shift_s << " s: " << wrong.empty << " of " << wrong.inside;
    EXPECT_GT(EmptyPlacesLogOdds(wrong), std::log(kRefuteOdds)) << "shift " << shift_s << " s";
  }
}

TEST(ReadingPlaces, ADashHiddenBesideABrightStarSaysNothingAndAHalvedOneHoldsItsPlace) {
  HandStar star;
  const int hidden = star.ImageOf(2, 5), halved = star.ImageOf(3, 6);
  ASSERT_GE(hidden, 0);
  ASSERT_GE(halved, 0);
  const ShutterExposure& e_hidden = star.schedule[hidden];
  const ShutterExposure& e_halved = star.schedule[halved];
  const PixelPoint across{-kVelocity_px_per_s.y_px / 0.4123, kVelocity_px_per_s.x_px / 0.4123};  // unit normal
  // Hidden: the dash undetected, moved far away (off the flow), and a star 50 times as bright 4 px aside.
  const PixelPoint q = star.images[hidden].point.position_px;
  star.images[hidden].point.position_px = {-5000.0, -5000.0};
  HandStar bare = star;
  star.Add({q.x_px + 4.0 * across.x_px, q.y_px + 4.0 * across.y_px}, 50.0 * kFluxPerS * e_hidden.duration_s,
           e_hidden, 0);
  star.trail_of.back() = 0;
  const DashPlaces without_neighbour = Places(bare, bare.t0_s);
  EXPECT_EQ(without_neighbour.empty, 1);  // the missing dash, alone, is an empty place
  const DashPlaces beside_bright = Places(star, star.t0_s);
  EXPECT_EQ(beside_bright.empty, 0);
  EXPECT_EQ(beside_bright.inside, without_neighbour.inside - 1);  // not counted either way
  // Halved: measured as a point at 40 % of its flux, fitted jointly with a neighbour (blended).
  star.images[halved].flux_dn = 0.4 * kFluxPerS * e_halved.duration_s;
  star.images[halved].length_px = 0.0;
  star.images[halved].flags = kStarBlended;
  EXPECT_EQ(Places(star, star.t0_s).empty, 0);
  star.images[halved].flags = 0;  // the same image, not blended: by flux less than half a dash
  EXPECT_EQ(Places(star, star.t0_s).empty, 1);
}

}  // namespace
}  // namespace platemeter
