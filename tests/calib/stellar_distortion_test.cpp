// The stellar lens's fields and profiles (stellar_distortion.h) against values
// derived by hand from the models' formulas and seed 001's printed numbers.
#include "platemeter/calib/stellar_distortion.h"

#include <cmath>

#include <gtest/gtest.h>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// Seed 001 Table 3, combined f/3.5, f/4, f/5.6 (units as printed: K1 1/m^2 ...); the
// point of symmetry at the principal point, Phi_T = 0.3 rad (the frame does not matter here).
StellarLensEstimate Orbigon() {
  StellarLensEstimate e;
  e.lens = DistortionModelId::kSlama;
  e.values = {80.17103, -0.0205, 0.0, 0.0, 0.0, 3.6494e-1, -1.1011e+2, 9.5244e+3, 7.8152e-4, 5.0665e-2, 0.3};
  e.covariance = Eigen::MatrixXd::Zero(11, 11);
  return e;
}

TEST(StellarDistortion, OrbigonProfilesAreSeed001sNumbers) {
  const StellarProfile p = ComputeStellarProfile(Orbigon(), 80.0, 16);
  ASSERT_EQ(p.rows.size(), 17u);
  // By hand (tests/calib/model_seed_values_test.cpp): dR(80 mm) = 25.7820 um.
  EXPECT_NEAR(p.rows.back().radial_um, 25.7820, 1e-3);
  // (K4 + K5 d^2) d^2 at d = 55 mm, d in metres.
  const double d = 0.055;
  EXPECT_NEAR(p.rows[11].d_mm, 55.0, 1e-12);
  EXPECT_NEAR(p.rows[11].decentering_um, (7.8152e-4 + 5.0665e-2 * d * d) * d * d * 1e6, 1e-4);
  // The transformed curve: dR - k0 d with equal lobes, the abstract's "does not exceed 4.1 um".
  double area = 0.0, largest = 0.0;
  for (size_t i = 0; i + 1 < p.rows.size(); ++i) {
    area += 0.5 * (p.rows[i].transformed_um + p.rows[i + 1].transformed_um) * (p.rows[i + 1].d_mm - p.rows[i].d_mm);
    largest = std::max(largest, std::abs(p.rows[i].transformed_um));
  }
  EXPECT_LT(std::abs(area), 0.02 * 80.0 * largest);  // the trapezoid on 16 steps against Simpson's zero
  EXPECT_GT(largest, 3.8);
  EXPECT_LT(largest, 4.5);
  // C' = C (1 + k0) and the curve is dR - k0 d.
  EXPECT_NEAR(p.transformed_focal_length_mm, 80.17103 * (1.0 + p.k0), 1e-12);
  EXPECT_NEAR(p.rows[8].transformed_um, p.rows[8].radial_um - 1e3 * p.k0 * 40.0, 1e-9);
  // No covariance: no envelope.
  EXPECT_EQ(p.rows[8].radial_sigma_um, 0.0);
}

TEST(StellarDistortion, OrbigonAxisIsPerpendicularToPhiT) {
  // The tangential component of the decentering term is P d^2 sin(Phi_T - theta)
  // (derived from SlamaDistortion::Apply): largest at theta = Phi_T + 90 deg.
  StellarLensEstimate e = Orbigon();
  e.values[3] = 1.0636;  // xs, ys from the principal point (mm)
  e.values[4] = -1.1637;
  const StellarSymmetry s = StellarSymmetryOf(e);
  EXPECT_NEAR(s.x_mm, -0.0205 + 1.0636, 1e-12);
  EXPECT_NEAR(s.y_mm, -1.1637, 1e-12);
  EXPECT_TRUE(s.has_decentering);
  EXPECT_NEAR(s.axis_rad, 0.3 + M_PI / 2, M_PI / 720 + 1e-12);
  // The radial part is symmetric about (xs, ys): equal and opposite at equal distances.
  const Eigen::Vector2d a = StellarDistortion_um(e, StellarLensPart::kRadial, s.x_mm + 30, s.y_mm + 40);
  const Eigen::Vector2d b = StellarDistortion_um(e, StellarLensPart::kRadial, s.x_mm - 30, s.y_mm - 40);
  EXPECT_NEAR((a + b).norm(), 0.0, 1e-9);
  // Total = radial + decentering (both terms of the model are additive).
  const Eigen::Vector2d t = StellarDistortion_um(e, StellarLensPart::kTotal, 20, -35);
  const Eigen::Vector2d r = StellarDistortion_um(e, StellarLensPart::kRadial, 20, -35);
  const Eigen::Vector2d c = StellarDistortion_um(e, StellarLensPart::kDecentering, 20, -35);
  EXPECT_NEAR((t - r - c).norm(), 0.0, 1e-9);
}

TEST(StellarDistortion, BrownIsMinusItsCorrectionWithSeed000sProfileAndPhase) {
  StellarLensEstimate e;
  e.lens = DistortionModelId::kBrownConrady;
  const double k1 = 2e-6, k2 = -4e-10, k3 = 1e-14, p1 = 3.6e-6, p2 = -3.0e-6;
  e.values = {80.0, 0.01, -0.02, k1, k2, k3, p1, p2};
  // A covariance on k1..k3 with a correlation: the radial envelope is exact for a linear function.
  e.covariance = Eigen::MatrixXd::Zero(8, 8);
  const double s1 = 1e-8, s2 = 5e-12, s3 = 2e-16, rho = -0.9;
  e.covariance(3, 3) = s1 * s1;
  e.covariance(4, 4) = s2 * s2;
  e.covariance(5, 5) = s3 * s3;
  e.covariance(3, 4) = e.covariance(4, 3) = rho * s1 * s2;
  // Distortion = -correction: radial -(k1 r^3 + k2 r^5 + k3 r^7) along +x from the principal point.
  const double r = 30.0;
  const Eigen::Vector2d v = StellarDistortion_um(e, StellarLensPart::kRadial, 0.01 + r, -0.02);
  EXPECT_NEAR(v.x(), -1e3 * (k1 * std::pow(r, 3) + k2 * std::pow(r, 5) + k3 * std::pow(r, 7)), 1e-9);
  EXPECT_NEAR(v.y(), 0.0, 1e-12);
  const StellarProfile p = ComputeStellarProfile(e, 40.0, 4);
  const StellarProfileRow& row = p.rows[3];  // r = 30 mm
  ASSERT_NEAR(row.d_mm, r, 1e-12);
  const Eigen::Vector3d g = -1e3 * Eigen::Vector3d(std::pow(r, 3), std::pow(r, 5), std::pow(r, 7));
  const double sigma = std::sqrt(g.dot(e.covariance.block<3, 3>(3, 3) * g));
  EXPECT_NEAR(row.radial_sigma_um, sigma, 1e-6 * sigma);
  // Seed 000 eq. 15: P(r) = sqrt(p1^2 + p2^2) r^2; eq. 16: phi0 = atan2(-p1, p2) is the axis.
  EXPECT_NEAR(row.decentering_um, 1e3 * std::hypot(p1, p2) * r * r, 1e-4 * row.decentering_um);
  const double phi0 = std::atan2(-p1, p2);
  const StellarSymmetry s = StellarSymmetryOf(e);
  EXPECT_NEAR(std::remainder(s.axis_rad - phi0, M_PI), 0.0, M_PI / 720 + 1e-12);
}

TEST(StellarDistortion, RejectsAnEmptyRange) {
  EXPECT_THROW(ComputeStellarProfile(Orbigon(), 0.0, 10), Error);
  EXPECT_THROW(ComputeStellarProfile(Orbigon(), 80.0, 1), Error);
}

}  // namespace
}  // namespace platemeter
