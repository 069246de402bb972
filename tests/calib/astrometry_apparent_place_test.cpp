// Observed places: the library (eraApco13 + eraAtciq + eraAtioq) against an
// independent classical reduction written here step by step (linear space
// motion and parallax by hand, light deflection and aberration by formula,
// IAU 2006/2000A precession-nutation matrix and GAST, horizon frame by hand,
// diurnal aberration from the site velocity, refraction A tan z + B tan^3 z
// solved for the observed zenith distance).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <erfa.h>
#include <Eigen/Dense>

#include "platemeter/calib/apparent_place.h"
#include "platemeter/core/error.h"
#include "support/sexagesimal.h"

namespace platemeter::calib {
namespace {

using testing::Dms;
using testing::Hms;

constexpr double kPi = std::numbers::pi;
constexpr double kArcsec = kPi / 648000.0;
constexpr double kMas = kArcsec / 1000.0;

CatalogStar Star(double ra, double dec, double pmra_mas, double pmdec_mas, double plx_mas, double rv = 0.0) {
  CatalogStar s;
  s.ra_rad = ra;
  s.dec_rad = dec;
  s.pm_ra_mas_yr = pmra_mas;
  s.pm_dec_mas_yr = pmdec_mas;
  s.parallax_mas = plx_mas;
  s.radial_velocity_km_s = rv;
  return s;
}

// Hipparcos values (J2000, mu_alpha* with cos dec).
CatalogStar Regulus() { return Star(Hms(10, 8, 22.311), Dms(+1, 11, 58, 1.95), -249.40, 4.91, 42.09); }
CatalogStar Castor() { return Star(Hms(7, 34, 35.873), Dms(+1, 31, 53, 17.82), -206.33, -148.18, 63.27); }
CatalogStar Arcturus() { return Star(Hms(14, 15, 39.672), Dms(+1, 19, 10, 56.68), -1093.45, -1999.40, 88.85); }
CatalogStar Procyon() { return Star(Hms(7, 39, 18.119), Dms(+1, 5, 13, 29.96), -716.57, -1034.58, 285.93); }
CatalogStar Polaris() { return Star(Hms(2, 31, 49.095), Dms(+1, 89, 15, 50.79), 44.22, -11.74, 7.56); }

struct Topocentric {
  Eigen::Vector3d enu;  // x east, y north, z up
  double az_rad, alt_rad;
};

// The independent reduction.
Topocentric ClassicalReduction(const CatalogStar& s, const ApparentPlaceOptions& o, const UtcInstant& utc) {
  double tai1, tai2, tt1, tt2, ut11, ut12;
  EXPECT_GE(eraUtctai(utc.jd1, utc.jd2, &tai1, &tai2), 0);
  eraTaitt(tai1, tai2, &tt1, &tt2);
  EXPECT_GE(eraUtcut1(utc.jd1, utc.jd2, o.ut1_minus_utc_s, &ut11, &ut12), 0);
  // Earth heliocentric and barycentric position/velocity (au, au/day); TDB ~ TT here.
  double pvh[2][3], pvb[2][3];
  eraEpv00(tt1, tt2, pvh, pvb);
  const Eigen::Vector3d eb(pvb[0][0], pvb[0][1], pvb[0][2]);
  const Eigen::Vector3d vb(pvb[1][0], pvb[1][1], pvb[1][2]);
  const Eigen::Vector3d eh(pvh[0][0], pvh[0][1], pvh[0][2]);

  // 1. Space motion (linear) and annual parallax, in the BCRS.
  const double years = ((tt1 - 2451545.0) + tt2) / 365.25;
  const double ca = std::cos(s.ra_rad), sa = std::sin(s.ra_rad);
  const double cd = std::cos(s.dec_rad), sd = std::sin(s.dec_rad);
  const Eigen::Vector3d u(cd * ca, cd * sa, sd), east(-sa, ca, 0), north(-sd * ca, -sd * sa, cd);
  Eigen::Vector3d p = u + years * (s.pm_ra_mas_yr * kMas * east + s.pm_dec_mas_yr * kMas * north) -
                      s.parallax_mas * kMas * eb;
  p.normalize();
  // 2. Light deflection by the Sun: 2GM/(c^2 r) (q x (e x q)) / (1 + q.e).
  const double em = eh.norm();
  const Eigen::Vector3d e = eh / em;
  const double g = 1.97412574336e-8 / em;  // 2 GM_sun / c^2 in au, over the distance
  p = (p + g * p.cross(e.cross(p)) / (1.0 + p.dot(e))).normalized();
  // 3. Annual aberration, first order in v/c (second order < 0.003").
  const double c_au_day = 299792458.0 * 86400.0 / 149597870700.0;
  p = (p + vb / c_au_day).normalized();
  // 4. Precession-nutation (GCRS -> true equator and equinox of date).
  double rnpb[3][3];
  eraPnm06a(tt1, tt2, rnpb);
  Eigen::Matrix3d npb;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) npb(i, j) = rnpb[i][j];
  // 5. Earth rotation by Greenwich apparent sidereal time (polar motion 0).
  const double gast = eraGst06a(ut11, ut12, tt1, tt2);
  const Eigen::Matrix3d rz = Eigen::AngleAxisd(-gast, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Vector3d d = rz * npb * p;  // terrestrial frame
  // 6. Diurnal aberration: site velocity omega x r (WGS84 geocentric position).
  double xyz[3];
  eraGd2gc(1, o.site.longitude_rad, o.site.latitude_rad, o.site.height_m, xyz);
  const double omega = 2.0 * kPi * 1.00273781191135448 / 86400.0;
  const Eigen::Vector3d v_site = Eigen::Vector3d(0, 0, omega).cross(Eigen::Vector3d(xyz[0], xyz[1], xyz[2]));
  d = (d + v_site / 299792458.0).normalized();
  // 7. Local horizon frame at the geodetic position.
  const double cl = std::cos(o.site.longitude_rad), sl = std::sin(o.site.longitude_rad);
  const double cp = std::cos(o.site.latitude_rad), sp = std::sin(o.site.latitude_rad);
  const Eigen::Vector3d ue(-sl, cl, 0), un(-sp * cl, -sp * sl, cp), uu(cp * cl, cp * sl, sp);
  Topocentric t;
  t.enu = Eigen::Vector3d(d.dot(ue), d.dot(un), d.dot(uu));
  t.az_rad = std::atan2(t.enu.x(), t.enu.y());
  if (t.az_rad < 0) t.az_rad += 2 * kPi;
  double z = std::acos(std::clamp(t.enu.z(), -1.0, 1.0));
  // 8. Refraction: z_vacuum = Z + A tan Z + B tan^3 Z, Z the observed zenith distance.
  if (o.refraction) {
    double a, b;
    eraRefco(o.pressure_hpa, o.temperature_degC, o.relative_humidity, o.wavelength_um, &a, &b);
    double zo = z;
    for (int i = 0; i < 20; ++i) {
      const double tz = std::tan(zo);
      zo = z - a * tz - b * tz * tz * tz;
    }
    z = zo;
  }
  t.alt_rad = kPi / 2 - z;
  t.enu = Eigen::Vector3d(std::sin(z) * std::sin(t.az_rad), std::sin(z) * std::cos(t.az_rad), std::cos(z));
  return t;
}

ApparentPlaceOptions SiteOptions() {
  ApparentPlaceOptions o;
  o.site = ObservingSite::Seed004CameraMount();
  o.pressure_hpa = 850.0;  // ~1500 m
  o.temperature_degC = 8.0;
  o.relative_humidity = 0.3;
  o.wavelength_um = 0.55;
  return o;
}

double AngleArcsec(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kArcsec;
}

TEST(ApparentPlace, Seed004SiteValues) {
  const ObservingSite s = ObservingSite::Seed004CameraMount();
  EXPECT_NEAR(s.latitude_rad * 180 / kPi, 32.533333333, 1e-8);
  EXPECT_NEAR(s.longitude_rad * 180 / kPi, -106.6, 1e-8);
  EXPECT_EQ(s.height_m, 1501.0);
}

TEST(ApparentPlace, MatchesIndependentClassicalReduction) {
  // Seed 004 exposure 6 PRE was at 5h01.5m GMT; the date here is chosen (1974).
  const UtcInstant utc = ParseUtcIso8601("1974-03-15T05:01:30Z");
  int compared = 0;
  for (bool refraction : {false, true}) {
    ApparentPlaceOptions o = SiteOptions();
    o.refraction = refraction;
    o.ut1_minus_utc_s = -0.35;  // exercised on both sides
    const ApparentPlaceCalculator calc(o, utc);
    for (const CatalogStar& s : {Regulus(), Castor(), Procyon(), Polaris()}) {
      const ObservedPlace lib = calc.Observe(s);
      const Topocentric ref = ClassicalReduction(s, o, utc);
      ASSERT_GT(ref.alt_rad, 25.0 * kPi / 180) << "test star below 25 deg: pick another time";
      EXPECT_LT(AngleArcsec(lib.enu, ref.enu), 0.05) << "star ra " << s.ra_rad << " refraction " << refraction;
      EXPECT_NEAR(lib.altitude_rad, ref.alt_rad, 0.05 * kArcsec);
      EXPECT_NEAR(std::remainder(lib.azimuth_rad - ref.az_rad, 2 * kPi) * std::cos(ref.alt_rad), 0.0,
                  0.05 * kArcsec);
      // The ENU vector is the unit vector of (az, alt).
      EXPECT_NEAR(lib.enu.norm(), 1.0, 1e-12);
      EXPECT_NEAR(std::asin(lib.enu.z()), lib.altitude_rad, 1e-9);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 8);
}

TEST(ApparentPlace, Ut1OffsetMovesHourAngle) {
  // 0.9 s of UT1-UTC is 0.9 * 15.041" of hour angle (sidereal rate).
  const UtcInstant utc = ParseUtcIso8601("1974-03-15T05:01:30Z");
  ApparentPlaceOptions o = SiteOptions();
  o.refraction = false;
  const ObservedPlace a = ObserveStar(Regulus(), o, utc);
  o.ut1_minus_utc_s = 0.9;
  const ObservedPlace b = ObserveStar(Regulus(), o, utc);
  EXPECT_NEAR((b.hour_angle_rad - a.hour_angle_rad) / kArcsec, 0.9 * 15.0410686, 0.01);
}

TEST(ApparentPlace, RefractionAtLowAltitude) {
  // Arcturus rises in the east around 04:00 UTC at this site and date; at about
  // 20 deg altitude refraction is ~2.6' at sea level.
  const UtcInstant utc = ParseUtcIso8601("1974-03-15T05:01:30Z").PlusSeconds(-1800.0);
  ApparentPlaceOptions on = SiteOptions();
  ApparentPlaceOptions off = on;
  off.refraction = false;
  const ObservedPlace r = ObserveStar(Arcturus(), on, utc);
  const ObservedPlace v = ObserveStar(Arcturus(), off, utc);
  const double h_deg = r.altitude_rad * 180 / kPi;
  ASSERT_GT(h_deg, 12.0);
  ASSERT_LT(h_deg, 25.0);
  // Refraction lifts the star, straight up: azimuth unchanged.
  EXPECT_NEAR(std::remainder(r.azimuth_rad - v.azimuth_rad, 2 * kPi) / kArcsec, 0.0, 0.01);
  const double refraction_arcsec = (r.altitude_rad - v.altitude_rad) / kArcsec;
  // Bennett (1982): R' = cot(h + 7.31/(h + 4.4)) arcmin at 1010 hPa, 10 C, scaled
  // by (P/1010)(283/(273+T)); stated accuracy 0.07' (4.2"). Allowed: 4.2" + 1"
  // for the A tan z + B tan^3 z model at z ~ 70-78 deg.
  const double bennett_arcmin = 1.0 / std::tan((h_deg + 7.31 / (h_deg + 4.4)) * kPi / 180) *
                                (on.pressure_hpa / 1010.0) * (283.0 / (273.0 + on.temperature_degC));
  EXPECT_NEAR(refraction_arcsec, bennett_arcmin * 60.0, 5.2) << "altitude " << h_deg << " deg";
  // And it equals A tan Z + B tan^3 Z with ERFA's constants (Z observed).
  double a, b;
  eraRefco(on.pressure_hpa, on.temperature_degC, on.relative_humidity, on.wavelength_um, &a, &b);
  const double tz = std::tan(kPi / 2 - r.altitude_rad);
  EXPECT_NEAR(refraction_arcsec, (a * tz + b * tz * tz * tz) / kArcsec, 0.05);
}

TEST(ApparentPlace, BarnardsStarThirtyYears) {
  // Barnard's star (Hipparcos): mu_alpha* = -798.58, mu_delta = 10328.12 mas/yr,
  // parallax 548.31 mas, RV -110.51 km/s. Over 30 yr the linear displacement is
  // hypot(-798.58, 10328.12) * 30 mas = 310.768".
  const CatalogStar barnard =
      Star(Hms(17, 57, 48.498), Dms(+1, 4, 41, 36.21), -798.58, 10328.12, 548.31, 0.0);
  const CatalogStar moved = PropagateCatalogStar(barnard, 2030.0);
  EXPECT_NEAR(AngularSeparation(barnard.ra_rad, barnard.dec_rad, moved.ra_rad, moved.dec_rad) / kArcsec, 310.768,
              0.05);
  // Direction: position angle atan2(-798.58, 10328.12) = -4.421 deg (north through east).
  const double dra = std::remainder(moved.ra_rad - barnard.ra_rad, 2 * kPi) * std::cos(barnard.dec_rad);
  const double ddec = moved.dec_rad - barnard.dec_rad;
  EXPECT_NEAR(std::atan2(dra, ddec) * 180 / kPi, -4.421, 0.01);
  EXPECT_DOUBLE_EQ(moved.epoch_jyear, 2030.0);

  // With the radial velocity the star approaches: the displacement grows by the
  // perspective factor d / (d + v_r t): v_r t / d = -23.312 au/yr * 30 yr /
  // 376183 au = -1.859e-3, so 310.768" / (1 - 1.859e-3) = 311.347".
  CatalogStar approaching = barnard;
  approaching.radial_velocity_km_s = -110.51;
  const CatalogStar moved2 = PropagateCatalogStar(approaching, 2030.0);
  EXPECT_NEAR(AngularSeparation(barnard.ra_rad, barnard.dec_rad, moved2.ra_rad, moved2.dec_rad) / kArcsec, 311.347,
              0.05);
  // Parallax grows as the star comes closer: 548.31 * d/(d + v_r t) (radial part).
  EXPECT_NEAR(moved2.parallax_mas, 548.31 / (1 - 1.859e-3), 0.05);

  // Without a parallax: great-circle motion at the catalog rate.
  CatalogStar no_px = barnard;
  no_px.parallax_mas = 0.0;
  const CatalogStar moved3 = PropagateCatalogStar(no_px, 2030.0);
  EXPECT_NEAR(AngularSeparation(barnard.ra_rad, barnard.dec_rad, moved3.ra_rad, moved3.dec_rad) / kArcsec, 310.768,
              0.05);
}

TEST(ApparentPlace, CatalogEpochOtherThanJ2000) {
  // The same star given at the Hipparcos epoch 1991.25 observes identically.
  const UtcInstant utc = ParseUtcIso8601("1974-03-15T05:01:30Z");
  const ApparentPlaceOptions o = SiteOptions();
  const CatalogStar at2000 = Arcturus();
  const CatalogStar at1991 = PropagateCatalogStar(at2000, 1991.25);
  const double moved = AngularSeparation(at2000.ra_rad, at2000.dec_rad, at1991.ra_rad, at1991.dec_rad) / kArcsec;
  EXPECT_NEAR(moved, 8.75 * std::hypot(1.09345, 1.99940), 0.02);  // 8.75 yr of proper motion
  const ObservedPlace a = ObserveStar(at2000, o, utc);
  const ObservedPlace b = ObserveStar(at1991, o, utc);
  EXPECT_LT(AngleArcsec(a.enu, b.enu), 0.001);
}

TEST(UtcTime, ParsesIso8601ToMjd) {
  // 1974-01-01 is MJD 42048 (1970-01-01 = 40587, + 3*365 + 366); + 31 + 28 + 14
  // days = 42121 for 1974-03-15; 05:01:30 = 18090 s = 0.209375 d.
  EXPECT_NEAR(ParseUtcIso8601("1974-03-15T05:01:30Z").Mjd(), 42121.209375, 1e-9);
  EXPECT_NEAR(ParseUtcIso8601("1974-03-15 05:01:30.5").Mjd(), 42121.209375 + 0.5 / 86400, 1e-9);
  EXPECT_NEAR(ParseUtcIso8601("1974-03-15T05:01+00:00").Mjd(), 42121.209375 - 30.0 / 86400, 1e-9);
  EXPECT_NEAR(UtcFromMjd(42121.209375).Mjd(), 42121.209375, 1e-9);
  EXPECT_EQ(FormatUtcIso8601(ParseUtcIso8601("1974-03-15T05:01:30.25Z"), 2), "1974-03-15T05:01:30.25Z");
  // A real leap second: 1972-06-30T23:59:60.
  EXPECT_NO_THROW(ParseUtcIso8601("1972-06-30T23:59:60.5Z"));
  EXPECT_THROW(ParseUtcIso8601("1973-06-30T23:59:60.5Z"), Error);
  EXPECT_THROW(ParseUtcIso8601("1974-13-01T00:00:00Z"), Error);
  EXPECT_THROW(ParseUtcIso8601("1974-02-30T00:00:00Z"), Error);
  EXPECT_THROW(ParseUtcIso8601("last night"), Error);
  try {
    ParseUtcIso8601("1974-03-15T05:01:30+02:00");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("UTC"), std::string::npos);
  }
}

TEST(ApparentPlace, OptionsChecked) {
  ApparentPlaceOptions o = SiteOptions();
  std::string why;
  EXPECT_TRUE(o.Check(&why)) << why;
  o.relative_humidity = 50.0;  // percent instead of a fraction
  EXPECT_FALSE(o.Check(&why));
  EXPECT_THROW(ApparentPlaceCalculator(o, ParseUtcIso8601("1974-03-15T05:01:30Z")), Error);
  o = SiteOptions();
  o.ut1_minus_utc_s = 1.2;
  EXPECT_FALSE(o.Check(&why));
  o = SiteOptions();
  o.site.latitude_rad = 2.0;
  EXPECT_FALSE(o.Check(&why));
}

}  // namespace
}  // namespace platemeter::calib
