// The camera model: collinearity (seed 000 eq. 1) with each distortion model,
// projection and back-projection, and the factory from published lens
// calibrations (the built-in camera definitions included).
#include <cmath>
#include <optional>
#include <vector>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"

namespace platemeter {
namespace {

LensCalibration TerrainLens203() {  // seed 004, Table A.4
  LensCalibration lens;
  lens.model = "smac-radial-decentering";
  lens.principal_distance_mm = 75.8069;
  lens.principal_point_x_mm = 0.0074;
  lens.principal_point_y_mm = 0.0094;
  lens.coefficients = {{"K1_per_mm2", -0.1278842e-05}, {"K2_per_mm4", +0.5264148e-09},
                       {"K3_per_mm6", -0.5259516e-13}, {"J1_per_mm", +0.3821279e-06},
                       {"J2_per_mm3", +0.1168324e-19}, {"theta0_rad", 3.371325}};
  return lens;
}

LensCalibration HasselbladStellar() {  // seed 000, Table 6
  LensCalibration lens;
  lens.model = "brown-balanced";
  lens.principal_distance_mm = 507.306;
  lens.coefficients = {{"k0", -0.14741e-1}, {"k1_per_mm2", +0.17241e-4}, {"k2_per_mm4", -0.95765e-9},
                       {"p1_per_mm", +0.3858e-5}, {"p2_per_mm", +0.1241e-5}};
  return lens;
}

LensCalibration OrbigonCombined() {  // seed 001, Table 3, combined
  LensCalibration lens;
  lens.model = "orbigon-11";
  lens.principal_distance_mm = 80.17103;
  lens.principal_point_x_mm = -0.02050;
  lens.principal_point_y_mm = -0.00004;
  lens.coefficients = {{"xs_um", 1063.6},       {"ys_um", -1163.7},      {"K1_per_m2", 3.6494e-1},
                       {"K2_per_m4", -1.1011e+2}, {"K3_per_m6", 9.5244e+3}, {"K4_per_m", 7.8152e-4},
                       {"K5_per_m3", 5.0665e-2}, {"Phi_T_deg", -271.2}};
  return lens;
}

struct CameraCase {
  LensCalibration lens;
  double half_format_mm;
};

std::vector<CameraCase> Cases() {
  return {{TerrainLens203(), 57.0}, {HasselbladStellar(), 27.5}, {OrbigonCombined(), 57.0}};
}

Eigen::Matrix3d SomeRotation() { return MatrixFromOmegaPhiKappa({0.3, -0.2, 1.1}); }

TEST(CameraModel, OnAxisDirectionLandsOnThePrincipalPoint) {
  for (const CameraCase& c : Cases()) {
    const CameraModel camera = CameraModelFromLensCalibration(c.lens);
    const Eigen::Matrix3d r = SomeRotation();
    // The optical axis in the object frame: the image frame's +z.
    const Eigen::Vector3d axis = r.transpose() * Eigen::Vector3d::UnitZ();
    const std::optional<Eigen::Vector2d> point = camera.ProjectDirection(r, axis);
    ASSERT_TRUE(point.has_value()) << c.lens.model;
    // Brown and SMAC distortions vanish at the principal point; Slama's is centred
    // on the point of symmetry 1.6 mm away, where it is ~0.003 um.
    const double tolerance = c.lens.model == "orbigon-11" ? 1e-5 : 1e-12;
    EXPECT_NEAR(point->x(), c.lens.principal_point_x_mm, tolerance) << c.lens.model;
    EXPECT_NEAR(point->y(), c.lens.principal_point_y_mm, tolerance) << c.lens.model;
  }
}

TEST(CameraModel, WithoutDistortionAFieldAngleLandsAtCTanTheta) {
  const CameraModel camera({100.0, 0.5, -0.25}, DistortionModelId::kNone, {});
  const double theta = 20.0 * M_PI / 180.0;
  const std::optional<Eigen::Vector2d> point =
      camera.ProjectDirection(Eigen::Matrix3d::Identity(), Eigen::Vector3d(std::sin(theta), 0.0, std::cos(theta)));
  ASSERT_TRUE(point.has_value());
  EXPECT_NEAR(point->x(), 0.5 + 100.0 * std::tan(theta), 1e-12);
  EXPECT_NEAR(point->y(), -0.25, 1e-12);
  // Behind the camera: no image.
  EXPECT_FALSE(camera.ProjectDirection(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.1, 0.0, -1.0)).has_value());
}

TEST(CameraModel, SmacCorrectionIsAddedToTheMeasuredPoint) {
  // Seed 004: the corrections are added to the measured coordinates (relative to
  // the principal point) to give the central projection: projecting a direction
  // and correcting the result must give c * (u/w, v/w) again.
  const LensCalibration lens = TerrainLens203();
  const CameraModel camera = CameraModelFromLensCalibration(lens);
  const Eigen::Vector3d direction(0.5, -0.3, 1.0);
  const std::optional<Eigen::Vector2d> point = camera.ProjectDirection(Eigen::Matrix3d::Identity(), direction);
  ASSERT_TRUE(point.has_value());
  const double xb = point->x() - lens.principal_point_x_mm, yb = point->y() - lens.principal_point_y_mm;
  const std::vector<double> p = {-0.1278842e-05, +0.5264148e-09, -0.5259516e-13, +0.3821279e-06, +0.1168324e-19, 3.371325};
  double dx = 0.0, dy = 0.0;
  SmacRadialDecentering::Apply(p.data(), xb, yb, &dx, &dy);
  EXPECT_NEAR(xb + dx, lens.principal_distance_mm * 0.5, 1e-11);
  EXPECT_NEAR(yb + dy, lens.principal_distance_mm * -0.3, 1e-11);
  // And the distortion is not negligible there (~47 mm off axis).
  EXPECT_GT(std::hypot(dx, dy), 1e-3);
}

TEST(CameraModel, ProjectAndBackProjectRoundTrip) {
  for (const CameraCase& c : Cases()) {
    const CameraModel camera = CameraModelFromLensCalibration(c.lens);
    const Eigen::Matrix3d r = SomeRotation();
    const double h = c.half_format_mm;
    for (int i = -4; i <= 4; ++i) {
      for (int j = -4; j <= 4; ++j) {
        const Eigen::Vector2d measured(h * i / 4.0 + 0.013, h * j / 4.0 - 0.021);
        const std::optional<Eigen::Vector3d> direction = camera.DirectionFromImage(r, measured);
        ASSERT_TRUE(direction.has_value());
        EXPECT_NEAR(direction->norm(), 1.0, 1e-14);
        const std::optional<Eigen::Vector2d> again = camera.ProjectDirection(r, *direction);
        ASSERT_TRUE(again.has_value());
        EXPECT_NEAR(again->x(), measured.x(), 1e-10) << c.lens.model;
        EXPECT_NEAR(again->y(), measured.y(), 1e-10) << c.lens.model;
      }
    }
  }
}

TEST(CameraModel, TemplatedProjectionAgreesAndGivesZeroResidual) {
  for (const CameraCase& c : Cases()) {
    const CameraModel camera = CameraModelFromLensCalibration(c.lens);
    const Eigen::Matrix3d r = SomeRotation();
    double rotation[9];
    for (int i = 0; i < 9; ++i) rotation[i] = r(i / 3, i % 3);
    const double interior[3] = {camera.interior().principal_distance_mm, camera.interior().principal_point_x_mm,
                                camera.interior().principal_point_y_mm};
    // A direction imaged inside the format (0.7, -0.9 of the half format).
    const double f = c.half_format_mm / camera.interior().principal_distance_mm;
    const Eigen::Vector3d direction = r.transpose() * Eigen::Vector3d(0.7 * f, -0.9 * f, 1.0);
    const std::optional<Eigen::Vector2d> point = camera.ProjectDirection(r, direction);
    ASSERT_TRUE(point.has_value()) << c.lens.model;
    VisitDistortionModel(camera.model(), [&](auto model) {
      using Model = decltype(model);
      double x = 0.0, y = 0.0;
      ASSERT_TRUE(ProjectDirectionT<Model>(interior, camera.params().data(), rotation, direction.data(), &x, &y));
      EXPECT_NEAR(x, point->x(), 1e-12);
      EXPECT_NEAR(y, point->y(), 1e-12);
      double residual[2];
      ASSERT_TRUE(CollinearityResidualT<Model>(interior, camera.params().data(), rotation, direction.data(),
                                               point->x(), point->y(), residual));
      EXPECT_NEAR(residual[0], 0.0, 1e-10);
      EXPECT_NEAR(residual[1], 0.0, 1e-10);
      // Moving the measurement by 1 um moves the residual by ~1 um.
      ASSERT_TRUE(CollinearityResidualT<Model>(interior, camera.params().data(), rotation, direction.data(),
                                               point->x() + 1e-3, point->y(), residual));
      EXPECT_NEAR(residual[0], 1e-3, 1e-4);
    });
  }
}

TEST(CameraModel, ProjectionDerivativeWithRespectToPrincipalDistance) {
  // d(x)/d(c) of the undistorted projection is u/w: a hand-derived check of the
  // Jet path through IdealFromDirectionT and MeasuredFromIdeal.
  using Jet = ceres::Jet<double, 3>;
  const Jet interior[3] = {Jet(80.0, 0), Jet(0.1, 1), Jet(-0.2, 2)};
  Jet rotation[9];
  for (int i = 0; i < 9; ++i) rotation[i] = Jet(i % 4 == 0 ? 1.0 : 0.0);
  const Jet direction[3] = {Jet(0.3), Jet(-0.4), Jet(1.0)};
  Jet x, y;
  ASSERT_TRUE(ProjectDirectionT<NoDistortion>(interior, static_cast<const Jet*>(nullptr), rotation, direction, &x, &y));
  EXPECT_NEAR(x.a, 80.0 * 0.3 + 0.1, 1e-12);
  EXPECT_NEAR(x.v[0], 0.3, 1e-15);
  EXPECT_NEAR(y.v[0], -0.4, 1e-15);
  EXPECT_NEAR(x.v[1], 1.0, 1e-15);
  EXPECT_NEAR(y.v[2], 1.0, 1e-15);
}

TEST(CameraModelFactory, ConvertsOrbigonUnits) {
  const CameraModel camera = CameraModelFromLensCalibration(OrbigonCombined());
  ASSERT_EQ(camera.model(), DistortionModelId::kSlama);
  // xs: 1063.6 um from the reseau centre = 1.0636 mm; relative to xp = -0.0205 mm.
  EXPECT_NEAR(camera.params()[0], 1.0636 + 0.0205, 1e-12);
  EXPECT_NEAR(camera.params()[1], -1.1637 + 0.00004, 1e-12);
  EXPECT_NEAR(camera.params()[7], -271.2 * M_PI / 180.0, 1e-12);
  EXPECT_EQ(camera.params()[2], 3.6494e-1);
}

TEST(CameraModelFactory, RejectsBadCalibrations) {
  LensCalibration unknown = TerrainLens203();
  unknown.model = "fisheye";
  try {
    CameraModelFromLensCalibration(unknown, "camera sn004-terrain");
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_EQ(error.subject(), "camera sn004-terrain");
    EXPECT_NE(error.reason().find("fisheye"), std::string::npos);
  }
  LensCalibration missing = TerrainLens203();
  missing.coefficients.erase("J2_per_mm3");
  EXPECT_THROW(CameraModelFromLensCalibration(missing), Error);
  LensCalibration extra = TerrainLens203();
  extra.coefficients["K4_per_mm8"] = 0.0;
  EXPECT_THROW(CameraModelFromLensCalibration(extra), Error);
  LensCalibration not_finite = TerrainLens203();
  not_finite.coefficients["K1_per_mm2"] = std::nan("");
  EXPECT_THROW(CameraModelFromLensCalibration(not_finite), Error);
  LensCalibration no_focal = TerrainLens203();
  no_focal.principal_distance_mm = 0.0;
  EXPECT_THROW(CameraModelFromLensCalibration(no_focal), Error);
  EXPECT_THROW(CameraModel({80.0, 0.0, 0.0}, DistortionModelId::kBrownConrady, {0.0, 0.0}), Error);
}

TEST(CameraModelFactory, BuildsEveryBuiltInCameraWithALens) {
  const DefinitionRegistry registry;
  int with_lens = 0;
  for (const std::string& name : registry.CameraNames()) {
    const CameraDefinition& definition = registry.Camera(name);
    if (!definition.lens) continue;
    ++with_lens;
    const CameraModel camera = CameraModelFromLensCalibration(*definition.lens, "camera " + name);
    EXPECT_GT(camera.interior().principal_distance_mm, 0.0) << name;
    // Round trip at the format corner.
    const Eigen::Vector2d corner(0.45 * definition.format_width_mm, 0.45 * definition.format_height_mm);
    const std::optional<Eigen::Vector3d> direction = camera.DirectionFromImage(Eigen::Matrix3d::Identity(), corner);
    ASSERT_TRUE(direction.has_value()) << name;
    const std::optional<Eigen::Vector2d> again = camera.ProjectDirection(Eigen::Matrix3d::Identity(), *direction);
    ASSERT_TRUE(again.has_value()) << name;
    EXPECT_NEAR((*again - corner).norm(), 0.0, 1e-10) << name;
  }
  EXPECT_GE(with_lens, 1);
}

}  // namespace
}  // namespace platemeter
