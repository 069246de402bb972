// The image of a catalog star on the simulated plate against an independent
// computation written here: eraAtco13 (ICRS -> observed in one call) for the
// direction, then this test's own gnomonic projection with the camera's
// principal distance and no distortion (zenith pointing: plate x east, y north).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <erfa.h>
#include <Eigen/Dense>

#include "platemeter/grids/registry.h"
#include "platemeter/samples/star_field.h"
#include "platemeter/core/angles.h"

namespace platemeter::sim {
namespace {


// Vega, Hipparcos (J2000, mu_alpha* with cos dec).
calib::CatalogStar Vega() {
  calib::CatalogStar s;
  s.id = 91262;  // HIP number; only an id here
  s.ra_rad = (18.0 + 36.0 / 60 + 56.336 / 3600) * 15.0 * kRadPerDeg;
  s.dec_rad = (38.0 + 47.0 / 60 + 1.28 / 3600) * kRadPerDeg;
  s.pm_ra_mas_yr = 200.94;
  s.pm_dec_mas_yr = 286.23;
  s.parallax_mas = 128.93;
  s.v_mag = 0.03;
  return s;
}

CameraDefinition PinholeCamera(double c_mm) {
  CameraDefinition camera;
  camera.name = "pinhole";
  camera.format_width_mm = 114.0;
  camera.format_height_mm = 114.0;
  camera.nominal_principal_distance_mm = c_mm;
  return camera;
}

// Beltsville, MD (approximate), a May night.
StarFieldOptions Beltsville(const std::string& utc) {
  StarFieldOptions o;
  o.place.site = {39.03 * kRadPerDeg, -76.93 * kRadPerDeg, 50.0};
  o.place.pressure_hpa = 1005.0;
  o.place.temperature_degC = 12.0;
  o.place.relative_humidity = 0.6;
  o.place.wavelength_um = 0.45;
  o.start_utc = calib::ParseUtcIso8601(utc);
  o.duty_cycle = false;
  o.single_exposure_s = 0.0;  // a point image at start_utc
  return o;
}

// Independent observed direction (ENU) with eraAtco13.
Eigen::Vector3d IndependentEnu(const calib::CatalogStar& s, const StarFieldOptions& o, double utc1, double utc2) {
  double aob, zob, hob, dob, rob, eo;
  const double pr = s.pm_ra_mas_yr / 1000.0 * kRadPerArcsec / std::cos(s.dec_rad);  // dRA/dt, rad/yr
  const double pd = s.pm_dec_mas_yr / 1000.0 * kRadPerArcsec;
  const int status = eraAtco13(s.ra_rad, s.dec_rad, pr, pd, s.parallax_mas / 1000.0, 0.0, utc1, utc2, 0.0,
                               o.place.site.longitude_rad, o.place.site.latitude_rad, o.place.site.height_m, 0.0, 0.0,
                               o.place.pressure_hpa, o.place.temperature_degC, o.place.relative_humidity,
                               o.place.wavelength_um, &aob, &zob, &hob, &dob, &rob, &eo);
  EXPECT_EQ(status, 0);
  return {std::sin(zob) * std::sin(aob), std::sin(zob) * std::cos(aob), std::cos(zob)};
}

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

TEST(StarFieldPlace, VegaMatchesEraAtco13AndAGnomonicProjection) {
  const double c_mm = 80.0;
  const CameraDefinition camera = PinholeCamera(c_mm);
  const PlateLens lens(camera);
  for (const char* utc : {"1972-05-12T06:30:00Z", "1972-05-12T07:45:30Z", "1972-05-12T08:20:00Z"}) {
    SCOPED_TRACE(utc);
    const StarFieldOptions o = Beltsville(utc);
    const StarFieldResult r = ComputeStarImages(o, {Vega()}, lens, camera.format_width_mm, camera.format_height_mm);
    ASSERT_EQ(r.images.size(), 1u);
    const StarImage& image = r.images[0];
    // Independent: ERFA's two-part UTC from the calendar, then the projection.
    int iy, im, id;
    int ih, imin;
    double sec;
    ASSERT_EQ(std::sscanf(utc, "%d-%d-%dT%d:%d:%lfZ", &iy, &im, &id, &ih, &imin, &sec), 6);
    double u1, u2;
    ASSERT_EQ(eraDtf2d("UTC", iy, im, id, ih, imin, sec, &u1, &u2), 0);
    const Eigen::Vector3d enu = IndependentEnu(Vega(), o, u1, u2);
    ASSERT_GT(enu.z(), 0.5);  // well up: Vega passes near the zenith at 39 N
    const double x_mm = c_mm * enu.x() / enu.z(), y_mm = c_mm * enu.y() / enu.z();
    const Eigen::Vector3d expected(x_mm, y_mm, c_mm);
    const Eigen::Vector3d got(image.mid_mm.x_mm, image.mid_mm.y_mm, c_mm);
    EXPECT_LT(AngleBetween(expected, got) / kRadPerArcsec, 0.05)
        << "plate (" << image.mid_mm.x_mm << ", " << image.mid_mm.y_mm << ") mm against (" << x_mm << ", " << y_mm << ")";
    EXPECT_EQ(image.star_id, "KS91262");
    EXPECT_EQ(image.kind, StarImageKind::kStar);
    EXPECT_EQ(image.mid_time_utc.substr(0, 19), std::string(utc).substr(0, 19));
  }
}

TEST(StarFieldPlace, RefractionLiftsTheStarTowardTheZenith) {
  // Same star with and without refraction: the refracted image is closer to
  // the plate centre (zenith) by about 58" tan z (the classical constant at
  // ~1000 hPa, 12 degC: R ~ 57" tan z within a few percent).
  const CameraDefinition camera = PinholeCamera(80.0);
  const PlateLens lens(camera);
  StarFieldOptions o = Beltsville("1972-05-12T06:30:00Z");
  const StarImage with = ComputeStarImages(o, {Vega()}, lens, 114, 114).images.at(0);
  o.place.refraction = false;
  const StarImage without = ComputeStarImages(o, {Vega()}, lens, 114, 114).images.at(0);
  const double z_with = std::atan(std::hypot(with.mid_mm.x_mm, with.mid_mm.y_mm) / 80.0);
  const double z_without = std::atan(std::hypot(without.mid_mm.x_mm, without.mid_mm.y_mm) / 80.0);
  const double refraction_arcsec = (z_without - z_with) / kRadPerArcsec;
  const double classical = 16.27 * 1005.0 / (273.15 + 12.0) * std::tan(z_without);  // Bennett/Saemundsson-type constant
  EXPECT_NEAR(refraction_arcsec, classical, 0.05 * classical);
}

TEST(StarFieldPlace, PointingConvention) {
  // Zenith, roll 30 deg: the plate x axis is east turned 30 deg toward north.
  const Eigen::Matrix3d zenith = CameraFromEnu(0.0, 90.0, 30.0);
  EXPECT_NEAR(zenith(0, 0), std::cos(30 * kRadPerDeg), 1e-15);
  EXPECT_NEAR(zenith(0, 1), std::sin(30 * kRadPerDeg), 1e-15);
  EXPECT_NEAR(zenith(2, 2), 1.0, 1e-15);
  // Tilted: the third row is the axis (azimuth 120, altitude 50) and a star on
  // the axis lands on the principal point.
  const Eigen::Matrix3d m = CameraFromEnu(120.0, 50.0, -15.0);
  const Eigen::Vector3d axis(std::sin(120 * kRadPerDeg) * std::cos(50 * kRadPerDeg), std::cos(120 * kRadPerDeg) * std::cos(50 * kRadPerDeg),
                             std::sin(50 * kRadPerDeg));
  EXPECT_NEAR((m.row(2).transpose() - axis).norm(), 0.0, 1e-14);
  EXPECT_NEAR((m * m.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-14);
  EXPECT_NEAR(m.determinant(), 1.0, 1e-14);
  const PlateLens lens(PinholeCamera(80.0));
  const std::optional<PlatePoint> p = lens.Project(m, axis);
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->x_mm, 0.0, 1e-12);
  EXPECT_NEAR(p->y_mm, 0.0, 1e-12);
  // Behind the camera: nothing.
  EXPECT_FALSE(lens.Project(m, -axis));
}

TEST(StarFieldPlace, OrbigonLensIsAppliedInSeed001sLeftHandedFrame) {
  // Seed 001 Table 3 (combined) as printed, in its left-handed focal-plane
  // frame: C, xp, yp, xs, ys (um), K1..K5, Phi_T. Seed 001's image equation
  // (SlamaImageEquation, epsilon 0) in that frame on the mirrored direction
  // (v -> -v), mirrored back (y -> -y), is the plate position.
  const double c_mm = 80.17103, xp_mm = -0.02050, yp_mm = -0.00004;
  const double slama[8] = {1.0636 - xp_mm, -1.1637 - yp_mm, 3.6494e-1, -1.1011e+2, 9.5244e+3, 7.8152e-4, 5.0665e-2,
                           -271.2 * kRadPerDeg};
  const DefinitionRegistry registry;
  const CameraDefinition* orbigon = registry.FindCamera("orbigon");
  ASSERT_NE(orbigon, nullptr);
  const PlateLens lens(*orbigon);
  EXPECT_TRUE(lens.printed_left_handed());
  EXPECT_NEAR(lens.PrincipalPoint().y_mm, -yp_mm, 1e-12);
  double worst_flip_um = 0.0;
  for (const auto& [u, v] : {std::pair{0.3, 0.4}, std::pair{-0.5, 0.2}, std::pair{0.6, -0.6}, std::pair{-0.1, -0.55}}) {
    const Eigen::Vector3d d(u, v, 1.0);
    const std::optional<PlatePoint> p = lens.Project(Eigen::Matrix3d::Identity(), d);
    ASSERT_TRUE(p);
    double x, y;
    SlamaImageEquation(slama, c_mm, c_mm, xp_mm, yp_mm, 0.0, d.x(), -d.y(), d.z(), &x, &y);
    EXPECT_NEAR(p->x_mm, x, 1e-7) << u << ", " << v;
    EXPECT_NEAR(p->y_mm, -y, 1e-7) << u << ", " << v;
    // Without the flip the same numbers would put the image elsewhere by microns.
    double xr, yr;
    SlamaImageEquation(slama, c_mm, c_mm, xp_mm, yp_mm, 0.0, d.x(), d.y(), d.z(), &xr, &yr);
    worst_flip_um = std::max(worst_flip_um, 1e3 * std::hypot(p->x_mm - xr, p->y_mm - yr));
  }
  EXPECT_GT(worst_flip_um, 1.0);
}

}  // namespace
}  // namespace platemeter::sim
