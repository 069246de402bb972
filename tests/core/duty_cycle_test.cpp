// Duty cycle of seed 001 Table 1. Expected times are derived by hand from the
// table: a trail with N leading dashes lasts
//   N*30 + 5*40 + 40 + 5*40 + 40 + 5*100 + 40 + 5*40 + 40 + 5*40 = 30 N + 1460 s.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

constexpr double kEps = 1e-9;

std::vector<ShutterExposure> TrailOf(const std::vector<ShutterExposure>& all, int trail) {
  std::vector<ShutterExposure> out;
  std::copy_if(all.begin(), all.end(), std::back_inserter(out),
               [&](const ShutterExposure& e) { return e.trail == trail; });
  return out;
}

TEST(DutyCycle, TrailDurationsByHand) {
  const DutyCycleProgram p = DutyCycleProgram::Table1();
  EXPECT_NEAR(TrailDuration(p, 2), 1520.0, kEps);
  EXPECT_NEAR(TrailDuration(p, 3), 1550.0, kEps);
  EXPECT_NEAR(TrailDuration(p, 5), 1610.0, kEps);
}

TEST(DutyCycle, FirstTrailWithTwoLeadingDashes) {
  DutyCycleScheduleOptions o;
  o.start_s = 1000.0;
  const auto trail = TrailOf(BuildShutterSchedule(o), 1);
  // 2 leading dashes + 25 dots + 4 separator dashes.
  ASSERT_EQ(trail.size(), 31u);
  const auto dots = std::count_if(trail.begin(), trail.end(),
                                  [](const ShutterExposure& e) { return e.kind == ExposureKind::kDot; });
  EXPECT_EQ(dots, 25);
  // Leading dashes: 20 s open at 0 and 30 s (2 x 30 s of dashes).
  EXPECT_EQ(trail[0].kind, ExposureKind::kDash);
  EXPECT_NEAR(trail[0].open_s, 1000.0, kEps);
  EXPECT_NEAR(trail[0].close_s, 1020.0, kEps);
  EXPECT_NEAR(trail[0].mid_s, 1010.0, kEps);
  EXPECT_NEAR(trail[1].open_s, 1030.0, kEps);
  EXPECT_EQ(trail[1].dash_index, 2);
  EXPECT_EQ(trail[1].group, 0);
  // Dot 1 (0.6 s) opens at 60 s, mid at 60.3 s; dot 5 opens at 60 + 4*40 = 220 s.
  EXPECT_EQ(trail[2].kind, ExposureKind::kDot);
  EXPECT_EQ(trail[2].dot_index, 1);
  EXPECT_EQ(trail[2].group, 1);
  EXPECT_NEAR(trail[2].open_s, 1060.0, kEps);
  EXPECT_NEAR(trail[2].mid_s, 1060.3, kEps);
  EXPECT_NEAR(trail[2].duration_s, 0.6, kEps);
  EXPECT_NEAR(trail[6].open_s, 1220.0, kEps);
  // Separator dash after group 1 at 260 s, open 20 s.
  EXPECT_EQ(trail[7].kind, ExposureKind::kDash);
  EXPECT_EQ(trail[7].dash_index, 3);
  EXPECT_EQ(trail[7].group, 1);
  EXPECT_NEAR(trail[7].open_s, 1260.0, kEps);
  EXPECT_NEAR(trail[7].close_s, 1280.0, kEps);
  // Dot 6 (1.2 s) at 300 s, mid 300.6 s.
  EXPECT_EQ(trail[8].dot_index, 6);
  EXPECT_EQ(trail[8].group, 2);
  EXPECT_NEAR(trail[8].mid_s, 1300.6, kEps);
  // Group 3 (3.2 s dots, 100 s period): dots 11..15 at 540, 640, ..., 940 s.
  const auto dot11 = std::find_if(trail.begin(), trail.end(), [](auto& e) { return e.dot_index == 11; });
  const auto dot15 = std::find_if(trail.begin(), trail.end(), [](auto& e) { return e.dot_index == 15; });
  EXPECT_NEAR(dot11->open_s, 1540.0, kEps);
  EXPECT_NEAR(dot15->open_s, 1940.0, kEps);
  EXPECT_NEAR(dot15->mid_s, 1941.6, kEps);
  EXPECT_EQ(dot15->table_row, 6);
  // Dots 16..20 (6.2 s) from 1080 s; dots 21..25 (10 s) from 1320 s; last at 1480 s.
  const auto dot16 = std::find_if(trail.begin(), trail.end(), [](auto& e) { return e.dot_index == 16; });
  EXPECT_NEAR(dot16->open_s, 2080.0, kEps);
  EXPECT_NEAR(dot16->mid_s, 2083.1, kEps);
  EXPECT_EQ(trail.back().dot_index, 25);
  EXPECT_EQ(trail.back().group, 5);
  EXPECT_NEAR(trail.back().open_s, 2480.0, kEps);
  EXPECT_NEAR(trail.back().close_s, 2490.0, kEps);
}

TEST(DutyCycle, FourTrailsNumberedAndSeparatedByBreaks) {
  DutyCycleScheduleOptions o;  // 2,3,4,5 dashes, 8 min breaks, start 0
  const auto all = BuildShutterSchedule(o);
  // 14 leading dashes + 4 x (25 dots + 4 separators).
  EXPECT_EQ(all.size(), 130u);
  // Trail starts: 0; 1520 + 480 = 2000; 2000 + 1550 + 480 = 4030; 4030 + 1580 + 480 = 6090.
  const double starts[4] = {0.0, 2000.0, 4030.0, 6090.0};
  const int dashes[4] = {2, 3, 4, 5};
  for (int t = 1; t <= 4; ++t) {
    const auto trail = TrailOf(all, t);
    ASSERT_EQ(trail.size(), static_cast<size_t>(dashes[t - 1] + 29)) << "trail " << t;
    EXPECT_NEAR(trail.front().open_s, starts[t - 1], kEps);
    // Leading dashes are the first N exposures, all 20 s, 30 s apart.
    for (int k = 0; k < dashes[t - 1]; ++k) {
      EXPECT_EQ(trail[k].kind, ExposureKind::kDash);
      EXPECT_NEAR(trail[k].open_s, starts[t - 1] + 30.0 * k, kEps);
    }
    EXPECT_EQ(trail[dashes[t - 1]].kind, ExposureKind::kDot);
    // Last dot opens 40 s before the trail's end (30 N + 1460).
    EXPECT_NEAR(trail.back().open_s, starts[t - 1] + 30.0 * dashes[t - 1] + 1420.0, kEps);
  }
  // The plate ends 30 s after the last dot closes: 6090 + 1610 = 7700 s.
  EXPECT_NEAR(all.back().close_s + 30.0, 7700.0, kEps);
  // Time order.
  for (size_t i = 1; i < all.size(); ++i) EXPECT_GT(all[i].open_s, all[i - 1].close_s);
}

TEST(DutyCycle, CustomOrderAndBreak) {
  DutyCycleScheduleOptions o;
  o.leading_dashes = {5, 2};
  o.break_s = 600.0;
  const auto all = BuildShutterSchedule(o);
  const auto t2 = TrailOf(all, 2);
  // Trail 1 (5 dashes) lasts 1610 s; trail 2 starts 1610 + 600.
  EXPECT_NEAR(t2.front().open_s, 2210.0, kEps);
  EXPECT_EQ(t2.size(), 31u);
}

TEST(DutyCycle, InvalidOptionsRejected) {
  std::string why;
  DutyCycleScheduleOptions o;
  EXPECT_TRUE(o.Check(&why)) << why;

  auto bad = o;
  bad.break_s = 360.0;  // 6 min < 7 min
  EXPECT_FALSE(bad.Check(&why));
  EXPECT_NE(why.find("break"), std::string::npos);
  EXPECT_THROW(BuildShutterSchedule(bad), Error);

  bad = o;
  bad.break_s = 660.0;
  EXPECT_FALSE(bad.Check(&why));

  bad = o;
  bad.leading_dashes = {2, 3, 6, 5};
  EXPECT_FALSE(bad.Check(&why));
  bad.leading_dashes = {2, 2, 4, 5};  // trail not identifiable
  EXPECT_FALSE(bad.Check(&why));
  bad.leading_dashes = {2, 3, 4, 5, 1};
  EXPECT_FALSE(bad.Check(&why));
  bad.leading_dashes = {};
  EXPECT_FALSE(bad.Check(&why));

  bad = o;
  bad.program.rows[3].open_s = 0.0;
  EXPECT_FALSE(bad.Check(&why));
  EXPECT_NE(why.find("row 4"), std::string::npos);
  bad = o;
  bad.program.rows[1].repetitions = 0;
  EXPECT_FALSE(bad.Check(&why));
}

}  // namespace
}  // namespace platemeter
