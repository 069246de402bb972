// The simulator's geometry chain: each step against hand-derived values (seed
// 001's thermal factor and emulsion-depth scale), round trips for all eight
// scan orientations, and Jacobians against finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "platemeter/core/error.h"
#include "platemeter/samples/geometry.h"

namespace platemeter::sim {
namespace {

// The Orbigon reseau: 11 x 11 crosses at 10 mm about the centre (seed 001).
std::vector<PlatePoint> OrbigonGrid() {
  std::vector<PlatePoint> points;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) points.push_back({10.0 * i, 10.0 * j});
  }
  return points;
}

GeometryChain EverythingOn(int orientation_deg, bool mirrored) {
  GeometryChain chain;
  chain.thermal = {22.0, 20.0, 8.1e-6};
  chain.emulsion.depth_um = 21.0;
  chain.emulsion.refractive_index = 1.65;
  chain.emulsion.principal_distance_mm = 80.2;
  chain.emulsion.principal_point_mm = {0.021, -0.008};
  chain.film.affine_ppm[0] = 35;
  chain.film.affine_ppm[1] = -12;
  chain.film.affine_ppm[2] = 7;
  chain.film.affine_ppm[3] = -20;
  chain.film.shift_um[0] = 3.5;
  chain.film.shift_um[1] = -1.25;
  chain.film.waves.push_back({2.0, -1.5, 40.0, 30.0, 15.0});
  chain.film.polynomial.push_back({2, 1, 1.5, -0.75});
  chain.scanner.pixel_size_um = 12.5;
  chain.scanner.pixel_aspect = 1.0003;
  chain.scanner.rotation_deg = 0.35;
  chain.scanner.non_orthogonality_arcsec = 25.0;
  chain.scanner.orientation_deg = orientation_deg;
  chain.scanner.mirrored = mirrored;
  chain.scanner.origin_px = {4600.25, 4599.75};
  return chain;
}

TEST(GeometryThermal, Seed001FactorFrom22To20DegC) {
  // Seed 001: measurements at 22.0 degC scaled to the 20.0 degC calibration by 0.9999838 (8.1e-6 per degC).
  const ThermalStep thermal{22.0, 20.0, 8.1e-6};
  EXPECT_DOUBLE_EQ(thermal.Scale(), 1.0 + 2.0 * 8.1e-6);
  const PlatePoint back = thermal.Inverse({100.0, -50.0});
  EXPECT_NEAR(back.x_mm / 100.0, 0.9999838, 5e-10);  // 1/(1 + 1.62e-5) = 0.99998380026
  EXPECT_NEAR(back.y_mm / -50.0, 0.9999838, 5e-10);
}

TEST(GeometryEmulsion, ExactRefractionOfOneRay) {
  // At r = 50 mm below a nodal point 80.2 mm up: theta = atan(50/80.2); Snell into n = 1.65;
  // 21 um deep the ray has moved 0.021 tan(theta') mm outward.
  EmulsionDepthStep step;
  step.depth_um = 21.0;
  const double theta = std::atan(50.0 / 80.2);
  const double theta_in = std::asin(std::sin(theta) / 1.65);
  const double expected = 0.021 * std::tan(theta_in);
  EXPECT_NEAR(step.RadialShiftMm(50.0), expected, 1e-15);
  EXPECT_NEAR(expected, 0.0071086, 1e-7);  // printed once by hand: 7.1 um at 50 mm
  // A point on the diagonal moves radially by that amount.
  const double r = 50.0 / std::sqrt(2.0);
  const PlatePoint moved = step.Forward({r, -r});
  EXPECT_NEAR(std::hypot(moved.x_mm, moved.y_mm) - 50.0, expected, 1e-12);
  EXPECT_NEAR(moved.x_mm, -moved.y_mm, 1e-14);
}

TEST(GeometryEmulsion, Seed001ScaleAndDepth) {
  EmulsionDepthStep step;
  step.depth_um = 21.0;
  step.refractive_index = 1.65;
  step.principal_distance_mm = 80.2;
  // Small-angle equivalent: 1 + d / (n c) = 1 + 0.021 / 132.33.
  EXPECT_NEAR(step.EquivalentScale(), 1.0 + 0.021 / 132.33, 1e-15);
  EXPECT_NEAR(EmulsionDepthStep::DepthUmFromEquivalentScale(1.0 + 0.021 / 132.33, 1.65, 80.2), 21.0, 1e-9);
  // The exact model seen through a scale fit of the 121 Orbigon crosses: about 1.00014 for 21 um
  // (the outer crosses refract less than the small-angle scale says).
  const std::vector<PlatePoint> grid = OrbigonGrid();
  const double fitted = step.FittedScale(grid);
  EXPECT_NEAR(fitted, 1.00014, 0.000002);
  EXPECT_LT(fitted, step.EquivalentScale());
  // Back from the seed's measured discrepancy 1.0001446 to the depth: "about 21 um".
  const double depth = step.DepthUmFromFittedScale(1.0001446, grid);
  EXPECT_NEAR(depth, 21.0, 1.0);
  // ... and the round trip scale -> depth -> scale is exact.
  EmulsionDepthStep at_depth = step;
  at_depth.depth_um = depth;
  EXPECT_NEAR(at_depth.FittedScale(grid), 1.0001446, 1e-13);
}

TEST(GeometryScanner, OrientationsMoveThePlateAxesAsDocumented) {
  // 25 um pixels: 1 mm = 40 px. Plate +x, then plate +y, in pixels (column, row down).
  struct Case {
    int orientation_deg;
    bool mirrored;
    double x_dcol, x_drow, y_dcol, y_drow;
  };
  const Case cases[] = {
      {0, false, 40, 0, 0, -40},   {90, false, 0, -40, -40, 0}, {180, false, -40, 0, 0, 40},
      {270, false, 0, 40, 40, 0},  {0, true, -40, 0, 0, -40},   {90, true, 0, 40, -40, 0},
      {180, true, 40, 0, 0, 40},   {270, true, 0, -40, 40, 0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.orientation_deg) + (c.mirrored ? " mirrored" : ""));
    ScannerStep scanner;
    scanner.pixel_size_um = 25.0;
    scanner.orientation_deg = c.orientation_deg;
    scanner.mirrored = c.mirrored;
    scanner.origin_px = {100.0, 200.0};
    const PixelPoint o = scanner.Forward({0, 0});
    const PixelPoint x = scanner.Forward({1, 0});
    const PixelPoint y = scanner.Forward({0, 1});
    EXPECT_DOUBLE_EQ(o.x_px, 100.0);
    EXPECT_DOUBLE_EQ(o.y_px, 200.0);
    EXPECT_NEAR(x.x_px - o.x_px, c.x_dcol, 1e-12);
    EXPECT_NEAR(x.y_px - o.y_px, c.x_drow, 1e-12);
    EXPECT_NEAR(y.x_px - o.x_px, c.y_dcol, 1e-12);
    EXPECT_NEAR(y.y_px - o.y_px, c.y_drow, 1e-12);
  }
}

TEST(GeometryScanner, RotationAndNonOrthogonality) {
  ScannerStep scanner;
  scanner.pixel_size_um = 10.0;
  scanner.non_orthogonality_arcsec = 36.0;
  // A point 50 mm up the plate y axis leans by 50 mm * tan(36") along the rows.
  const PixelPoint up = scanner.Forward({0, 50});
  EXPECT_NEAR(up.x_px, 50.0 * std::tan(36.0 / 3600.0 * std::numbers::pi / 180.0) * 100.0, 1e-9);
  EXPECT_NEAR(up.y_px, -50.0 / std::cos(36.0 / 3600.0 * std::numbers::pi / 180.0) * 100.0, 1e-9);
  // A counter-clockwise rotation of 1 deg turns plate +x slightly up (row decreases).
  scanner.non_orthogonality_arcsec = 0;
  scanner.rotation_deg = 1.0;
  const PixelPoint x = scanner.Forward({10, 0});
  EXPECT_NEAR(x.x_px, 1000.0 * std::cos(std::numbers::pi / 180.0), 1e-9);
  EXPECT_NEAR(x.y_px, -1000.0 * std::sin(std::numbers::pi / 180.0), 1e-9);
}

TEST(GeometryChain, RoundTripsForAllEightOrientations) {
  for (int orientation : {0, 90, 180, 270}) {
    for (bool mirrored : {false, true}) {
      SCOPED_TRACE(std::to_string(orientation) + (mirrored ? " mirrored" : ""));
      const GeometryChain chain = EverythingOn(orientation, mirrored);
      std::string why;
      ASSERT_TRUE(chain.Check(&why)) << why;
      double worst_mm = 0;
      for (double x = -57; x <= 57; x += 9.5) {
        for (double y = -57; y <= 57; y += 9.5) {
          const PixelPoint q = chain.PixelFromPlate({x, y});
          const PlatePoint back = chain.PlateFromPixel(q);
          worst_mm = std::max(worst_mm, std::hypot(back.x_mm - x, back.y_mm - y));
        }
      }
      EXPECT_LT(worst_mm, 1e-9);
      // The principal point itself (r = 0) as well.
      const PlatePoint pp = chain.emulsion.principal_point_mm;
      const PlatePoint at_pp = chain.thermal.Inverse(pp);
      const PlatePoint back = chain.PlateFromPixel(chain.PixelFromPlate(at_pp));
      EXPECT_NEAR(back.x_mm, at_pp.x_mm, 1e-9);
      EXPECT_NEAR(back.y_mm, at_pp.y_mm, 1e-9);
    }
  }
}

TEST(GeometryChain, EachStepMovesPointsByItsOwnAmount) {
  GeometryChain chain = EverythingOn(0, false);
  chain.scanner = ScannerStep{};  // 25 um, origin at 0
  // Only the thermal step: 100 mm grows by 1.62 um.
  GeometryChain thermal_only;
  thermal_only.thermal = chain.thermal;
  const PixelPoint q = thermal_only.PixelFromPlate({100, 0});
  EXPECT_NEAR(q.x_px * 25e-3, 100.0 * (1 + 1.62e-5), 1e-11);
  // Only a film shift of 3.5 um: 0.14 px at 25 um.
  GeometryChain film_only;
  film_only.film.shift_um[0] = 3.5;
  EXPECT_NEAR(film_only.PixelFromPlate({0, 0}).x_px, 0.14, 1e-12);
  // A film wave of 2 um along x, wavelength 40 mm, at a quarter wavelength: +2 um in x.
  GeometryChain wave_only;
  wave_only.film.waves.push_back({2.0, 0.0, 40.0, 0.0, 0.0});
  EXPECT_NEAR(wave_only.PixelFromPlate({10, 0}).x_px * 25e-3 - 10.0, 0.002, 1e-12);
}

// Central differences with a step that keeps truncation and rounding below 1e-7.
Matrix2 NumericJacobian(const GeometryChain& chain, PlatePoint p) {
  const double h = 1e-4;
  const PixelPoint xp = chain.PixelFromPlate({p.x_mm + h, p.y_mm});
  const PixelPoint xm = chain.PixelFromPlate({p.x_mm - h, p.y_mm});
  const PixelPoint yp = chain.PixelFromPlate({p.x_mm, p.y_mm + h});
  const PixelPoint ym = chain.PixelFromPlate({p.x_mm, p.y_mm - h});
  return Matrix2{{(xp.x_px - xm.x_px) / (2 * h), (yp.x_px - ym.x_px) / (2 * h), (xp.y_px - xm.y_px) / (2 * h),
                  (yp.y_px - ym.y_px) / (2 * h)}};
}

TEST(GeometryChain, JacobianEqualsFiniteDifferences) {
  for (int orientation : {0, 90, 180, 270}) {
    for (bool mirrored : {false, true}) {
      const GeometryChain chain = EverythingOn(orientation, mirrored);
      for (PlatePoint p : {PlatePoint{0.021, -0.008}, PlatePoint{12.3, -45.6}, PlatePoint{-55, 55},
                           PlatePoint{3, 0.5}}) {
        const Matrix2 analytic = chain.PixelFromPlateJacobian(p);
        const Matrix2 numeric = NumericJacobian(chain, p);
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(analytic.a[k], numeric.a[k], 2e-6) << "entry " << k;
        const Matrix2 per_um = chain.PxFromUm(p);
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(per_um.a[k], analytic.a[k] / 1000.0, 1e-15);
      }
    }
  }
}

TEST(GeometryChain, JsonKeepsEveryParameter) {
  const GeometryChain chain = EverythingOn(270, true);
  const GeometryChain back = GeometryChain::FromJson(chain.ToJson(), "chain.json");
  for (PlatePoint p : {PlatePoint{1, 2}, PlatePoint{-40, 33}}) {
    const PixelPoint a = chain.PixelFromPlate(p), b = back.PixelFromPlate(p);
    EXPECT_EQ(a.x_px, b.x_px);
    EXPECT_EQ(a.y_px, b.y_px);
  }
  EXPECT_THROW(GeometryChain::FromJson("{\"thermal\": 3}", "chain.json"), Error);
}

TEST(GeometryChain, ChecksRejectImpossibleParameters) {
  std::string why;
  GeometryChain chain;
  chain.scanner.orientation_deg = 45;
  EXPECT_FALSE(chain.Check(&why));
  EXPECT_NE(why.find("orientation_deg"), std::string::npos);
  chain = GeometryChain{};
  chain.emulsion.refractive_index = 0.9;
  EXPECT_FALSE(chain.Check(&why));
  chain = GeometryChain{};
  chain.scanner.pixel_size_um = 0;
  EXPECT_FALSE(chain.Check(&why));
}

}  // namespace
}  // namespace platemeter::sim
