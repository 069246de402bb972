// Terrain-to-stellar interlock of seed 004 (Lunar Mapping Camera SN-004), Table
// A.6: omega, phi, kappa and their standard deviations from the printed matrix
// and covariance; the propagation maps checked against finite differences, a
// Monte Carlo and each other; one-line errors. docs/interlock.md.
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "platemeter/calib/interlock.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// Seed 004 (/work/shared/seeds/004_02f421a20419daf1.txt), Table A.6, "Relative
// orientation matrix defining a transformation from the Terrain Camera to the
// Stellar Camera", as printed.
Eigen::Matrix3d TableA6Matrix() {
  Eigen::Matrix3d m;
  m << +0.99999994, +0.00025051, -0.00022525,  //
      -0.00019782, -0.10455878, -0.99451869,   //
      -0.00027269, +0.99451868, -0.10455872;
  return m;
}

// Table A.6, "Covariance Matrix", printed as "+0.21544 -09" etc. (mantissa and a
// separate power of ten: 0.21544e-9). Its diagonal is the covariance of
// (omega, phi, kappa) in rad^2 (docs/interlock.md).
Eigen::Matrix3d TableA6Covariance() {
  Eigen::Matrix3d c;
  c << +0.21544e-09, -0.30039e-11, -0.58996e-12,  //
      -0.30039e-11, +0.12097e-09, -0.79069e-11,   //
      -0.58996e-12, -0.79069e-11, +0.27709e-09;
  return c;
}

// Table A.6, "Relative Orientation Angles", OCR'd as "OMEGA = -96 <sup>0</sup>
// 00'06"276 | S.D. 3"0": degrees, minutes, seconds with the decimal mark after
// the seconds sign; the superscript 0 is the degree sign.
OmegaPhiKappa TableA6Angles() {
  return {RadiansFromDms(-1, 96, 0, 6.276), RadiansFromDms(-1, 0, 0, 56.246),
          RadiansFromDms(+1, 0, 0, 40.803)};
}
constexpr double kPrintedOmegaSigmaArcsec = 3.0;
constexpr double kPrintedPhiSigmaArcsec = 2.3;
constexpr double kPrintedKappaSigmaArcsec = 3.4;

double ArcsecDifference(double a_rad, double b_rad) { return ArcsecFromRadians(a_rad - b_rad); }

// A rotation of the AXES by the vector v (seed 004's senses) is the point
// rotation by -|v| about v.
Eigen::Matrix3d AxesRotation(const Eigen::Vector3d& v) {
  if (v.norm() == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(-v.norm(), v.normalized()).toRotationMatrix();
}

Eigen::Vector3d AnglesVector(const OmegaPhiKappa& a) { return {a.omega_rad, a.phi_rad, a.kappa_rad}; }

TEST(InterlockSeed004, PrintedAnglesFromThePrintedMatrix) {
  const OmegaPhiKappa printed = TableA6Angles();
  // The nearest rotation to the 8-digit elements (the least-squares fit of the
  // angles to all nine) reproduces the printed angles to 0.001": -0.0005",
  // +0.0000", +0.0005" -- the size of the elements' rounding (5e-9 = 0.001").
  const InterlockAngles nearest = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kAngles);
  EXPECT_NEAR(ArcsecDifference(nearest.angles.omega_rad, printed.omega_rad), 0.0, 0.001);
  EXPECT_NEAR(ArcsecDifference(nearest.angles.phi_rad, printed.phi_rad), 0.0, 0.001);
  EXPECT_NEAR(ArcsecDifference(nearest.angles.kappa_rad, printed.kappa_rad), 0.0, 0.001);
  EXPECT_LT(nearest.orthogonality_deviation, 1e-7);  // orthonormal to its 8 digits
  // The atan2 forms on the printed elements (m31, m32, m33, m21, m11) reproduce
  // them digit for digit: -96 00'06.2760", -0 00'56.2464", +0 00'40.8033".
  InterlockOptions element_forms;
  element_forms.angle_form = InterlockAngleForm::kElementAtan2;
  const InterlockAngles elements = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kAngles, element_forms);
  EXPECT_NEAR(ArcsecDifference(elements.angles.omega_rad, printed.omega_rad), 0.0, 0.0005);
  EXPECT_NEAR(ArcsecDifference(elements.angles.phi_rad, printed.phi_rad), 0.0, 0.0005);
  EXPECT_NEAR(ArcsecDifference(elements.angles.kappa_rad, printed.kappa_rad), 0.0, 0.0005);
  EXPECT_EQ(DmsFromRadians(elements.angles.omega_rad), "-96 00'06.276\"");
  EXPECT_EQ(DmsFromRadians(elements.angles.phi_rad), "-0 00'56.246\"");
  EXPECT_EQ(DmsFromRadians(elements.angles.kappa_rad), "+0 00'40.803\"");
  // The sigmas do not depend on the angle form.
  EXPECT_EQ(elements.covariance_rad2, nearest.covariance_rad2);
}

TEST(InterlockSeed004, PrintedAnglesGiveThePrintedMatrixWithinItsRounding) {
  // The angles are the adjusted quantities; the matrix was computed from them
  // and rounded to 8 decimals: every element agrees within 5e-9.
  const Eigen::Matrix3d m = MatrixFromOmegaPhiKappa(TableA6Angles());
  EXPECT_LE((m - TableA6Matrix()).cwiseAbs().maxCoeff(), 5.01e-9);
}

TEST(InterlockSeed004, PrintedSigmasFromThePrintedCovarianceOfTheAngles) {
  InterlockOptions element_forms;
  element_forms.angle_form = InterlockAngleForm::kElementAtan2;
  const InterlockAngles r = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kAngles, element_forms);
  // sqrt(0.21544e-9) rad = 3.027", sqrt(0.12097e-9) = 2.269", sqrt(0.27709e-9) = 3.434".
  EXPECT_NEAR(r.omega_sigma_arcsec, 3.0275, 0.0005);
  EXPECT_NEAR(r.phi_sigma_arcsec, 2.2686, 0.0005);
  EXPECT_NEAR(r.kappa_sigma_arcsec, 3.4335, 0.0005);
  // Printed to 0.1": 3"0, 2"3, 3"4.
  EXPECT_NEAR(r.omega_sigma_arcsec, kPrintedOmegaSigmaArcsec, 0.05);
  EXPECT_NEAR(r.phi_sigma_arcsec, kPrintedPhiSigmaArcsec, 0.05);
  EXPECT_NEAR(r.kappa_sigma_arcsec, kPrintedKappaSigmaArcsec, 0.05);
  // The angles are nearly uncorrelated: |rho| < 0.05.
  EXPECT_LT(std::abs(r.correlation(0, 1)), 0.05);
  EXPECT_LT(std::abs(r.correlation(0, 2)), 0.05);
  EXPECT_LT(std::abs(r.correlation(1, 2)), 0.05);
  EXPECT_NE(r.summary.find("omega -96 00'06.276\" +- 3.0\""), std::string::npos) << r.summary;
  EXPECT_NE(r.summary.find("phi -0 00'56.246\" +- 2.3\""), std::string::npos) << r.summary;
  EXPECT_NE(r.summary.find("kappa +0 00'40.803\" +- 3.4\""), std::string::npos) << r.summary;
}

TEST(InterlockSeed004, StellarAxesSmallRotationsGiveTheSameSigmas) {
  // Read as a small rotation of the stellar axes the printed covariance gives the
  // same sigmas to 0.01" (phi and kappa are under 1', so d angles / d d_s is the
  // identity to 3e-4): the table cannot tell these two readings apart.
  const InterlockAngles angles = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kAngles);
  const InterlockAngles stellar = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kSmallRotationStellarAxes);
  EXPECT_NEAR(stellar.omega_sigma_arcsec, angles.omega_sigma_arcsec, 0.01);
  EXPECT_NEAR(stellar.phi_sigma_arcsec, angles.phi_sigma_arcsec, 0.01);
  EXPECT_NEAR(stellar.kappa_sigma_arcsec, angles.kappa_sigma_arcsec, 0.01);
  EXPECT_NEAR(stellar.omega_sigma_arcsec, kPrintedOmegaSigmaArcsec, 0.05);
  EXPECT_NEAR(stellar.phi_sigma_arcsec, kPrintedPhiSigmaArcsec, 0.05);
  EXPECT_NEAR(stellar.kappa_sigma_arcsec, kPrintedKappaSigmaArcsec, 0.05);
}

TEST(InterlockSeed004, TerrainAxesSmallRotationsDoNotReproduceTheTable) {
  // Read as a small rotation of the terrain axes, omega = -96 deg turns the
  // terrain y and z into the stellar -z and y: phi and kappa swap their sigmas
  // (3.4" and 2.3"), which is not what Table A.6 prints.
  const InterlockAngles terrain = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), TableA6Covariance(), InterlockCovarianceKind::kSmallRotationTerrainAxes);
  EXPECT_NEAR(terrain.omega_sigma_arcsec, kPrintedOmegaSigmaArcsec, 0.05);
  EXPECT_NEAR(terrain.phi_sigma_arcsec, 3.4, 0.05);
  EXPECT_NEAR(terrain.kappa_sigma_arcsec, 2.3, 0.05);
  EXPECT_GT(std::abs(terrain.phi_sigma_arcsec - kPrintedPhiSigmaArcsec), 1.0);
}

TEST(InterlockSeed004, NineElementCovarianceReproducesTheSigmas) {
  // The printed 3x3 carried to the 9 matrix elements (reverse map, rank 3) and
  // back through the exact map from the printed matrix.
  const Matrix9d elements = MatrixCovarianceFromAngleCovariance(TableA6Angles(), TableA6Covariance());
  Eigen::SelfAdjointEigenSolver<Matrix9d> eigen(elements);
  EXPECT_LT(eigen.eigenvalues().head<6>().cwiseAbs().maxCoeff(), 1e-12 * eigen.eigenvalues()(8));
  const InterlockAngles r = InterlockAnglesFromMatrix(TableA6Matrix(), elements);
  EXPECT_LT((r.covariance_rad2 - TableA6Covariance()).cwiseAbs().maxCoeff(), 1e-6 * 0.27709e-9);
  EXPECT_NEAR(r.omega_sigma_arcsec, kPrintedOmegaSigmaArcsec, 0.05);
  EXPECT_NEAR(r.phi_sigma_arcsec, kPrintedPhiSigmaArcsec, 0.05);
  EXPECT_NEAR(r.kappa_sigma_arcsec, kPrintedKappaSigmaArcsec, 0.05);
  EXPECT_NE(r.summary.find("9 matrix elements"), std::string::npos) << r.summary;
  // m33 = cos(omega) cos(phi) moves with omega by sin(omega): its sigma is
  // omega's (1.47e-5) times |sin(-96 deg)| = 1.46e-5; m32's is times |cos| = 1.5e-6.
  const double omega = TableA6Angles().omega_rad;
  EXPECT_NEAR(std::sqrt(elements(8, 8)), std::sqrt(0.21544e-9) * std::abs(std::sin(omega)), 1e-8);
  EXPECT_NEAR(std::sqrt(elements(7, 7)), std::sqrt(0.21544e-9) * std::abs(std::cos(omega)), 1e-8);
}

TEST(InterlockSeed004, MonteCarloOfTheMatrixAgreesWithThePropagation) {
  // Draw the angles from the printed covariance, build exact matrices, add a
  // non-rotation stretch of the same size, and recover the angles through the
  // nearest rotation: the sample covariance matches the printed one.
  const OmegaPhiKappa mean = TableA6Angles();
  const Eigen::Matrix3d chol = TableA6Covariance().llt().matrixL();
  std::mt19937 rng(4004);
  std::normal_distribution<double> normal;
  const int n = 20000;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = chol * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    Eigen::Matrix3d stretch;
    for (int e = 0; e < 9; ++e) stretch(e / 3, e % 3) = 5e-6 * normal(rng);
    stretch = 0.5 * (stretch + stretch.transpose()).eval();
    const Eigen::Matrix3d m =
        MatrixFromOmegaPhiKappa({mean.omega_rad + d(0), mean.phi_rad + d(1), mean.kappa_rad + d(2)}) *
        (Eigen::Matrix3d::Identity() + stretch);
    const Eigen::Vector3d e = AnglesVector(OmegaPhiKappaFromMatrix(m)) - AnglesVector(mean);
    scatter += e * e.transpose();
  }
  const Eigen::Matrix3d sample = scatter / n;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(std::sqrt(sample(a, a) / TableA6Covariance()(a, a)), 1.0, 0.02) << a;
  }
}

TEST(InterlockPropagation, MatrixJacobianMatchesFiniteDifferencesThroughTheNearestRotation) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 10; ++trial) {
    Eigen::Matrix3d stretch;
    for (int e = 0; e < 9; ++e) stretch(e / 3, e % 3) = 1e-5 * normal(rng);
    const Eigen::Matrix3d m =
        MatrixFromOmegaPhiKappa({angle(rng), 0.45 * angle(rng), angle(rng)}) *
        (Eigen::Matrix3d::Identity() + stretch);
    const Matrix39d j = AnglesFromMatrixJacobian(m);
    const double h = 1e-7;
    for (int k = 0; k < 9; ++k) {
      Eigen::Matrix3d step = Eigen::Matrix3d::Zero();
      step(k / 3, k % 3) = h;
      const Eigen::Vector3d fd = (AnglesVector(OmegaPhiKappaFromMatrix(m + step)) -
                                  AnglesVector(OmegaPhiKappaFromMatrix(m - step))) /
                                 (2 * h);
      EXPECT_LT((j.col(k) - fd).cwiseAbs().maxCoeff(), 1e-6) << trial << " " << k;
    }
  }
}

TEST(InterlockPropagation, StretchingTheMatrixMovesNoAngle) {
  const Eigen::Matrix3d r = TableA6Matrix();
  const Matrix39d j = AnglesFromMatrixJacobian(r);
  const Eigen::Matrix3d rotation = NearestRotation(r);
  for (int a = 0; a < 3; ++a) {
    for (int b = a; b < 3; ++b) {
      Eigen::Matrix3d z = Eigen::Matrix3d::Zero();
      z(a, b) = z(b, a) = 1.0;
      const Eigen::Matrix3d dm = rotation * z;
      Eigen::Matrix<double, 9, 1> v;
      for (int e = 0; e < 9; ++e) v(e) = dm(e / 3, e % 3);
      EXPECT_LT((j * v).cwiseAbs().maxCoeff(), 1e-7) << a << b;
    }
  }
}

TEST(InterlockPropagation, ForwardAfterReverseIsTheIdentity) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 10; ++trial) {
    const OmegaPhiKappa a{angle(rng), 0.45 * angle(rng), angle(rng)};
    const Eigen::Matrix3d product =
        AnglesFromMatrixJacobian(MatrixFromOmegaPhiKappa(a)) * MatrixFromAnglesJacobian(a);
    EXPECT_LT((product - Eigen::Matrix3d::Identity()).norm(), 1e-12) << trial;
  }
}

TEST(InterlockPropagation, SmallRotationJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  const double h = 1e-6;
  for (int trial = 0; trial < 5; ++trial) {
    const OmegaPhiKappa a{angle(rng), 0.45 * angle(rng), angle(rng)};
    const Eigen::Matrix3d m = MatrixFromOmegaPhiKappa(a);
    for (const auto kind : {InterlockCovarianceKind::kSmallRotationStellarAxes,
                            InterlockCovarianceKind::kSmallRotationTerrainAxes}) {
      const Eigen::Matrix3d j = AnglesFromSmallRotationJacobian(a, kind);
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(i);
        auto perturbed = [&](const Eigen::Vector3d& d) {
          return kind == InterlockCovarianceKind::kSmallRotationStellarAxes ? Eigen::Matrix3d(AxesRotation(d) * m)
                                                                            : Eigen::Matrix3d(m * AxesRotation(d));
        };
        Eigen::Vector3d fd = (AnglesVector(OmegaPhiKappaFromMatrix(perturbed(step))) -
                              AnglesVector(OmegaPhiKappaFromMatrix(perturbed(-step)))) /
                             (2 * h);
        for (int c = 0; c < 3; ++c) fd(c) = std::remainder(fd(c) * 2 * h, 2 * M_PI) / (2 * h);
        EXPECT_LT((j.col(i) - fd).cwiseAbs().maxCoeff(), 1e-7)
            << InterlockCovarianceKindName(kind) << " " << trial << " " << i;
      }
    }
    // About the stellar x axis at phi = kappa = 0 the first small rotation is omega.
    const Eigen::Matrix3d at_omega_only = AnglesFromSmallRotationJacobian(
        {a.omega_rad, 0.0, 0.0}, InterlockCovarianceKind::kSmallRotationStellarAxes);
    EXPECT_LT((at_omega_only - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  }
}

TEST(InterlockPropagation, SmallRotationCovarianceRoundTrips) {
  const OmegaPhiKappa a = TableA6Angles();
  const Eigen::Matrix3d m = MatrixFromOmegaPhiKappa(a);
  for (const auto kind : {InterlockCovarianceKind::kAngles, InterlockCovarianceKind::kSmallRotationStellarAxes,
                          InterlockCovarianceKind::kSmallRotationTerrainAxes}) {
    const Eigen::Matrix3d small = SmallRotationCovarianceFromAngleCovariance(a, TableA6Covariance(), kind);
    const InterlockAngles back = InterlockAnglesFromRotationCovariance(m, small, kind);
    EXPECT_LT((back.covariance_rad2 - TableA6Covariance()).cwiseAbs().maxCoeff(), 1e-9 * 0.27709e-9)
        << InterlockCovarianceKindName(kind);
  }
  // d_s = M d_t: the two small-rotation covariances are related by M.
  const Eigen::Matrix3d stellar =
      SmallRotationCovarianceFromAngleCovariance(a, TableA6Covariance(), InterlockCovarianceKind::kSmallRotationStellarAxes);
  const Eigen::Matrix3d terrain =
      SmallRotationCovarianceFromAngleCovariance(a, TableA6Covariance(), InterlockCovarianceKind::kSmallRotationTerrainAxes);
  EXPECT_LT((m * terrain * m.transpose() - stellar).cwiseAbs().maxCoeff(), 1e-9 * 0.27709e-9);
}

TEST(InterlockDms, FormatsAsTheSeedPrints) {
  EXPECT_EQ(DmsFromRadians(RadiansFromDms(-1, 96, 0, 6.276)), "-96 00'06.276\"");
  EXPECT_EQ(DmsFromRadians(RadiansFromDms(+1, 0, 0, 59.9996)), "+0 01'00.000\"");
  EXPECT_EQ(DmsFromRadians(RadiansFromDms(-1, 0, 0, 0.0001)), "+0 00'00.000\"");
  EXPECT_EQ(DmsFromRadians(RadiansFromDms(+1, 12, 34, 56.7), 1), "+12 34'56.7\"");
}

void ExpectOneLineError(const std::function<void()>& call, const std::string& fragment) {
  try {
    call();
    ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

TEST(InterlockErrors, RejectsNonRotationsAndBadCovariances) {
  const Eigen::Matrix3d c = TableA6Covariance();
  const auto kAngles = InterlockCovarianceKind::kAngles;
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(1.01 * TableA6Matrix(), c, kAngles); },
                     "not orthonormal");
  Eigen::Matrix3d reflection = TableA6Matrix();
  reflection.row(2) *= -1.0;
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(reflection, c, kAngles); }, "determinant");
  ExpectOneLineError(
      [&] { InterlockAnglesFromRotationCovariance(MatrixFromOmegaPhiKappa({0.3, M_PI / 2, 0.2}), c, kAngles); },
      "not separable");
  Eigen::Matrix3d asymmetric = c;
  asymmetric(0, 1) += 1e-11;
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(TableA6Matrix(), asymmetric, kAngles); },
                     "not symmetric");
  Eigen::Matrix3d indefinite = c;
  indefinite(1, 1) = -0.12097e-09;
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(TableA6Matrix(), indefinite, kAngles); },
                     "not positive semi-definite");
  Eigen::Matrix3d not_finite = c;
  not_finite(2, 2) = NAN;
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(TableA6Matrix(), not_finite, kAngles); },
                     "non-finite");
  Matrix9d elements = Matrix9d::Identity();
  elements(3, 3) = -1.0;
  ExpectOneLineError([&] { InterlockAnglesFromMatrix(TableA6Matrix(), elements); }, "not positive semi-definite");
  ExpectOneLineError([&] { MatrixCovarianceFromAngleCovariance(TableA6Angles(), indefinite); },
                     "not positive semi-definite");
  InterlockOptions bad;
  bad.max_orthogonality_deviation = 0.0;
  std::string why;
  EXPECT_FALSE(bad.Check(&why));
  EXPECT_NE(why.find("max_orthogonality_deviation"), std::string::npos);
  ExpectOneLineError([&] { InterlockAnglesFromRotationCovariance(TableA6Matrix(), c, kAngles, bad); },
                     "max_orthogonality_deviation");
  EXPECT_TRUE(InterlockOptions{}.Check(&why));
}

TEST(InterlockErrors, AZeroCovarianceIsAllowed) {
  const InterlockAngles r = InterlockAnglesFromRotationCovariance(
      TableA6Matrix(), Eigen::Matrix3d::Zero(), InterlockCovarianceKind::kSmallRotationTerrainAxes);
  EXPECT_EQ(r.omega_sigma_arcsec, 0.0);
  EXPECT_EQ(r.correlation(0, 1), 0.0);
}

}  // namespace
}  // namespace platemeter
