// A reading's places (detect/src/trails/reading_places.cpp, internal; docs/trails.md "Empty places"), on one
// star built by hand along a uniform flow: its right reading finds every dash and dot place held, a reading
// one exposure off finds many empty and is refused, and so is one a dot group off by its dot places alone; a
// dash hidden beside a bright star says nothing, one measured beside it as a blended point at a fraction of
// its flux holds its place.
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
  std::vector<ImageTag> tag_of;  // the image's tag: its right reading's (trail number, mid-time)

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
    tag_of.push_back({e.trail, e.mid_s});
  }
  int ImageOf(int trail, int dash_index) const {  // the star's image of that dash
    for (size_t i = 0; i < schedule.size(); ++i)
      if (schedule[i].trail == trail && schedule[i].dash_index == dash_index) return static_cast<int>(i);
    return -1;
  }
};

// The places of the star's readings: the seed (its first dash) read at seed_s; dots of min_dot_flux_dn or more
// counted (by default every dot: the faintest, 0.6 s, holds 600 DN).
DashPlaces Places(const HandStar& star, double seed_s, double min_dot_flux_dn = 0.0) {
  const test::HandContext hand(star.images, star.schedule, kFwhm_px, kVelocity_px_per_s);
  EXPECT_TRUE(hand.flow_ok);
  const double span_s = star.schedule.back().mid_s - star.schedule.front().mid_s;
  const FlowPath path(hand.flow, star.origin, span_s);
  return ReadingPlaces(hand.c, hand.all, path, star.origin, seed_s, kFluxPerS, min_dot_flux_dn,
                       [&](int i) { return star.tag_of[i]; });
}

TEST(ReadingPlaces, ARightReadingFindsItsDashPlacesHeld) {
  const HandStar star;
  const DashPlaces right = Places(star, star.t0_s);
  EXPECT_EQ(right.inside, 2 + 3 + 4 + 5 + 4 * 4);  // leading dashes and four separators per trail
  EXPECT_EQ(right.empty, 0);
  // Each trail's first dot (0.6 s) lies 10 s of motion (4 px) past the end of its last leading dash, 33 times
  // brighter: beside it, it says nothing.
  EXPECT_EQ(right.dot_inside, 4 * 25 - 4);
  EXPECT_EQ(right.dot_empty, 0);
  EXPECT_LT(EmptyPlacesLogOdds(right), 0.0);
  // Dots fainter than the bound are not counted (the detector may have missed them): the 0.6 s ones.
  EXPECT_EQ(Places(star, star.t0_s, 0.9 * kFluxPerS).dot_inside, 4 * 20);
}

// Paris's twin path (docs/trails_record.md, 2026-12-07): a reading whose dash places another star on the
// star's diurnal path holds (its dashes, where the reading puts the star's) is refused by its dot places.
TEST(ReadingPlaces, AReadingWhoseDashPlacesAnotherStarHoldsIsRefusedByItsDots) {
  HandStar star;
  const double shift_s = -240.0;  // the seed read 240 s late: every image predicted 240 s after the star's
  const DashPlaces alone = Places(star, star.t0_s + shift_s);
  for (const ShutterExposure& e : star.schedule)  // the twin's dashes at the reading's dash places
    if (e.kind == ExposureKind::kDash) {
      star.Add(star.At(e.mid_s - shift_s), kFluxPerS * e.duration_s, e, 0);
      star.tag_of.back() = {};  // (not decoded)
    }
  const DashPlaces twin = Places(star, star.t0_s + shift_s);
  std::printf("[reading places] seed read 240 s late: dashes %d of %d empty (%d without the twin), dots %d of %d\n",
              twin.empty, twin.inside, alone.empty, twin.dot_empty, twin.dot_inside);
  EXPECT_GE(alone.empty, 6);
  EXPECT_EQ(twin.empty, 0);
  EXPECT_GE(twin.dot_empty, 20);
  EXPECT_GT(EmptyPlacesLogOdds(twin), std::log(kRefuteOdds));
  // The star's right reading keeps every place held with the twin's dashes beside it.
  const DashPlaces right = Places(star, star.t0_s);
  EXPECT_EQ(right.empty + right.dot_empty, 0);
}

// Lisbon (docs/trails_record.md, 2026-12-07, stop 49): a star already decoded (its images tagged with their
// exposures) whose separator, left untagged in a crowd, seeds a reading one group (240 s) off. Its images
// tagged with other exposures than the reading puts there hold none of its places; untagged, they would.
TEST(ReadingPlaces, AStarsImagesTaggedWithOtherExposuresHoldNoneOfAReadingOneGroupOff) {
  const HandStar tagged;
  HandStar untagged;
  for (ImageTag& t : untagged.tag_of) t = {};
  for (const double shift_s : {240.0, -240.0}) {
    const DashPlaces off = Places(tagged, tagged.t0_s + shift_s), fresh = Places(untagged, untagged.t0_s + shift_s);
    std::printf("[reading places] one group off (%+.0f s): empty %d of %d dash, %d of %d dot places (untagged: %d, %d)\n",
                shift_s, off.empty, off.inside, off.dot_empty, off.dot_inside, fresh.empty, fresh.dot_empty);
    EXPECT_GT(EmptyPlacesLogOdds(off), std::log(kRefuteOdds)) << shift_s;
    EXPECT_LT(fresh.empty + fresh.dot_empty, off.empty + off.dot_empty) << shift_s;
  }
  // Tagged with the reading's own exposures (the star decoded twice, rightly), they hold every place.
  const DashPlaces right = Places(tagged, tagged.t0_s);
  EXPECT_EQ(right.empty + right.dot_empty, 0);
}

// Lisbon's KS13794 (docs/trails_record.md, 2026-12-07, stop 49), before its star was decoded: a dash read one
// group off found its star's own images at most places; in its crowd 5 of 46 places fell empty (leaning
// right). ReadingRefuted compares every other timing of the seed: the right one leaves fewer places empty.
// (Here, without the crowd, the wrong reading is refuted on its own too; the comparison is what is tested.)
TEST(ReadingPlaces, AReadingOneGroupOffGivesWayToTheRightTimingOfItsSeed) {
  HandStar star;
  for (ImageTag& t : star.tag_of) t = {};  // (not decoded)
  const size_t own = star.images.size();
  const PixelPoint across{-kVelocity_px_per_s.y_px / 0.4123, kVelocity_px_per_s.x_px / 0.4123};  // unit normal
  for (size_t i = 0; i < own; ++i) {  // a decoded neighbour 40 px aside: every trail was exposed
    const PixelPoint p = star.images[i].point.position_px;
    star.Add({p.x_px + 40.0 * across.x_px, p.y_px + 40.0 * across.y_px}, star.images[i].flux_dn, star.schedule[i], 0);
  }
  const DashPlaces right = Places(star, star.t0_s);
  for (const double shift_s : {240.0, -240.0}) {
    const DashPlaces off = Places(star, star.t0_s + shift_s);
    std::printf("[reading places] one group off (%+.0f s), star undecoded: %d of %d dash, %d of %d dot places empty, "
                "log odds %.1f; right: %d of %d, %d of %d\n", shift_s, off.empty, off.inside, off.dot_empty,
                off.dot_inside, EmptyPlacesLogOdds(off), right.empty, right.inside, right.dot_empty, right.dot_inside);
    EXPECT_TRUE(OtherReadingLikelier(off, right)) << shift_s;
  }
  EXPECT_EQ(right.empty + right.dot_empty, 0);
  EXPECT_FALSE(OtherReadingLikelier(right, Places(star, star.t0_s + 240.0)));
}

TEST(ReadingPlaces, AReadingAnExposureOffFindsManyEmptyAndIsRefused) {
  const HandStar star;
  // The seed read as the next dash (30 s later) and as the dash before a whole trail's shift (one group).
  for (const double shift_s : {30.0, -30.0, 120.0}) {
    const DashPlaces wrong = Places(star, star.t0_s + shift_s);
    std::printf("[reading places] seed read %+.0f s off: %d of %d dash places empty, %d of %d dot places, log odds %.1f\n",
                shift_s, wrong.empty, wrong.inside, wrong.dot_empty, wrong.dot_inside, EmptyPlacesLogOdds(wrong));
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
  star.tag_of.back() = {};
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

// A lone trail's number against the others' (decoder_flow.cpp, LoneNumberRefuted), with the places of two
// Paris readings (docs/trails_record.md, 2026-12-07). KS18071's T1, counted T2 over another star's dash before
// its run: 3 of 18 dash places and 1 of 4 dot places empty (log odds +3.3, short of refusal), against 0 of 13
// and 0 of 2 as T1. KS6851's right T2 reading: 0 of 12 and 0 of 7 empty, against 0 of 26 and 1 of 31 as T4
// (more places held, log odds -16.0 against -6.2: held places, which every reading predicts, do not decide).
TEST(ReadingPlaces, ALoneReadingLeaningWrongGivesWayToANumberLeavingTwoFewerPlacesEmpty) {
  const auto places = [](int empty, int inside, int dot_empty, int dot_inside) {
    DashPlaces p;
    p.empty = empty, p.inside = inside, p.dot_empty = dot_empty, p.dot_inside = dot_inside;
    return p;
  };
  const DashPlaces counted_t2 = places(3, 18, 1, 4), as_t1 = places(0, 13, 0, 2);
  EXPECT_GT(EmptyPlacesLogOdds(counted_t2), 0.0);
  EXPECT_LT(EmptyPlacesLogOdds(counted_t2), std::log(kRefuteOdds));  // not refused on its own
  EXPECT_TRUE(OtherReadingLikelier(counted_t2, as_t1));
  EXPECT_FALSE(OtherReadingLikelier(as_t1, counted_t2));
  const DashPlaces right_t2 = places(0, 12, 0, 7), as_t4 = places(0, 26, 1, 31);
  EXPECT_FALSE(OtherReadingLikelier(right_t2, as_t4));
  // One empty place fewer is not enough (10 times likelier, not 100), nor, against a reading not leaning
  // wrong, one looking at fewer places (it has fewer to find empty).
  EXPECT_FALSE(OtherReadingLikelier(places(2, 18, 0, 4), places(1, 13, 0, 2)));
  EXPECT_FALSE(OtherReadingLikelier(places(2, 30, 0, 40), places(0, 13, 0, 2)));
  // Lisbon's KS13794 (2026-12-07, stop 49): its flow reading one group off, 4 of 28 dash and 1 of 18 dot
  // places empty (log odds -1.9, leaning right), against 0 of 28 and 0 of 25 for its seed read right.
  const DashPlaces group_off = places(4, 28, 1, 18), read_right = places(0, 28, 0, 25);
  EXPECT_LT(EmptyPlacesLogOdds(group_off), 0.0);
  EXPECT_TRUE(OtherReadingLikelier(group_off, read_right));
  EXPECT_FALSE(OtherReadingLikelier(read_right, group_off));
}

}  // namespace
}  // namespace platemeter
