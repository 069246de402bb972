// The capping-shutter duty cycle on the plate: one star near the zenith, four
// trails with 2, 3, 4, 5 leading dashes. Mid-exposure times against Table 1
// worked out by hand here; consecutive dots against the sidereal rate
// (15.0411"/s of hour angle) times the sine of the star's polar distance,
// measured from the plate images themselves (refraction off, so the images
// are the unrefracted topocentric directions).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include <erfa.h>
#include <Eigen/Dense>

#include "platemeter/samples/star_field.h"

namespace platemeter::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kArcsec = kPi / 648000.0;

// Seed 001 Table 1, one trail with n leading dashes: dot d (1..25) opens at
// this many seconds after the trail's first opening, and lasts dot_s.
double DotOpen(int n, int d) {
  const int group = (d - 1) / 5, i = (d - 1) % 5;
  const double t0 = 30.0 * n;                                        // leading dashes: 20 s open + 10 s closed
  const double group_start[5] = {0.0, 240.0, 480.0, 1020.0, 1260.0};  // 5 x 40 s (+40 s dash), 5 x 40, 5 x 100, 5 x 40, 5 x 40
  const double period[5] = {40.0, 40.0, 100.0, 40.0, 40.0};
  return t0 + group_start[group] + period[group] * i;
}
double DotLength(int d) {
  const double open[5] = {0.6, 1.2, 3.2, 6.2, 10.0};
  return open[(d - 1) / 5];
}

TEST(StarFieldDutyCycle, FourTrailsOfTwentyFiveDotsAlongTheDiurnalArc) {
  StarFieldOptions o;
  o.place.site = {39.03 * kDeg, -76.93 * kDeg, 50.0};
  o.place.refraction = false;
  o.start_utc = calib::ParseUtcIso8601("1972-05-12T05:30:00Z");
  o.duty_cycle = true;
  o.schedule.leading_dashes = {2, 3, 4, 5};
  o.schedule.break_s = 480.0;
  // Plate length by hand: trails of 30 n + 1460 s and three 480 s breaks.
  const double trail_length[4] = {1520, 1550, 1580, 1610};
  const double trail_start[4] = {0, 1520 + 480, 1520 + 480 + 1550 + 480, 1520 + 480 + 1550 + 480 + 1580 + 480};

  // A star that culminates at mid-plate 0.5 deg north of the zenith: its RA is
  // the local sidereal time then (ERFA's GMST + longitude, to ~1 s).
  double u1, u2, t1, t2;
  ASSERT_EQ(eraDtf2d("UTC", 1972, 5, 12, 5, 30, 0.0, &u1, &u2), 0);
  u2 += 0.5 * (trail_start[3] + trail_length[3]) / 86400.0;
  double tai1, tai2;
  eraUtctai(u1, u2, &tai1, &tai2);
  eraTaitt(tai1, tai2, &t1, &t2);
  calib::CatalogStar star;
  star.id = 7;
  star.ra_rad = eraAnp(eraGmst06(u1, u2, t1, t2) + o.place.site.longitude_rad);
  star.dec_rad = 39.53 * kDeg;
  star.v_mag = 4.0;

  CameraDefinition camera;
  camera.name = "pinhole";
  camera.format_width_mm = 114.0;
  camera.format_height_mm = 114.0;
  camera.nominal_principal_distance_mm = 80.0;
  const PlateLens lens(camera);
  const StarFieldResult r = ComputeStarImages(o, {star}, lens, 114.0, 114.0);
  EXPECT_EQ(r.skipped_below_horizon + r.skipped_outside, 0);

  std::map<std::pair<int, int>, const StarImage*> dots;
  int dashes[5] = {0, 0, 0, 0, 0};
  for (const StarImage& image : r.images) {
    EXPECT_EQ(image.star_id, "KS7");
    if (image.kind == StarImageKind::kTrailDot) {
      EXPECT_TRUE(dots.emplace(std::make_pair(image.trail, image.index), &image).second) << image.id;
      EXPECT_EQ(image.id, "KS7-T" + std::to_string(image.trail) + "-D" + std::to_string(image.index));
    } else {
      ASSERT_EQ(image.kind, StarImageKind::kTrailDash);
      ASSERT_GE(image.trail, 1);
      ASSERT_LE(image.trail, 4);
      ++dashes[image.trail];
    }
  }
  ASSERT_EQ(dots.size(), 100u);
  // Leading dashes plus four separators per trail.
  for (int t = 1; t <= 4; ++t) EXPECT_EQ(dashes[t], (t + 1) + 4) << "trail " << t;

  // The celestial pole in ENU (geodetic latitude, no polar motion).
  const double lat = o.place.site.latitude_rad;
  const Eigen::Vector3d pole(0.0, std::cos(lat), std::sin(lat));
  auto direction = [](const StarImage& image) {
    // Zenith pointing, roll 0: camera frame = ENU; pinhole with c = 80 mm.
    return Eigen::Vector3d(image.mid_mm.x_mm, image.mid_mm.y_mm, 80.0).normalized();
  };
  const double sidereal_arcsec_per_s = 15.0410686;
  double polar_first = -1.0;
  for (int t = 1; t <= 4; ++t) {
    const int n = t + 1;
    double polar_trail = -1.0;
    for (int d = 1; d <= 25; ++d) {
      const StarImage& image = *dots.at({t, d});
      // Mid-time by hand, checked through the ISO string.
      const double mid_s = trail_start[t - 1] + DotOpen(n, d) + DotLength(d) / 2;
      EXPECT_NEAR(image.open_s, trail_start[t - 1] + DotOpen(n, d), 1e-9) << image.id;
      EXPECT_NEAR(image.close_s - image.open_s, DotLength(d), 1e-9) << image.id;
      int iy, im, id, ih, imin;
      double sec;
      ASSERT_EQ(std::sscanf(image.mid_time_utc.c_str(), "%d-%d-%dT%d:%d:%lfZ", &iy, &im, &id, &ih, &imin, &sec), 6);
      const double since_start = (id - 12) * 86400.0 + (ih - 5) * 3600.0 + (imin - 30) * 60.0 + sec;
      EXPECT_NEAR(since_start, mid_s, 0.0006) << image.id << " " << image.mid_time_utc;

      // On one small circle about the pole (within a trail: diurnal
      // aberration, 0.25" toward the east point, moves the polar distance by
      // up to ~0.06" over the whole plate but < 0.02" over one trail).
      const double polar = std::acos(direction(image).dot(pole));
      if (polar_first < 0) polar_first = polar;
      if (polar_trail < 0) polar_trail = polar;
      EXPECT_NEAR((polar - polar_trail) / kArcsec, 0.0, 0.05) << image.id;
      if (d == 1) continue;
      // Spacing from the previous dot: the hour angle advances at the sidereal
      // rate; on the sky that is an arc of dH sin(p) (chord on the sphere).
      const StarImage& previous = *dots.at({t, d - 1});
      const double dt = DotOpen(n, d) + DotLength(d) / 2 - DotOpen(n, d - 1) - DotLength(d - 1) / 2;
      const double dh = sidereal_arcsec_per_s * dt * kArcsec;
      const double expected = 2 * std::asin(std::sin(polar) * std::sin(dh / 2));
      const double got = std::acos(std::clamp(direction(image).dot(direction(previous)), -1.0, 1.0));
      EXPECT_NEAR(got / kArcsec, expected / kArcsec, 0.02) << image.id << " dt " << dt;
      // The star moves west (toward -x, plate x = east) as it culminates.
      EXPECT_LT(image.mid_mm.x_mm, previous.mid_mm.x_mm) << image.id;
    }
  }
  // The hand-made RA: cos(dec)-scaled spacing against the catalog declination
  // (precession 1972 vs J2000 changes dec by a few arcmin: 1 percent here).
  EXPECT_NEAR(std::sin(polar_first), std::cos(star.dec_rad), 0.01);
  // The rendered segment's centre against the mid-exposure image: a few nm.
  EXPECT_LT(r.max_arc_offset_um, 0.05);
}

}  // namespace
}  // namespace platemeter::sim
