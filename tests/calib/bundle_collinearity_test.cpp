// The bundle's observation equation with analytic Jacobians
// (calib/src/bundle_collinearity.h) against the same residual differentiated
// automatically (calib/src/bundle_equations.h CollinearityEquation): the
// residuals agree to 1e-12 mm and every Jacobian entry to 1e-9 relative, on
// random geometry and on the edges (rays along the axis, strong distortion,
// rotations near 90 degrees, a point behind the camera), with frames sharing
// the per-thread rotation memo's slots and from several threads at once.
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "../../calib/src/bundle_collinearity.h"
#include "../../calib/src/bundle_equations.h"
#include "platemeter/calib/rotations.h"

namespace platemeter::bundle_internal {
namespace {

struct Case {
  std::array<double, 10> camera{};  // c, xp, yp, k1, k2, k3, p1, p2, b1, b2
  std::array<double, 6> frame{};    // X, Y, Z m; phi, omega, kappa rad
  std::array<double, 3> point{};    // X, Y, Z m
  double x_mm = 0.0, y_mm = 0.0;    // the measurement
};

struct Evaluation {
  bool ok = false;
  double residual_mm[2] = {0.0, 0.0};
  std::array<double, 20> camera{};  // 2 x 10, row-major
  std::array<double, 12> frame{};   // 2 x 6
  std::array<double, 6> point{};    // 2 x 3
};

Evaluation Evaluate(const ceres::CostFunction& cost, const Case& c) {
  Evaluation e;
  const double* parameters[3] = {c.camera.data(), c.frame.data(), c.point.data()};
  double* jacobians[3] = {e.camera.data(), e.frame.data(), e.point.data()};
  e.ok = cost.Evaluate(parameters, e.residual_mm, jacobians);
  return e;
}

// Entry by entry: |analytic - automatic| <= 1e-9 |automatic|, with a floor of
// 1e-9 of the row's largest entry in that column's own scale (the column
// times a typical change of its parameter) so that entries that cancel to
// nearly zero are compared against the size of what cancelled.
template <size_t N>
void ExpectClose(const std::array<double, N>& analytic, const std::array<double, N>& automatic,
                 const std::array<double, N / 2>& parameter_scale, const char* block, int case_index) {
  constexpr int kCols = N / 2;
  for (int row = 0; row < 2; ++row) {
    double row_scale = 0.0;  // residual mm per typical parameter change
    for (int k = 0; k < kCols; ++k) {
      row_scale = std::max(row_scale, std::abs(automatic[row * kCols + k]) * parameter_scale[k]);
    }
    for (int k = 0; k < kCols; ++k) {
      const double a = analytic[row * kCols + k], b = automatic[row * kCols + k];
      const double tolerance = 1e-9 * std::max(std::abs(b), 1e-3 * row_scale / parameter_scale[k]);
      EXPECT_NEAR(a, b, tolerance) << "case " << case_index << ", " << block << " row " << row << " column " << k;
    }
  }
}

// Typical changes of the parameters: 1 mm of c, xp, yp; each distortion
// coefficient by what moves a 50 mm radius by 0.1 mm; 1 m; 1 mrad.
const std::array<double, 10> kCameraScale = {1.0, 1.0, 1.0, 1e-1 / std::pow(50.0, 3), 1e-1 / std::pow(50.0, 5),
                                             1e-1 / std::pow(50.0, 7), 1e-1 / std::pow(50.0, 2),
                                             1e-1 / std::pow(50.0, 2), 1e-1 / 50.0, 1e-1 / 50.0};
const std::array<double, 6> kFrameScale = {1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3};
const std::array<double, 3> kPointScale = {1.0, 1.0, 1.0};

void ExpectSame(const Case& c, int case_index) {
  const std::unique_ptr<ceres::CostFunction> automatic(CollinearityEquation::Create(c.x_mm, c.y_mm));
  // Three frame slots for many frames: the per-thread rotation memo sees both hits and changed angles.
  const CollinearityCost analytic(c.x_mm, c.y_mm, case_index % 3);
  const Evaluation a = Evaluate(analytic, c);
  const Evaluation b = Evaluate(*automatic, c);
  ASSERT_EQ(a.ok, b.ok) << "case " << case_index;
  if (!a.ok) return;
  EXPECT_NEAR(a.residual_mm[0], b.residual_mm[0], 1e-12) << "case " << case_index;
  EXPECT_NEAR(a.residual_mm[1], b.residual_mm[1], 1e-12) << "case " << case_index;
  ExpectClose(a.camera, b.camera, kCameraScale, "camera", case_index);
  ExpectClose(a.frame, b.frame, kFrameScale, "frame", case_index);
  ExpectClose(a.point, b.point, kPointScale, "point", case_index);
  // Without Jacobians the residual is the same.
  const double* parameters[3] = {c.camera.data(), c.frame.data(), c.point.data()};
  double residual_only[2];
  ASSERT_TRUE(analytic.Evaluate(parameters, residual_only, nullptr));
  EXPECT_EQ(residual_only[0], a.residual_mm[0]);
  EXPECT_EQ(residual_only[1], a.residual_mm[1]);
}

// A point on the ray through image point (x, y) (ideal, relative to the
// principal point) at `range_m` in front of the frame's station.
std::array<double, 3> PointOnRay(const Case& c, double x_ideal_mm, double y_ideal_mm, double range_m) {
  const Eigen::Matrix3d t = TMatrixFromAngles({c.frame[3], c.frame[4], c.frame[5]});
  const Eigen::Vector3d in_image = Eigen::Vector3d(x_ideal_mm, y_ideal_mm, c.camera[0]).normalized() * range_m;
  const Eigen::Vector3d point = Eigen::Vector3d(c.frame[0], c.frame[1], c.frame[2]) + t.transpose() * in_image;
  return {point.x(), point.y(), point.z()};
}

Case RandomCase(std::mt19937& random, double distortion_scale) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Case c;
  c.camera = {80.0 + 70.0 * (unit(random) + 1.0), 0.1 * unit(random), 0.1 * unit(random),
              distortion_scale * 2e-5 * unit(random), distortion_scale * 1e-9 * unit(random),
              distortion_scale * 1e-13 * unit(random), distortion_scale * 1e-5 * unit(random),
              distortion_scale * 1e-5 * unit(random), distortion_scale * 1e-4 * unit(random),
              distortion_scale * 1e-4 * unit(random)};
  c.frame = {1000.0 * unit(random), 1000.0 * unit(random), 1500.0 + 100.0 * unit(random),
             1.5 * unit(random), M_PI * unit(random), M_PI * unit(random)};
  c.x_mm = 55.0 * unit(random);
  c.y_mm = 55.0 * unit(random);
  // The point near the measurement's ray, off by a few tens of micrometres.
  c.point = PointOnRay(c, c.x_mm + 0.05 * unit(random), c.y_mm + 0.05 * unit(random), 800.0 + 700.0 * (unit(random) + 1.0));
  return c;
}

TEST(BundleCollinearity, AnalyticJacobiansMatchAutomaticOnRandomGeometry) {
  std::mt19937 random(20240623);
  for (int i = 0; i < 500; ++i) ExpectSame(RandomCase(random, 1.0), i);
}

TEST(BundleCollinearity, StrongDistortion) {
  // 50 times the random case's coefficients: corrections of several millimetres in the corners.
  std::mt19937 random(7);
  for (int i = 0; i < 200; ++i) ExpectSame(RandomCase(random, 50.0), i);
}

TEST(BundleCollinearity, RaysAlongTheAxis) {
  std::mt19937 random(11);
  for (int i = 0; i < 50; ++i) {
    Case c = RandomCase(random, 1.0);
    // Measured at the principal point and the point exactly on the axis: u = v = 0, xb = yb = 0.
    c.x_mm = c.camera[1];
    c.y_mm = c.camera[2];
    c.point = PointOnRay(c, 0.0, 0.0, 1200.0);
    ExpectSame(c, i);
    // A hair off the axis.
    c.x_mm += 1e-7;
    c.point = PointOnRay(c, 1e-6, -1e-6, 1200.0);
    ExpectSame(c, i);
  }
}

TEST(BundleCollinearity, RotationsNearNinetyDegrees) {
  std::mt19937 random(13);
  const double near = M_PI / 2 - 1e-4;
  const std::array<std::array<double, 3>, 6> angles = {{{near, 0.3, -0.2},
                                                        {-near, -1.0, 2.0},
                                                        {0.1, M_PI / 2, M_PI / 2},
                                                        {0.2, -M_PI / 2, M_PI},
                                                        {M_PI / 2, M_PI / 2, M_PI / 2},
                                                        {-M_PI / 2, -M_PI / 2, -M_PI / 2}}};
  int index = 0;
  for (const auto& a : angles) {
    for (int i = 0; i < 20; ++i) {
      Case c = RandomCase(random, 1.0);
      c.frame[3] = a[0], c.frame[4] = a[1], c.frame[5] = a[2];
      c.point = PointOnRay(c, c.x_mm + 0.01, c.y_mm - 0.02, 1500.0);
      ExpectSame(c, index++);
    }
  }
}

TEST(BundleCollinearity, PointBehindTheCameraFailsLikeTheAutomaticForm) {
  std::mt19937 random(17);
  Case c = RandomCase(random, 1.0);
  const std::array<double, 3> in_front = PointOnRay(c, 10.0, -5.0, 1000.0);
  for (int k = 0; k < 3; ++k) c.point[k] = 2.0 * c.frame[k] - in_front[k];  // mirrored through the station
  ExpectSame(c, 0);
  const CollinearityCost analytic(c.x_mm, c.y_mm, 0);
  const double* parameters[3] = {c.camera.data(), c.frame.data(), c.point.data()};
  double residual[2];
  EXPECT_FALSE(analytic.Evaluate(parameters, residual, nullptr));
}

TEST(BundleCollinearity, ThreadsSharingFrameSlotsGetTheSameAnswers) {
  // Ceres evaluates residual blocks in parallel; each thread keeps its own rotations.
  std::mt19937 random(19);
  std::vector<Case> cases;
  for (int i = 0; i < 400; ++i) cases.push_back(RandomCase(random, 1.0));
  auto evaluate_all = [&](std::vector<Evaluation>* out) {
    for (size_t i = 0; i < cases.size(); ++i) {
      const CollinearityCost cost(cases[i].x_mm, cases[i].y_mm, static_cast<int>(i % 5));
      (*out)[i] = Evaluate(cost, cases[i]);
    }
  };
  std::vector<Evaluation> serial(cases.size());
  evaluate_all(&serial);
  std::vector<std::vector<Evaluation>> parallel(4, std::vector<Evaluation>(cases.size()));
  std::vector<std::thread> threads;
  for (auto& out : parallel) threads.emplace_back(evaluate_all, &out);
  for (std::thread& t : threads) t.join();
  for (const auto& out : parallel) {
    for (size_t i = 0; i < cases.size(); ++i) {
      EXPECT_EQ(out[i].residual_mm[0], serial[i].residual_mm[0]);
      EXPECT_EQ(out[i].residual_mm[1], serial[i].residual_mm[1]);
      EXPECT_EQ(out[i].frame, serial[i].frame);
      EXPECT_EQ(out[i].camera, serial[i].camera);
    }
  }
}

}  // namespace
}  // namespace platemeter::bundle_internal
