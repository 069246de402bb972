// Rotation conventions of seeds 000 and 004: the SN-004 interlock of Table A.6,
// the senses the seed states, and seed 000's T matrix, checked against
// independent constructions with Eigen::AngleAxis.
#include <cmath>
#include <random>

#include <ceres/jet.h>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "platemeter/calib/rotations.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// Table A.6: "Relative orientation matrix defining a transformation from the
// Terrain Camera to the Stellar Camera", as printed.
Eigen::Matrix3d TableA6MatrixRotations() {
  Eigen::Matrix3d m;
  m << +0.99999994, +0.00025051, -0.00022525,  //
      -0.00019782, -0.10455878, -0.99451869,   //
      -0.00027269, +0.99451868, -0.10455872;
  return m;
}

// Rotation of the AXES by `angle` about a coordinate axis, as seed 004 states the
// senses, is the point rotation by -angle.
Eigen::Matrix3d AxesRotation(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(-angle, axis).toRotationMatrix();
}

TEST(RadiansFromDms, HandValues) {
  // -96 deg 00' 06.276" = -(96 + 6.276 / 3600) deg = -96.001743333 deg
  EXPECT_NEAR(RadiansFromDms(-1, 96, 0, 6.276), -96.001743333333 * M_PI / 180.0, 1e-13);
  // -0 deg 00' 56.246" keeps its sign.
  EXPECT_NEAR(RadiansFromDms(-1, 0, 0, 56.246), -56.246 / 206264.80624709636, 1e-15);
  EXPECT_NEAR(ArcsecFromRadians(1.0), 206264.80624709636, 1e-8);
  EXPECT_THROW(RadiansFromDms(0, 1, 0, 0.0), Error);
  EXPECT_THROW(RadiansFromDms(1, 1, 60, 0.0), Error);
  EXPECT_THROW(RadiansFromDms(1, 1, 0, 61.0), Error);
}

TEST(InterlockTableA6, AnglesFromThePrintedMatrix) {
  const OmegaPhiKappa angles = OmegaPhiKappaFromMatrix(TableA6MatrixRotations());
  // Printed: OMEGA = -96 deg 00' 06.276", PHI = -0 deg 00' 56.246",
  // KAPPA = +0 deg 00' 40.803". The 8-digit elements carry 1e-8 rad = 0.002".
  EXPECT_NEAR(ArcsecFromRadians(angles.omega_rad - RadiansFromDms(-1, 96, 0, 6.276)), 0.0, 0.01);
  EXPECT_NEAR(ArcsecFromRadians(angles.phi_rad - RadiansFromDms(-1, 0, 0, 56.246)), 0.0, 0.01);
  EXPECT_NEAR(ArcsecFromRadians(angles.kappa_rad - RadiansFromDms(+1, 0, 0, 40.803)), 0.0, 0.01);
}

TEST(InterlockTableA6, MatrixFromThePrintedAngles) {
  OmegaPhiKappa angles;
  angles.omega_rad = RadiansFromDms(-1, 96, 0, 6.276);
  angles.phi_rad = RadiansFromDms(-1, 0, 0, 56.246);
  angles.kappa_rad = RadiansFromDms(+1, 0, 0, 40.803);
  const Eigen::Matrix3d m = MatrixFromOmegaPhiKappa(angles);
  const Eigen::Matrix3d printed = TableA6MatrixRotations();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // 8 printed digits (5e-9) plus the angles' 0.001" (5e-9 rad).
      EXPECT_NEAR(m(i, j), printed(i, j), 1e-7) << i << "," << j;
    }
  }
}

TEST(OmegaPhiKappa, IsTheSeedsSequenceOfAxisRotations) {
  // omega about x, then phi about the new y', then kappa about the new z''.
  // Rotating axes in sequence composes as R(kappa) R(phi) R(omega).
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 20; ++trial) {
    const OmegaPhiKappa a{angle(rng), angle(rng) / 2, angle(rng)};
    const Eigen::Matrix3d expected = AxesRotation(a.kappa_rad, Eigen::Vector3d::UnitZ()) *
                                     AxesRotation(a.phi_rad, Eigen::Vector3d::UnitY()) *
                                     AxesRotation(a.omega_rad, Eigen::Vector3d::UnitX());
    EXPECT_LT((MatrixFromOmegaPhiKappa(a) - expected).norm(), 1e-14);
  }
}

TEST(OmegaPhiKappa, PositiveSensesAsTheSeedStatesThem) {
  // Rows of M are the new axes in old coordinates.
  const double small = 0.01;
  // "Positive omega rotates the +y axis toward the +z axis."
  EXPECT_GT(MatrixFromOmegaPhiKappa({small, 0.0, 0.0}).row(1).z(), 0.0);
  // "Positive phi rotates the +z' axis toward the +x' axis."
  EXPECT_GT(MatrixFromOmegaPhiKappa({0.0, small, 0.0}).row(2).x(), 0.0);
  // "Positive kappa rotates the +x'' axis toward the +y'' axis."
  EXPECT_GT(MatrixFromOmegaPhiKappa({0.0, 0.0, small}).row(0).y(), 0.0);
}

TEST(OmegaPhiKappa, AnglesRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 50; ++trial) {
    const OmegaPhiKappa a{angle(rng), 0.49 * angle(rng), angle(rng)};
    const OmegaPhiKappa b = OmegaPhiKappaFromMatrix(MatrixFromOmegaPhiKappa(a));
    EXPECT_NEAR(b.omega_rad, a.omega_rad, 1e-12);
    EXPECT_NEAR(b.phi_rad, a.phi_rad, 1e-12);
    EXPECT_NEAR(b.kappa_rad, a.kappa_rad, 1e-12);
  }
}

TEST(OmegaPhiKappa, RejectsBadMatrices) {
  Eigen::Matrix3d scaled = 1.01 * Eigen::Matrix3d::Identity();
  EXPECT_THROW(OmegaPhiKappaFromMatrix(scaled), Error);
  Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();
  reflection(2, 2) = -1.0;
  EXPECT_THROW(OmegaPhiKappaFromMatrix(reflection), Error);
  // phi = 90 deg: omega and kappa are not separable.
  EXPECT_THROW(OmegaPhiKappaFromMatrix(MatrixFromOmegaPhiKappa({0.3, M_PI / 2, 0.2})), Error);
}

TEST(Seed000TMatrix, MatchesTheSeedsPrintedElements) {
  // Elements written out from eq. (1)'s T, with (2,3) = sw ck - cw sp sk (the OCR
  // prints sw sk - cw sp sk, which is not orthogonal).
  const double p = 0.3, w = -0.7, k = 1.9;
  const double cp = std::cos(p), sp = std::sin(p), cw = std::cos(w), sw = std::sin(w), ck = std::cos(k),
               sk = std::sin(k);
  Eigen::Matrix3d printed;
  printed << cp * ck, cw * sk - sw * sp * ck, sw * sk + cw * sp * ck,  //
      -cp * sk, cw * ck + sw * sp * sk, sw * ck - cw * sp * sk,        //
      -sp, -sw * cp, cw * cp;
  EXPECT_LT((TMatrixFromAngles({p, w, k}) - printed).norm(), 1e-15);
}

TEST(Seed000TMatrix, IsOrthogonalAndSeed004WithPhiReversed) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 20; ++trial) {
    const PhiOmegaKappaT a{0.49 * angle(rng), angle(rng), angle(rng)};
    const Eigen::Matrix3d t = TMatrixFromAngles(a);
    EXPECT_LT((t.transpose() * t - Eigen::Matrix3d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(t.determinant(), 1.0, 1e-14);
    const Eigen::Matrix3d expected = AxesRotation(a.kappa_rad, Eigen::Vector3d::UnitZ()) *
                                     AxesRotation(-a.phi_rad, Eigen::Vector3d::UnitY()) *
                                     AxesRotation(a.omega_rad, Eigen::Vector3d::UnitX());
    EXPECT_LT((t - expected).norm(), 1e-14);
    const PhiOmegaKappaT b = AnglesFromTMatrix(t);
    EXPECT_NEAR(b.phi_rad, a.phi_rad, 1e-12);
    EXPECT_NEAR(b.omega_rad, a.omega_rad, 1e-12);
    EXPECT_NEAR(b.kappa_rad, a.kappa_rad, 1e-12);
  }
}

TEST(RotationTemplates, JetMatricesMatchDoubleAndFiniteDifferences) {
  using Jet = ceres::Jet<double, 3>;
  const double w = 0.4, p = -0.2, k = 2.5;
  Jet m[9];
  OmegaPhiKappaMatrixT(Jet(w, 0), Jet(p, 1), Jet(k, 2), m);
  const Eigen::Matrix3d value = MatrixFromOmegaPhiKappa({w, p, k});
  const double h = 1e-6;
  const Eigen::Matrix3d dw = (MatrixFromOmegaPhiKappa({w + h, p, k}) - MatrixFromOmegaPhiKappa({w - h, p, k})) / (2 * h);
  const Eigen::Matrix3d dp = (MatrixFromOmegaPhiKappa({w, p + h, k}) - MatrixFromOmegaPhiKappa({w, p - h, k})) / (2 * h);
  const Eigen::Matrix3d dk = (MatrixFromOmegaPhiKappa({w, p, k + h}) - MatrixFromOmegaPhiKappa({w, p, k - h})) / (2 * h);
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(m[i].a, value(i / 3, i % 3));
    EXPECT_NEAR(m[i].v[0], dw(i / 3, i % 3), 1e-9);
    EXPECT_NEAR(m[i].v[1], dp(i / 3, i % 3), 1e-9);
    EXPECT_NEAR(m[i].v[2], dk(i / 3, i % 3), 1e-9);
  }
  Jet t[9];
  TMatrixT(Jet(p, 0), Jet(w, 1), Jet(k, 2), t);
  const Eigen::Matrix3d t_value = TMatrixFromAngles({p, w, k});
  for (int i = 0; i < 9; ++i) EXPECT_EQ(t[i].a, t_value(i / 3, i % 3));
}

}  // namespace
}  // namespace platemeter
