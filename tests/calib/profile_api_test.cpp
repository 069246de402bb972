// ComputeDistortionProfile beyond the seed's tables: the balances, the sigmas
// against finite differences through a full covariance (c included), the
// degenerate cases and the errors.
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "platemeter/calib/distortion_profile.h"
#include "platemeter/calib/model_conversion.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {


// A full, well-conditioned covariance with the given sigmas and correlations
// rho_ij = 0.6 * cos(i + 2 j) (symmetrized): every parameter correlated with every other.
Eigen::MatrixXd FullCovariance(const std::vector<double>& sigmas) {
  const int n = int(sigmas.size());
  Eigen::MatrixXd rho = Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < i; ++j) rho(i, j) = rho(j, i) = 0.6 * std::cos(i + 2.0 * j) / (1.0 + 0.3 * (i - j));
  }
  // Make sure it is positive definite: shrink toward the identity if needed.
  while (Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(rho).eigenvalues().minCoeff() < 0.05) {
    rho = 0.8 * rho + 0.2 * Eigen::MatrixXd::Identity(n, n);
  }
  const Eigen::VectorXd s = Eigen::Map<const Eigen::VectorXd>(sigmas.data(), n);
  return s.asDiagonal() * rho * s.asDiagonal();
}

// Hasselblad-like lenses of each model of the common form, with full covariances.
LensEstimate Conrady() {
  LensEstimate lens;
  lens.model = DistortionModelId::kBrownConrady;
  lens.principal_distance_mm = 509.8;
  lens.params = {1.58e-5, -2.0e-9, 1.0e-13, 3.6e-6, 3.0e-6};
  lens.covariance = FullCovariance({2.0, 1.7e-7, 3e-10, 1e-13, 3.5e-6, 3.0e-6});
  return lens;
}
LensEstimate Affine() {
  LensEstimate lens;
  lens.model = DistortionModelId::kBrownAffine;
  lens.principal_distance_mm = 509.8;
  lens.params = {1.58e-5, -2.0e-9, 1.0e-13, 3.6e-6, 3.0e-6, 2e-5, -1e-5};
  lens.covariance = FullCovariance({2.0, 1.7e-7, 3e-10, 1e-13, 3.5e-6, 3.0e-6, 1e-5, 1e-5});
  return lens;
}
LensEstimate Balanced() {
  LensEstimate lens;
  lens.model = DistortionModelId::kBrownBalanced;
  lens.principal_distance_mm = 507.306;
  lens.params = {-0.14741e-1, +0.17241e-4, -0.95765e-9, +0.3858e-5, +0.1241e-5};
  lens.covariance = FullCovariance({0.072, 0.2e-5, 0.422e-6, 0.29277e-9, 0.8626e-6, 0.8375e-6});
  return lens;
}
LensEstimate Smac() {
  LensEstimate lens;
  lens.model = DistortionModelId::kSmacRadialDecentering;
  lens.principal_distance_mm = 75.8069;
  lens.params = {-0.1278842e-05, +0.5264148e-09, -0.5259516e-13, +0.3821279e-06, +0.4e-10, 3.371325};
  lens.covariance = FullCovariance({0.0016, 0.26e-7, 0.94e-11, 0.10e-14, 0.67e-7, 0.2e-10, 0.29});
  return lens;
}

DistortionProfileOptions Balance(RadialBalance balance, double max_radius_mm) {
  DistortionProfileOptions options;
  options.balance = balance;
  options.balance_radius_mm = 0.6 * max_radius_mm;
  options.max_radius_mm = max_radius_mm;
  options.radii_mm = {0.0, 0.2 * max_radius_mm, 0.45 * max_radius_mm, 0.7 * max_radius_mm, max_radius_mm};
  return options;
}

// Every value the profile reports, in one vector (for finite differences).
std::vector<double> Outputs(const DistortionProfile& p) {
  std::vector<double> out = {p.calibrated_focal_length_mm.value, p.decentering_j1_per_mm.value,
                             p.decentering_j2_per_mm3.value, p.phase_angle_rad.value};
  for (const ValueWithSigma& k : p.radial_coefficients) out.push_back(k.value);
  for (const DistortionProfileRow& row : p.rows) {
    out.push_back(row.radial_um);
    out.push_back(row.decentering_um);
  }
  return out;
}
std::vector<double> Sigmas(const DistortionProfile& p) {
  std::vector<double> out = {p.calibrated_focal_length_mm.sigma, p.decentering_j1_per_mm.sigma,
                             p.decentering_j2_per_mm3.sigma, p.phase_angle_rad.sigma};
  for (const ValueWithSigma& k : p.radial_coefficients) out.push_back(k.sigma);
  for (const DistortionProfileRow& row : p.rows) {
    out.push_back(row.radial_sigma_um);
    out.push_back(row.decentering_sigma_um);
  }
  return out;
}

TEST(DistortionProfileSigmas, AutomaticDifferentiationMatchesFiniteDifferences) {
  struct Case {
    const char* name;
    LensEstimate lens;
    double max_radius_mm;
  };
  for (const Case& c : {Case{"brown-conrady", Conrady(), 39.0}, Case{"brown-affine", Affine(), 39.0},
                        Case{"brown-balanced", Balanced(), 39.0}, Case{"smac", Smac(), 80.8}}) {
    for (RadialBalance balance : {RadialBalance::kAsGiven, RadialBalance::kZeroAtRadius,
                                  RadialBalance::kEqualLobePeaks, RadialBalance::kEqualLobeAreas}) {
      SCOPED_TRACE(::testing::Message() << c.name << ", " << RadialBalanceName(balance));
      const DistortionProfileOptions options = Balance(balance, c.max_radius_mm);
      const DistortionProfile profile = ComputeDistortionProfile(c.lens, options);
      const std::vector<double> values = Outputs(profile);
      const std::vector<double> sigmas = Sigmas(profile);
      // Central differences of every output in every parameter (c first).
      const int n = int(c.lens.covariance.rows());
      Eigen::MatrixXd jacobian(values.size(), n);
      for (int i = 0; i < n; ++i) {
        const double value = i == 0 ? c.lens.principal_distance_mm : c.lens.params[i - 1];
        const double h = 1e-4 * std::sqrt(c.lens.covariance(i, i));
        LensEstimate plus = c.lens, minus = c.lens;
        (i == 0 ? plus.principal_distance_mm : plus.params[i - 1]) = value + h;
        (i == 0 ? minus.principal_distance_mm : minus.params[i - 1]) = value - h;
        const std::vector<double> up = Outputs(ComputeDistortionProfile(plus, options));
        const std::vector<double> down = Outputs(ComputeDistortionProfile(minus, options));
        for (size_t k = 0; k < values.size(); ++k) jacobian(k, i) = (up[k] - down[k]) / (2 * h);
      }
      for (size_t k = 0; k < values.size(); ++k) {
        const double numeric = PropagatedSigma(c.lens.covariance, jacobian.row(k).transpose());
        EXPECT_NEAR(sigmas[k], numeric, 1e-5 * numeric + 1e-12) << "output " << k;
      }
      // c enters c' only: with c alone uncertain, no radial or decentering sigma.
      LensEstimate only_c = c.lens;
      only_c.covariance.setZero();
      only_c.covariance(0, 0) = 4.0;
      const DistortionProfile from_c = ComputeDistortionProfile(only_c, options);
      EXPECT_NEAR(from_c.calibrated_focal_length_mm.sigma, 2.0 * from_c.scale, 1e-12);
      for (const DistortionProfileRow& row : from_c.rows) {
        EXPECT_EQ(row.radial_sigma_um, 0.0);
        EXPECT_EQ(row.decentering_sigma_um, 0.0);
      }
    }
  }
}

TEST(DistortionProfileBalance, ZeroAtRadiusIsZeroWithZeroSigma) {
  DistortionProfileOptions options;
  options.balance = RadialBalance::kZeroAtRadius;
  options.balance_radius_mm = 30.0;
  options.radii_mm = {30.0};
  for (const LensEstimate& lens : {Conrady(), Affine(), Balanced(), Smac()}) {
    const DistortionProfile p = ComputeDistortionProfile(lens, options);
    EXPECT_NEAR(p.rows[0].radial_um, 0.0, 1e-9);
    EXPECT_NEAR(p.rows[0].radial_sigma_um, 0.0, 1e-9);
    // k0' = -(k1' R^2 + k2' R^4 + k3' R^6) (model_conversion.h).
    const auto& k = p.radial_coefficients;
    EXPECT_NEAR(k[0].value, -(k[1].value * 900 + k[2].value * 810000 + k[3].value * 729e6), 1e-15);
  }
}

TEST(DistortionProfileBalance, GaussianBalancedIsTheExactConversion) {
  // The profile's balanced coefficients are those of ConvertLens to brown-balanced at R.
  LensEstimate gaussian = Conrady();
  // brown-balanced holds no k3: neither its value nor its uncertainty.
  gaussian.params[2] = 0.0;
  gaussian.covariance.row(3).setZero();
  gaussian.covariance.col(3).setZero();
  ConversionOptions conversion;
  conversion.format_width_mm = conversion.format_height_mm = 55.0;
  conversion.balance_radius_mm = 30.0;
  const LensConversion balanced = ConvertLens(gaussian, DistortionModelId::kBrownBalanced, conversion);
  ASSERT_TRUE(balanced.exact) << balanced.summary;
  DistortionProfileOptions options;
  options.balance = RadialBalance::kZeroAtRadius;
  options.balance_radius_mm = 30.0;
  const DistortionProfile p = ComputeDistortionProfile(gaussian, options);
  EXPECT_NEAR(p.calibrated_focal_length_mm.value, balanced.lens.principal_distance_mm, 1e-12);
  EXPECT_NEAR(p.calibrated_focal_length_mm.sigma, std::sqrt(balanced.lens.covariance(0, 0)), 1e-12);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(p.radial_coefficients[i].value, balanced.lens.params[i], 1e-18 + 1e-12 * std::abs(balanced.lens.params[i]));
    EXPECT_NEAR(p.radial_coefficients[i].sigma, std::sqrt(balanced.lens.covariance(i + 1, i + 1)),
                1e-9 * p.radial_coefficients[i].sigma + 1e-20);
  }
  // And the balanced lens as given has the same profile again.
  DistortionProfileOptions as_given;
  as_given.radii_mm = options.radii_mm;
  const DistortionProfile again = ComputeDistortionProfile(balanced.lens, as_given);
  for (size_t i = 0; i < p.rows.size(); ++i) {
    EXPECT_NEAR(again.rows[i].radial_um, p.rows[i].radial_um, 1e-9);
    EXPECT_NEAR(again.rows[i].radial_sigma_um, p.rows[i].radial_sigma_um, 1e-9);
    EXPECT_NEAR(again.rows[i].decentering_um, p.rows[i].decentering_um, 1e-9);
    EXPECT_NEAR(again.rows[i].decentering_sigma_um, p.rows[i].decentering_sigma_um, 1e-9);
  }
}

// delta_r'(r) from the profile's coefficients.
double Radial_mm(const DistortionProfile& p, double r) {
  const auto& k = p.radial_coefficients;
  return r * (k[0].value + r * r * (k[1].value + r * r * (k[2].value + r * r * k[3].value)));
}

TEST(DistortionProfileBalance, EqualLobePeaksIsTheMinimax) {
  for (const LensEstimate& lens : {Balanced(), Smac()}) {
    const double m = lens.model == DistortionModelId::kSmacRadialDecentering ? 80.8 : 38.9;
    const DistortionProfile p = ComputeDistortionProfile(lens, Balance(RadialBalance::kEqualLobePeaks, m));
    double high = 0.0, low = 0.0;
    for (int k = 0; k <= 20000; ++k) {
      const double v = Radial_mm(p, m * k / 20000);
      high = std::max(high, v);
      low = std::min(low, v);
    }
    EXPECT_GT(high, 1e-4);
    // Equal to 1e-8 mm: 20000 samples find a peak to ~1e-9 mm.
    EXPECT_NEAR(high, -low, 1e-8) << "lobes " << high * 1e3 << " and " << low * 1e3 << " um";
    // Any other scale makes the largest |delta'| larger.
    for (double factor : {1.0 - 1e-6, 1.0 + 1e-6}) {
      double worst = 0.0;
      for (int k = 0; k <= 20000; ++k) {
        const double r = m * k / 20000;
        worst = std::max(worst, std::abs(factor * (Radial_mm(p, r) + r) - r));
      }
      EXPECT_GT(worst, high);
    }
  }
}

TEST(DistortionProfileBalance, EqualLobeAreasHasZeroIntegral) {
  const double m = 38.9;
  const DistortionProfile p = ComputeDistortionProfile(Balanced(), Balance(RadialBalance::kEqualLobeAreas, m));
  // Simpson's rule is exact for the polynomial up to rounding with this many panels.
  const int panels = 2000;
  double integral = Radial_mm(p, 0) + Radial_mm(p, m);
  for (int k = 1; k < panels; ++k) integral += (k % 2 ? 4 : 2) * Radial_mm(p, m * k / panels);
  integral *= m / panels / 3;
  EXPECT_NEAR(integral, 0.0, 1e-12);
  EXPECT_NE(p.scale, 1.0);
}

TEST(DistortionProfileDecentering, SmacProfileAndPhase) {
  LensEstimate lens = Smac();
  lens.covariance.setZero();
  lens.covariance(6, 6) = std::pow(0.29, 2);  // theta0 only
  DistortionProfileOptions options;
  options.radii_mm = {10.0, 40.0, 80.0};
  const DistortionProfile p = ComputeDistortionProfile(lens, options);
  const double j1 = lens.params[3], j2 = lens.params[4];
  for (const DistortionProfileRow& row : p.rows) {
    EXPECT_NEAR(row.decentering_um, std::abs(j1 + j2 * row.r_mm * row.r_mm) * row.r_mm * row.r_mm * 1e3, 1e-12);
    EXPECT_NEAR(row.decentering_sigma_um, 0.0, 1e-15);  // the phase does not change the length
  }
  // theta0 = 3.371325 rad (193.2 deg) is phi0 = -166.8 deg, its sigma theta0's.
  EXPECT_NEAR(p.phase_angle_rad.value, 3.371325 - 2 * M_PI, 1e-12);
  EXPECT_NEAR(p.phase_angle_rad.sigma, 0.29, 1e-12);
  EXPECT_NEAR(p.decentering_j1_per_mm.value, j1, 1e-18);
  EXPECT_NEAR(p.decentering_j2_per_mm3.value, j2, 1e-22);
}

TEST(DistortionProfileDecentering, NoDecenteringHasNoPhase) {
  LensEstimate lens = Balanced();
  lens.params[3] = lens.params[4] = 0.0;
  lens.covariance.setZero();
  lens.covariance(4, 4) = 4e-12;  // sigma(p1) = 2e-6
  lens.covariance(5, 5) = 1e-12;  // sigma(p2) = 1e-6
  DistortionProfileOptions options;
  options.radii_mm = {0.0, 10.0};
  const DistortionProfile p = ComputeDistortionProfile(lens, options);
  EXPECT_TRUE(std::isnan(p.phase_angle_rad.value));
  EXPECT_TRUE(std::isnan(p.phase_angle_rad.sigma));
  EXPECT_EQ(p.rows[1].decentering_um, 0.0);
  // The worst direction: r^2 sigma(p1).
  EXPECT_NEAR(p.rows[1].decentering_sigma_um, 100.0 * 2e-6 * 1e3, 1e-12);
  EXPECT_NEAR(p.decentering_j1_per_mm.sigma, 2e-6, 1e-18);
}

TEST(DistortionProfileOptions, Checks) {
  std::string why;
  DistortionProfileOptions options;
  EXPECT_TRUE(options.Check(&why)) << why;
  options.radii_mm = {};
  EXPECT_FALSE(options.Check(&why));
  options.radii_mm = {0.0, -1.0};
  EXPECT_FALSE(options.Check(&why));
  EXPECT_NE(why.find("-1"), std::string::npos);
  options.radii_mm = {NAN};
  EXPECT_FALSE(options.Check(&why));
  options = {};
  options.balance = RadialBalance::kZeroAtRadius;
  options.balance_radius_mm = 0.0;
  EXPECT_FALSE(options.Check(&why));
  options = {};
  options.balance = RadialBalance::kEqualLobePeaks;
  EXPECT_FALSE(options.Check(&why));  // no range
  options.max_radius_mm = 38.9;
  EXPECT_TRUE(options.Check(&why));
}

TEST(DistortionProfileErrors, BadLensesAreErrors) {
  DistortionProfileOptions options;
  LensEstimate lens = Balanced();
  lens.covariance = Eigen::MatrixXd::Zero(3, 3);
  EXPECT_THROW(ComputeDistortionProfile(lens, options), Error);
  lens = Balanced();
  lens.covariance(1, 2) += 1e-9;  // not symmetric
  EXPECT_THROW(ComputeDistortionProfile(lens, options), Error);
  lens = Balanced();
  lens.params.pop_back();
  EXPECT_THROW(ComputeDistortionProfile(lens, options), Error);
  LensEstimate slama;
  slama.model = DistortionModelId::kSlama;
  slama.principal_distance_mm = 80.171;
  slama.params = {1.0, -1.0, 0.36, -110, 9500, 7.8e-4, 5e-2, 0.0};
  slama.covariance = Eigen::MatrixXd::Zero(9, 9);
  try {
    ComputeDistortionProfile(slama, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("orbigon-11"), std::string::npos) << e.what();
  }
}

TEST(DistortionProfileRadii, DefaultsFollowTheFormat) {
  auto expect = [](double width, double height, std::vector<double> steps) {
    const std::vector<double> radii = DefaultProfileRadii_mm(width, height);
    steps.push_back(FormatHalfDiagonal_mm(width, height));  // the corner
    EXPECT_EQ(radii, steps);
  };
  expect(55, 55, {0, 5, 10, 15, 20, 25, 30, 35});          // 38.89 mm
  expect(114.3, 114.3, {0, 10, 20, 30, 40, 50, 60, 70, 80});  // 80.82 mm
  expect(24, 24, {0, 2, 4, 6, 8, 10, 12, 14, 16});          // 16.97 mm
  expect(20, 0.1, {0, 2, 4, 6, 8});                         // 10.0003 mm: no row 0.0003 mm from the corner
  EXPECT_NEAR(FormatHalfDiagonal_mm(55, 55), 38.890873, 1e-6);
}

TEST(LensEstimateFromDefinition, SigmasAndCorrelations) {
  LensCalibration lens;
  lens.model = "brown-balanced";
  lens.principal_distance_mm = 507.306;
  lens.coefficients = {{"k0", -0.014741}, {"k1_per_mm2", 1.7241e-5}, {"k2_per_mm4", -9.5765e-10},
                       {"p1_per_mm", 3.858e-6}, {"p2_per_mm", 1.241e-6}};
  lens.sigmas = {{"principal_distance_mm", 0.072}, {"k1_per_mm2", 0.422e-6}, {"k2_per_mm4", 0.29277e-9}};
  std::vector<std::string> without_sigma;
  LensEstimate estimate = LensEstimateFromCalibration(lens, "test", &without_sigma);
  EXPECT_EQ(without_sigma, (std::vector<std::string>{"k0", "p1_per_mm", "p2_per_mm"}));
  EXPECT_EQ(estimate.ParameterNames().front(), "principal_distance_mm");
  EXPECT_NEAR(estimate.covariance(0, 0), 0.072 * 0.072, 1e-15);
  SetCorrelation(&estimate, "k1_per_mm2", "k2_per_mm4", -0.5);
  EXPECT_NEAR(estimate.covariance(2, 3), -0.5 * 0.422e-6 * 0.29277e-9, 1e-30);
  EXPECT_EQ(estimate.covariance(2, 3), estimate.covariance(3, 2));
  EXPECT_THROW(SetCorrelation(&estimate, "k1_per_mm2", "k9", 0.1), Error);
  EXPECT_THROW(SetCorrelation(&estimate, "k1_per_mm2", "k1_per_mm2", 0.1), Error);
  EXPECT_THROW(SetCorrelation(&estimate, "k1_per_mm2", "k0", 1.5), Error);
}

}  // namespace
}  // namespace platemeter
