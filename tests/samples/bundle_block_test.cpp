// The bundle-block simulator (samples/bundle_block.h): geometry facts of seed
// 000's lunar blocks (sections 3 and 4), the planar target's OpenCV view, the
// large aerial block; exact projection of the truth and the noise's sigma.
#include "platemeter/samples/bundle_block.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include <Eigen/LU>
#include <numbers>

#include "platemeter/core/error.h"

namespace platemeter::sim {
namespace {


// Largest |residual| (mm) of seed 000 eq. (1) over the noise-free observations,
// through calib's CollinearityResidualT<BrownAffine> with the true values.
double MaxTruthResidualMm(const BundleTruth& truth) {
  std::map<std::string, const StationTruth*> stations;
  for (const StationTruth& s : truth.stations) stations[s.id] = &s;
  std::map<std::string, const PointTruth*> points;
  for (const PointTruth& p : truth.points) points[p.id] = &p;
  const auto values = truth.camera.Values();
  double worst = 0.0;
  for (const ImageObservation& o : truth.observations) {
    const StationTruth& s = *stations.at(o.frame);
    double rotation[9];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation[3 * r + c] = s.image_from_object(r, c);
    }
    const Eigen::Vector3d direction = points.at(o.point_id)->position_m - s.position_m;
    double residual[2] = {1e9, 1e9};
    EXPECT_TRUE(CollinearityResidualT<BrownAffine>(values.data(), values.data() + 3, rotation, direction.data(),
                                                   o.x_mm, o.y_mm, residual));
    worst = std::max({worst, std::abs(residual[0]), std::abs(residual[1])});
  }
  return worst;
}

// Every observation: point in front of the camera, inside the format.
void ExpectInFrontAndInside(const BundleTruth& truth, double margin_mm) {
  std::map<std::string, const StationTruth*> stations;
  for (const StationTruth& s : truth.stations) stations[s.id] = &s;
  std::map<std::string, const PointTruth*> points;
  for (const PointTruth& p : truth.points) points[p.id] = &p;
  int behind = 0, outside = 0;
  for (const ImageObservation& o : truth.observations) {
    const StationTruth& s = *stations.at(o.frame);
    const Eigen::Vector3d d = points.at(o.point_id)->position_m - s.position_m;
    if (!(s.OpticalAxis().dot(d) > 0.0)) ++behind;
    if (std::abs(o.x_mm) > 0.5 * truth.camera.format_width_mm - margin_mm + 1e-12 ||
        std::abs(o.y_mm) > 0.5 * truth.camera.format_height_mm - margin_mm + 1e-12) {
      ++outside;
    }
  }
  EXPECT_EQ(behind, 0);
  EXPECT_EQ(outside, 0);
}

// Sample standard deviation of (noisy - true), both axes pooled, mm.
double NoiseSigmaMm(const SimulatedBlock& block) {
  const auto& noisy = block.input.observations;
  const auto& exact = block.truth.observations;
  EXPECT_EQ(noisy.size(), exact.size());
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < noisy.size(); ++i) {
    EXPECT_EQ(noisy[i].frame, exact[i].frame);
    EXPECT_EQ(noisy[i].point_id, exact[i].point_id);
    for (double d : {noisy[i].x_mm - exact[i].x_mm, noisy[i].y_mm - exact[i].y_mm}) sum += d, sum2 += d * d;
  }
  const double n = 2.0 * noisy.size();
  return std::sqrt((sum2 - sum * sum / n) / (n - 1.0));
}

TEST(BundleBlockLunar, Section4GeometryFacts) {
  const LunarBlockOptions options = Seed000Table9Options(80.0);
  const SimulatedBlock block = SimulateLunarBlock(options);
  const BundleTruth& truth = block.truth;
  ASSERT_EQ(truth.stations.size(), 9u);
  ASSERT_EQ(truth.points.size(), 215u);
  // Passpoints on the common ground area: every point in all 9 frames.
  EXPECT_EQ(truth.observations.size(), 9u * 215u);
  EXPECT_EQ(block.input.observations.size(), 9u * 215u);
  EXPECT_EQ(block.input.frames.size(), 9u);
  EXPECT_EQ(block.input.ground_points.size(), 215u);
  ASSERT_EQ(block.input.cameras.size(), 1u);
  EXPECT_EQ(block.input.cameras[0].format_width_mm, 55.0);

  for (int orbit = 0; orbit < 3; ++orbit) {
    const StationTruth& first = truth.stations[3 * orbit];
    const StationTruth& last = truth.stations[3 * orbit + 2];
    EXPECT_NEAR(ConvergenceAngleDeg(first, last), 80.0, 1.0) << "orbit " << orbit;
    for (int j = 0; j < 3; ++j) {
      const StationTruth& s = truth.stations[3 * orbit + j];
      EXPECT_EQ(s.group, orbit);
      EXPECT_NEAR(s.position_m.norm() - 1737.4e3, 108.5e3, 1e-6);
      // Fig. 3's arrows: the camera turned 90 deg about its axis between exposures.
      EXPECT_NEAR(RollAboutAxisDeg(s.image_from_object, s.velocity_direction), s.roll_deg, 1e-9);
      if (j > 0) {
        const StationTruth& prev = truth.stations[3 * orbit + j - 1];
        const double step = RollAboutAxisDeg(s.image_from_object, s.velocity_direction) -
                            RollAboutAxisDeg(prev.image_from_object, prev.velocity_direction);
        EXPECT_NEAR(std::remainder(step - 90.0, 360.0), 0.0, 1e-9);
      }
      // Every optical axis points at the centre of the common area, G = (0, 0, R).
      const Eigen::Vector3d to_target = (Eigen::Vector3d(0, 0, 1737.4e3) - s.position_m).normalized();
      EXPECT_NEAR(s.OpticalAxis().dot(to_target), 1.0, 1e-12);
      // The T angles reproduce the matrix.
      EXPECT_LT((TMatrixFromAngles(s.angles) - s.image_from_object).norm(), 1e-12);
    }
  }
  // The middle orbit passes over G: there seed 000's kappa itself steps by 90 deg.
  for (int j = 1; j < 3; ++j) {
    const double step = truth.stations[3 + j].angles.kappa_rad - truth.stations[3 + j - 1].angles.kappa_rad;
    EXPECT_NEAR(std::remainder(step - std::numbers::pi / 2, 2 * std::numbers::pi), 0.0, 1e-9);
  }
  // Consecutive orbits 8.5 km apart across the track (Y) at the centre frames.
  EXPECT_NEAR((truth.stations[4].position_m - truth.stations[1].position_m).y() * 1737.4 / 1846.0, 8.5e3, 10.0);
  ExpectInFrontAndInside(truth, options.format_margin_mm);

  // The points fill the format: in the centre frame of the middle orbit they
  // reach beyond 80 % of the half format on both axes.
  double max_x = 0.0, max_y = 0.0;
  for (const ImageObservation& o : truth.observations) {
    if (o.frame != truth.stations[4].id) continue;
    max_x = std::max(max_x, std::abs(o.x_mm));
    max_y = std::max(max_y, std::abs(o.y_mm));
  }
  EXPECT_GT(max_x, 0.8 * 27.5);
  EXPECT_GT(max_y, 0.8 * 27.5);

  // Relief: heights spread over most of +-150 m.
  double lo = 1e9, hi = -1e9;
  for (const PointTruth& p : truth.points) {
    lo = std::min(lo, p.position_m.norm() - 1737.4e3);
    hi = std::max(hi, p.position_m.norm() - 1737.4e3);
  }
  EXPECT_GE(lo, -150.0);
  EXPECT_LE(hi, 150.0);
  EXPECT_GT(hi - lo, 200.0);
}

TEST(BundleBlockLunar, TruthReprojectsExactlyAndNoiseHasItsSigma) {
  const SimulatedBlock block = SimulateLunarBlock(Seed000Table9Options(80.0));
  EXPECT_LT(MaxTruthResidualMm(block.truth), 1e-9);
  EXPECT_NEAR(NoiseSigmaMm(block) / 15e-3, 1.0, 0.05);
  EXPECT_DOUBLE_EQ(block.truth.sigma_mm, 15e-3);
  for (const ImageObservation& o : block.input.observations) {
    ASSERT_DOUBLE_EQ(o.sigma_x_mm, 15e-3);
    ASSERT_DOUBLE_EQ(o.sigma_y_mm, 15e-3);
  }
  // Free and fixed states are the caller's: frames free, points free, camera as CameraSetup's default.
  for (const FrameSetup& f : block.input.frames) {
    EXPECT_FALSE(f.fixed);
    EXPECT_FALSE(f.position_covariance_m2.has_value());
    ASSERT_TRUE(f.position_m.has_value() && f.angles.has_value());
  }
  for (const GroundPoint& g : block.input.ground_points) {
    for (const auto& sigma : g.sigma_m) EXPECT_FALSE(sigma.has_value());
  }
}

TEST(BundleBlockLunar, Table9FocalLengthsAndTable10TerrainCamera) {
  for (double focal : {50.0, 150.0, 500.0}) {
    const SimulatedBlock block = SimulateLunarBlock(Seed000Table9Options(focal));
    EXPECT_EQ(block.truth.points.size(), 215u) << focal;
    EXPECT_EQ(block.truth.observations.size(), 9u * 215u) << focal;
    EXPECT_LT(MaxTruthResidualMm(block.truth), 1e-9) << focal;
    ExpectInFrontAndInside(block.truth, 0.5);
    EXPECT_NEAR(ConvergenceAngleDeg(block.truth.stations[0], block.truth.stations[2]), 80.0, 1.0);
  }
  const SimulatedBlock terrain = SimulateLunarBlock(Seed000Table10Options());
  EXPECT_EQ(terrain.truth.camera.c_mm, 76.2);
  EXPECT_EQ(terrain.truth.camera.format_width_mm, 114.3);
  EXPECT_EQ(terrain.truth.observations.size(), 9u * 215u);
  EXPECT_NEAR(NoiseSigmaMm(terrain) / 5e-3, 1.0, 0.05);
  EXPECT_LT(MaxTruthResidualMm(terrain.truth), 1e-9);
  ExpectInFrontAndInside(terrain.truth, 0.5);
}

TEST(BundleBlockLunar, Apollo14Section3SameKappaNarrowField) {
  const LunarBlockOptions options = Apollo14Section3Options();
  const SimulatedBlock block = SimulateLunarBlock(options);
  const BundleTruth& truth = block.truth;
  ASSERT_EQ(truth.stations.size(), 9u);
  EXPECT_EQ(truth.stations[0].id, "R27-9515");
  EXPECT_EQ(truth.stations[8].id, "R30-9615");
  EXPECT_EQ(truth.points.size(), 170u);
  EXPECT_NEAR(truth.camera.c_mm, 509.80, 0.01);
  // 8.9 deg across the diagonal of 55 x 55 mm ("8 deg" in the seed).
  EXPECT_NEAR(2.0 * std::atan(std::hypot(27.5, 27.5) / truth.camera.c_mm) * 180.0 / std::numbers::pi, 8.8, 0.2);
  for (int orbit = 0; orbit < 3; ++orbit) {
    EXPECT_NEAR(ConvergenceAngleDeg(truth.stations[3 * orbit], truth.stations[3 * orbit + 2]), 80.0, 1.0);
  }
  for (const StationTruth& s : truth.stations) {
    EXPECT_NEAR(RollAboutAxisDeg(s.image_from_object, s.velocity_direction), 0.0, 1e-9) << s.id;
  }
  // Revolutions 27, 28, 30: the track moves 1, then 2 spacings across.
  const double d1 = truth.stations[4].position_m.y() - truth.stations[1].position_m.y();
  const double d2 = truth.stations[7].position_m.y() - truth.stations[4].position_m.y();
  EXPECT_NEAR(d2 / d1, 2.0, 1e-6);
  EXPECT_LT(MaxTruthResidualMm(truth), 1e-9);
  ExpectInFrontAndInside(truth, options.format_margin_mm);
}

TEST(BundleBlockLunar, ZeroNoiseGivesTheTruthAndSeedsAreRepeatable) {
  LunarBlockOptions options = Seed000Table9Options(150.0);
  options.sigma_um = 0.0;
  options.weight_sigma_um = 15.0;
  const SimulatedBlock exact = SimulateLunarBlock(options);
  for (std::size_t i = 0; i < exact.truth.observations.size(); ++i) {
    ASSERT_EQ(exact.input.observations[i].x_mm, exact.truth.observations[i].x_mm);
    ASSERT_EQ(exact.input.observations[i].y_mm, exact.truth.observations[i].y_mm);
    ASSERT_EQ(exact.input.observations[i].sigma_x_mm, 15e-3);
  }
  options.sigma_um = 15.0;
  const SimulatedBlock a = SimulateLunarBlock(options);
  const SimulatedBlock b = SimulateLunarBlock(options);
  ASSERT_EQ(a.input.observations.size(), b.input.observations.size());
  for (std::size_t i = 0; i < a.input.observations.size(); ++i) {
    ASSERT_EQ(a.input.observations[i].x_mm, b.input.observations[i].x_mm);
  }
  // The noise has its own stream: same points with or without noise.
  for (std::size_t i = 0; i < a.truth.points.size(); ++i) {
    ASSERT_EQ(a.truth.points[i].position_m, exact.truth.points[i].position_m);
  }
}

TEST(BundleBlockLunar, ApproximationsPerturbTheTruth) {
  LunarBlockOptions options = Seed000Table9Options(80.0);
  const SimulatedBlock plain = SimulateLunarBlock(options);
  EXPECT_EQ(plain.input.frames[3].position_m.value(), plain.truth.stations[3].position_m);
  EXPECT_EQ(plain.input.ground_points[7].position_m, plain.truth.points[7].position_m);
  EXPECT_EQ(plain.input.cameras[0].values, plain.truth.camera.Values());

  options.approximations.station_sigma_m = 1000.0;
  options.approximations.angle_sigma_deg = 1.0;
  options.approximations.point_sigma_m = 500.0;
  options.approximations.principal_distance_sigma_mm = 1.0;
  options.approximations.zero_distortion = true;
  const SimulatedBlock rough = SimulateLunarBlock(options);
  double station_ss = 0.0, point_ss = 0.0;
  for (std::size_t i = 0; i < rough.truth.stations.size(); ++i) {
    station_ss += (rough.input.frames[i].position_m.value() - rough.truth.stations[i].position_m).squaredNorm();
  }
  for (std::size_t i = 0; i < rough.truth.points.size(); ++i) {
    point_ss += (rough.input.ground_points[i].position_m - rough.truth.points[i].position_m).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(station_ss / (3.0 * 9)), 1000.0, 500.0);
  EXPECT_NEAR(std::sqrt(point_ss / (3.0 * 215)), 500.0, 50.0);
  EXPECT_NE(rough.input.cameras[0].values[0], rough.truth.camera.c_mm);
  for (int i = 3; i < kBundleCameraParams; ++i) EXPECT_EQ(rough.input.cameras[0].values[i], 0.0);
  // The observations do not depend on the approximations.
  EXPECT_EQ(rough.input.observations[100].x_mm, plain.input.observations[100].x_mm);
}

TEST(BundleBlockLunar, BadOptionsThrowWithTheReason) {
  LunarBlockOptions options = Seed000Table9Options(80.0);
  options.track_spacing_m = 700e3;  // the outer orbits do not see the common area
  EXPECT_THROW(SimulateLunarBlock(options), Error);
  options = Seed000Table9Options(80.0);
  options.format_margin_mm = 27.0;  // leaves a 1 mm square of the format: too few places
  EXPECT_THROW(SimulateLunarBlock(options), Error);
  options = Seed000Table9Options(80.0);
  options.passpoints = 0;
  std::string why;
  EXPECT_FALSE(options.Check(&why));
  EXPECT_NE(why.find("passpoints"), std::string::npos);
  options = Seed000Table9Options(80.0);
  options.sigma_um = 0.0;  // no noise and no sigma for the observations
  EXPECT_FALSE(options.Check(&why));
  EXPECT_THROW(SimulateLunarBlock(options), Error);
  options = Seed000Table9Options(80.0);
  options.frame_ids = {"only-one"};
  EXPECT_THROW(SimulateLunarBlock(options), Error);
}

TEST(BundleBlockPlanar, OpenCvViewsFollowTheDocumentedPixelMapping) {
  PlanarTargetOptions options;
  const PlanarTargetBlock target = SimulatePlanarTarget(options);
  const BundleTruth& truth = target.block.truth;
  ASSERT_EQ(target.views.size(), 15u);
  ASSERT_EQ(truth.observations.size(), 15u * 12u * 9u);
  EXPECT_EQ(target.pixels.width_px, 3000);
  EXPECT_EQ(target.pixels.height_px, 2000);
  EXPECT_NEAR(target.intrinsics.fx_px, 16.0 / 0.006, 1e-9);
  EXPECT_NEAR(target.intrinsics.cx_px, 0.03 / 0.006 + 1499.5, 1e-9);
  EXPECT_NEAR(target.intrinsics.cy_px, -0.02 / 0.006 + 999.5, 1e-9);
  EXPECT_LT(MaxTruthResidualMm(truth), 1e-9);
  ExpectInFrontAndInside(truth, options.format_margin_mm);
  EXPECT_NEAR(NoiseSigmaMm(target.block) / 0.6e-3, 1.0, 0.05);

  // Varied poses: tilts spread over 10..45 deg from the target normal.
  double min_tilt = 90.0, max_tilt = 0.0;
  for (const StationTruth& s : truth.stations) {
    const double tilt = std::acos(-s.OpticalAxis().z()) * 180.0 / std::numbers::pi;
    min_tilt = std::min(min_tilt, tilt), max_tilt = std::max(max_tilt, tilt);
  }
  EXPECT_GE(min_tilt, 10.0 - 1e-9);
  EXPECT_LE(max_tilt, 45.0 + 1e-9);
  EXPECT_GT(max_tilt - min_tilt, 20.0);

  // Without distortion, OpenCV's pinhole K [R | t] gives the true pixels.
  options.camera.k1_per_mm2 = options.camera.k2_per_mm4 = options.camera.p1_per_mm = options.camera.p2_per_mm = 0.0;
  const PlanarTargetBlock pinhole = SimulatePlanarTarget(options);
  double worst = 0.0;
  for (const PlanarTargetView& view : pinhole.views) {
    EXPECT_NEAR(view.rotation.determinant(), 1.0, 1e-12);
    ASSERT_EQ(view.object_points_m.size(), 108u);
    for (std::size_t i = 0; i < view.object_points_m.size(); ++i) {
      const Eigen::Vector3d camera = view.rotation * view.object_points_m[i] + view.translation_m;
      ASSERT_GT(camera.z(), 0.0);
      const double u = pinhole.intrinsics.fx_px * camera.x() / camera.z() + pinhole.intrinsics.cx_px;
      const double v = pinhole.intrinsics.fy_px * camera.y() / camera.z() + pinhole.intrinsics.cy_px;
      worst = std::max({worst, std::abs(u - view.true_image_points_px[i].x()),
                        std::abs(v - view.true_image_points_px[i].y())});
      const Eigen::Vector2d& px = view.true_image_points_px[i];
      EXPECT_TRUE(px.x() > -0.5 && px.x() < 2999.5 && px.y() > -0.5 && px.y() < 1999.5);
    }
  }
  EXPECT_LT(worst, 1e-7);
  // Round trip of the mapping, and plate +y runs down the rows.
  const Eigen::Vector2d p(3.25, -4.5);
  EXPECT_LT((pinhole.pixels.PlateFromPixel(pinhole.pixels.PixelFromPlate(p)) - p).norm(), 1e-12);
  EXPECT_GT(pinhole.pixels.PixelFromPlate({0.0, 1.0}).y(), pinhole.pixels.PixelFromPlate({0.0, 0.0}).y());
}

TEST(BundleBlockAerial, SmallBlockFacts) {
  AerialBlockOptions options;
  options.strips = 4;
  options.frames_per_strip = 8;
  options.points = 1500;
  const SimulatedBlock block = SimulateAerialBlock(options);
  const BundleTruth& truth = block.truth;
  ASSERT_EQ(truth.stations.size(), 32u);
  ASSERT_EQ(truth.points.size(), 1500u);
  EXPECT_LT(MaxTruthResidualMm(truth), 1e-9);
  ExpectInFrontAndInside(truth, options.format_margin_mm);
  EXPECT_NEAR(NoiseSigmaMm(block) / 3e-3, 1.0, 0.05);
  std::map<std::string, int> per_point;
  for (const ImageObservation& o : truth.observations) ++per_point[o.point_id];
  for (const auto& [id, n] : per_point) EXPECT_GE(n, 2) << id;
  EXPECT_EQ(per_point.size(), 1500u);
  for (const StationTruth& s : truth.stations) {
    EXPECT_NEAR(std::acos(-s.OpticalAxis().z()) * 180.0 / std::numbers::pi, 15.0, 1e-9) << s.id;
    EXPECT_NEAR(std::remainder(RollAboutAxisDeg(s.image_from_object, s.velocity_direction) - 90.0 * s.index_in_group,
                               360.0),
                0.0, 1e-9);
  }
}

TEST(BundleBlockAerial, BenchmarkBlockSize) {
  const auto start = std::chrono::steady_clock::now();
  const SimulatedBlock block = SimulateAerialBlock(AerialBlockOptions{});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(block.truth.stations.size(), 200u);
  EXPECT_EQ(block.truth.points.size(), 20000u);
  const double per_point = static_cast<double>(block.truth.observations.size()) / 20000.0;
  EXPECT_GT(per_point, 17.0);
  EXPECT_LT(per_point, 23.0);
  EXPECT_NEAR(NoiseSigmaMm(block) / 3e-3, 1.0, 0.05);
  std::cout << block.summary << " (" << seconds << " s)\n";
}

}  // namespace
}  // namespace platemeter::sim
