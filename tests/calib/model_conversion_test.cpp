// Conversions between the lens models, checked through the models' own Apply
// functions: an exact conversion reproduces the field (in the focal length it
// goes with) to 1e-9 mm; a fitted one reports its RMS and maximum residual.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/calib/model_conversion.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"

namespace platemeter {
namespace {

constexpr double kExactMm = 1e-9;  // mm; the brief's bound for an exact conversion

ConversionOptions Format(double side_mm) {
  ConversionOptions options;
  options.format_width_mm = side_mm;
  options.format_height_mm = side_mm;
  return options;
}

// The ideal point of a measured point (relative to the principal point) divided
// by c: what the collinearity equations see. Equal for two lenses that are the
// same camera, whatever their focal lengths.
Eigen::Vector2d Projection(const LensEstimate& lens, double x, double y) {
  Eigen::Vector2d ideal;
  VisitDistortionModel(lens.model, [&](auto model) {
    using M = decltype(model);
    IdealFromMeasured<M>(lens.params.data(), x, y, &ideal.x(), &ideal.y());
  });
  return ideal / lens.principal_distance_mm;
}

// Largest difference over a grid of the format of c_b times the two projections (mm).
double LargestFieldDifference_mm(const LensEstimate& a, const LensEstimate& b, double side_mm) {
  double worst = 0.0;
  for (int j = 0; j <= 20; ++j) {
    for (int i = 0; i <= 20; ++i) {
      const double x = side_mm * (i / 20.0 - 0.5), y = side_mm * (j / 20.0 - 0.5);
      worst = std::max(worst, ((Projection(a, x, y) - Projection(b, x, y)) * b.principal_distance_mm).norm());
    }
  }
  return worst;
}

LensEstimate Estimate(DistortionModelId model, double c_mm, std::vector<double> params) {
  LensEstimate lens;
  lens.model = model;
  lens.principal_distance_mm = c_mm;
  lens.params = std::move(params);
  const int n = 1 + int(lens.params.size());
  lens.covariance = Eigen::MatrixXd::Zero(n, n);
  lens.covariance(0, 0) = 1e-4;
  for (int i = 1; i < n; ++i) lens.covariance(i, i) = std::pow(0.1 * lens.params[i - 1] + 1e-30, 2);
  return lens;
}

// SN-004 terrain lens No. 203 (seed 004, Table A.4), J2 as printed (1.17e-20: zero in effect).
LensEstimate Sn004(double j2 = +0.1168324e-19) {
  return Estimate(DistortionModelId::kSmacRadialDecentering, 75.8069,
                  {-0.1278842e-05, +0.5264148e-09, -0.5259516e-13, +0.3821279e-06, j2, 3.371325});
}

TEST(ModelConversionSigns, SmacDecenteringIsBrownsWithP1MinusJ1SinTheta0) {
  // Through both models' Apply: K = k and p1 = -J1 sin(theta0), p2 = J1 cos(theta0).
  const double k1 = -1.3e-6, k2 = 5.3e-10, k3 = -5.3e-14, j1 = 3.8e-7;
  for (double theta0 : {0.3, 1.9, 3.371325, -2.5}) {
    double p1, p2;
    BrownDecenteringFromSmac(j1, theta0, &p1, &p2);
    EXPECT_DOUBLE_EQ(p1, -j1 * std::sin(theta0));
    EXPECT_DOUBLE_EQ(p2, j1 * std::cos(theta0));
    const std::vector<double> smac = {k1, k2, k3, j1, 0.0, theta0};
    const std::vector<double> brown = {k1, k2, k3, p1, p2};
    for (double x : {-50.0, -7.0, 13.0, 55.0}) {
      for (double y : {-40.0, 0.0, 21.0}) {
        double sx, sy, bx, by;
        SmacRadialDecentering::Apply(smac.data(), x, y, &sx, &sy);
        BrownConrady::Apply(brown.data(), x, y, &bx, &by);
        EXPECT_NEAR(sx, bx, 1e-15);
        EXPECT_NEAR(sy, by, 1e-15);
      }
    }
    double j1_back, theta_back;
    SmacDecenteringFromBrown(p1, p2, &j1_back, &theta_back);
    EXPECT_NEAR(j1_back, j1, 1e-20);
    EXPECT_NEAR(std::remainder(theta_back - theta0, 2 * M_PI), 0.0, 1e-12);
  }
}

TEST(ModelConversionExact, BrownFromSmacAndBack) {
  const LensEstimate smac = Sn004(0.0);
  const LensConversion brown = ConvertLens(smac, DistortionModelId::kBrownConrady, Format(114.3));
  EXPECT_TRUE(brown.exact) << brown.summary;
  EXPECT_EQ(brown.lens.principal_distance_mm, smac.principal_distance_mm);
  EXPECT_LT(LargestFieldDifference_mm(smac, brown.lens, 114.3), kExactMm);
  const LensConversion back = ConvertLens(brown.lens, DistortionModelId::kSmacRadialDecentering, Format(114.3));
  EXPECT_TRUE(back.exact) << back.summary;
  EXPECT_LT(LargestFieldDifference_mm(smac, back.lens, 114.3), kExactMm);
  // theta0 comes back in (-pi, pi]: 3.371325 - 2 pi.
  EXPECT_NEAR(back.lens.params[5], 3.371325 - 2 * M_PI, 1e-12);
  EXPECT_NEAR(back.lens.params[3], smac.params[3], 1e-20);
}

TEST(ModelConversionExact, CovarianceThroughTheJacobian) {
  // p1 = -J1 sin(theta0): sigma(p1)^2 = sin^2 sigma(J1)^2 + J1^2 cos^2 sigma(theta0)^2.
  LensEstimate smac = Sn004(0.0);
  const double j1 = smac.params[3], theta0 = smac.params[5];
  smac.covariance.setZero();
  smac.covariance(4, 4) = std::pow(0.67e-7, 2);
  smac.covariance(6, 6) = std::pow(0.29, 2);
  const LensConversion brown = ConvertLens(smac, DistortionModelId::kBrownConrady, Format(114.3));
  const double s = std::sin(theta0), c = std::cos(theta0);
  EXPECT_NEAR(brown.lens.covariance(4, 4), s * s * 0.67e-7 * 0.67e-7 + j1 * j1 * c * c * 0.29 * 0.29, 1e-25);
  EXPECT_NEAR(brown.lens.covariance(5, 5), c * c * 0.67e-7 * 0.67e-7 + j1 * j1 * s * s * 0.29 * 0.29, 1e-25);
  EXPECT_NEAR(brown.lens.covariance(4, 5), s * c * (-0.67e-7 * 0.67e-7 + j1 * j1 * 0.29 * 0.29), 1e-25);
}

TEST(ModelConversionExact, GaussianAndBalancedAreTheSameCamera) {
  // Table 6 (brown-balanced) -> Gaussian: c = c'/(1 + k0'), k = k'/(1 + k0'), p = p'/(1 + k0').
  const LensEstimate table6 = Estimate(DistortionModelId::kBrownBalanced, 507.306,
                                       {-0.14741e-1, +0.17241e-4, -0.95765e-9, +0.3858e-5, +0.1241e-5});
  const LensConversion gaussian = ConvertLens(table6, DistortionModelId::kBrownConrady, Format(55));
  ASSERT_TRUE(gaussian.exact) << gaussian.summary;
  const double s = 1.0 - 0.14741e-1;
  EXPECT_NEAR(gaussian.lens.principal_distance_mm, 507.306 / s, 1e-9);
  EXPECT_NEAR(gaussian.lens.params[0], 0.17241e-4 / s, 1e-18);
  EXPECT_NEAR(gaussian.lens.params[3], 0.3858e-5 / s, 1e-18);
  EXPECT_LT(LargestFieldDifference_mm(table6, gaussian.lens, 55), kExactMm);
  // Back, balanced at 30 mm: c' = c / g(30), zero radial distortion at 30 mm.
  ConversionOptions at30 = Format(55);
  at30.balance_radius_mm = 30.0;
  const LensConversion balanced = ConvertLens(gaussian.lens, DistortionModelId::kBrownBalanced, at30);
  ASSERT_TRUE(balanced.exact) << balanced.summary;
  EXPECT_LT(LargestFieldDifference_mm(table6, balanced.lens, 55), kExactMm);
  const std::vector<double>& k = balanced.lens.params;
  EXPECT_NEAR(30 * (k[0] + 900 * (k[1] + 900 * k[2])), 0.0, 1e-13);
  const double g30 = 1 + 900 * (gaussian.lens.params[0] + 900 * gaussian.lens.params[1]);
  EXPECT_NEAR(balanced.lens.principal_distance_mm, gaussian.lens.principal_distance_mm / g30, 1e-9);
  // Table 6 is balanced at 30 mm already (to 6e-6 mm, so lambda = 1 - 2e-7): the same numbers.
  EXPECT_NEAR(balanced.lens.principal_distance_mm, 507.306, 2e-4);
  EXPECT_NEAR(k[0], -0.14741e-1, 3e-7);
  // Without a balance radius the Gaussian lens is brown-balanced with k0' = 0.
  const LensConversion plain = ConvertLens(gaussian.lens, DistortionModelId::kBrownBalanced, Format(55));
  EXPECT_TRUE(plain.exact);
  EXPECT_EQ(plain.lens.params[0], 0.0);
  EXPECT_EQ(plain.lens.principal_distance_mm, gaussian.lens.principal_distance_mm);
}

TEST(ModelConversionExact, BrownAffineWithoutAffinityIsBrownConrady) {
  const LensEstimate affine =
      Estimate(DistortionModelId::kBrownAffine, 509.8, {1.58e-5, -2e-9, 1e-13, 3.6e-6, 3.0e-6, 0.0, 0.0});
  const LensConversion conrady = ConvertLens(affine, DistortionModelId::kBrownConrady, Format(55));
  EXPECT_TRUE(conrady.exact);
  EXPECT_LT(LargestFieldDifference_mm(affine, conrady.lens, 55), kExactMm);
  const LensConversion back = ConvertLens(conrady.lens, DistortionModelId::kBrownAffine, Format(55));
  EXPECT_TRUE(back.exact);
  EXPECT_LT(LargestFieldDifference_mm(affine, back.lens, 55), kExactMm);
}

TEST(ModelConversionFit, SmacJ2HasNoBrownCounterpart) {
  // J2 = 2e-10 1/mm^3: 8.5 um of decentering (J2 r^4) at the corner of the
  // 114.3 mm format, which Brown's r^2 terms cannot hold.
  const LensEstimate smac = Sn004(2e-10);
  const LensConversion brown = ConvertLens(smac, DistortionModelId::kBrownConrady, Format(114.3));
  EXPECT_FALSE(brown.exact);
  EXPECT_GT(brown.rms_residual_mm, 1e-4);
  EXPECT_LT(brown.rms_residual_mm, 3e-3);
  EXPECT_GE(brown.max_residual_mm, brown.rms_residual_mm);
  EXPECT_EQ(brown.num_points, 21 * 21);
  EXPECT_NE(brown.summary.find("RMS residual"), std::string::npos);
  // The reported residuals are those of the returned lens.
  EXPECT_NEAR(LargestFieldDifference_mm(smac, brown.lens, 114.3), brown.max_residual_mm, 1e-9);
  // The fit beats simply dropping J2.
  LensEstimate dropped = smac;
  dropped.params[4] = 0.0;
  EXPECT_LT(brown.max_residual_mm, LargestFieldDifference_mm(smac, dropped, 114.3));
  // The covariance went through the fit: p1, p2 now carry J2's uncertainty too.
  EXPECT_EQ(brown.lens.covariance.rows(), 6);
  EXPECT_GT(brown.lens.covariance(4, 4), 0.0);
  EXPECT_EQ(brown.lens.covariance(4, 5), brown.lens.covariance(5, 4));
}

TEST(ModelConversionFit, FitCovarianceMatchesFiniteDifferences) {
  const LensEstimate smac = Sn004(2e-10);
  // d p1 / d J2 by central differences of the whole fit.
  LensEstimate plus = smac, minus = smac;
  const double h = 2e-11;
  plus.params[4] += h;
  minus.params[4] -= h;
  const double numeric = (ConvertLens(plus, DistortionModelId::kBrownConrady, Format(114.3)).lens.params[3] -
                          ConvertLens(minus, DistortionModelId::kBrownConrady, Format(114.3)).lens.params[3]) /
                         (2 * h);
  LensEstimate only_j2 = smac;
  only_j2.covariance.setZero();
  only_j2.covariance(5, 5) = 1.0;
  const LensConversion unit = ConvertLens(only_j2, DistortionModelId::kBrownConrady, Format(114.3));
  EXPECT_NEAR(std::sqrt(unit.lens.covariance(4, 4)), std::abs(numeric), 1e-6 * std::abs(numeric));
}

TEST(ModelConversionFit, GenericFieldFit) {
  // A model fitted to itself from a poor start: the same field.
  const LensEstimate smac = Sn004(0.0);
  const FieldFit self = FitDistortionField(DistortionModelId::kSmacRadialDecentering, smac.params,
                                           DistortionModelId::kSmacRadialDecentering,
                                           {0.0, 0.0, 0.0, 1e-7, 0.0, 2.5}, Format(114.3));
  EXPECT_TRUE(self.converged) << self.summary;
  EXPECT_LT(self.max_residual_mm, kExactMm) << self.summary;
  // Brown from seed 004 without J2: exact, as the closed form.
  const FieldFit brown = FitDistortionField(DistortionModelId::kSmacRadialDecentering, smac.params,
                                            DistortionModelId::kBrownConrady, {}, Format(114.3));
  EXPECT_LT(brown.max_residual_mm, kExactMm) << brown.summary;
  const LensConversion closed = ConvertLens(smac, DistortionModelId::kBrownConrady, Format(114.3));
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(brown.params[i], closed.lens.params[i], 1e-9 * std::abs(closed.lens.params[i]) + 1e-22);
}

TEST(ModelConversionFit, OrbigonDistortionFormAgainstBrown) {
  // Seed 001's model (kDistortion, about a point of symmetry) has no exact
  // Brown counterpart: the fit compares ideal coordinates and reports its residual.
  const DefinitionRegistry registry;  // Camera() returns a reference into it
  const CameraDefinition& orbigon = registry.Camera("orbigon");
  const LensEstimate lens = LensEstimateFromCalibration(*orbigon.lens, "orbigon");
  ConversionOptions options;
  options.format_width_mm = orbigon.format_width_mm;
  options.format_height_mm = orbigon.format_height_mm;
  const FieldFit fit =
      FitDistortionField(DistortionModelId::kSlama, lens.params, DistortionModelId::kBrownAffine, {}, options);
  EXPECT_TRUE(fit.converged) << fit.summary;
  EXPECT_GT(fit.rms_residual_mm, 0.0);
  EXPECT_LT(fit.rms_residual_mm, 0.01) << fit.summary;  // the fields are tens of um; the fit far better
  EXPECT_GE(fit.max_residual_mm, fit.rms_residual_mm);
  // The Orbigon has no common form for ConvertLens.
  EXPECT_THROW(ConvertLens(lens, DistortionModelId::kBrownConrady, options), Error);
}

TEST(ModelConversionOptions, Checks) {
  std::string why;
  ConversionOptions options;
  EXPECT_FALSE(options.Check(&why));  // no format
  options = Format(55);
  EXPECT_TRUE(options.Check(&why)) << why;
  options.grid_points_per_side = 2;
  EXPECT_FALSE(options.Check(&why));
  options = Format(55);
  options.balance_radius_mm = -3;
  EXPECT_FALSE(options.Check(&why));
  EXPECT_THROW(ConvertLens(Sn004(), DistortionModelId::kBrownConrady, ConversionOptions{}), Error);
  EXPECT_THROW(FitDistortionField(DistortionModelId::kBrownConrady, {1.0}, DistortionModelId::kBrownConrady, {},
                                  Format(55)),
               Error);
}

}  // namespace
}  // namespace platemeter
