// Conformance of every distortion model (DESIGN.md "every model runs through the
// same conformance tests"): identity at zero parameters, round trip
// measured -> ideal -> measured, and automatic-differentiation derivatives
// (ceres::Jet) against central finite differences, for Apply and for the
// iterated inverse.
#include <array>
#include <cmath>
#include <vector>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "platemeter/calib/distortion_models.h"

namespace platemeter {
namespace {

// Realistic parameters per model (from the seeds) and the half-size of the
// format over which the model is exercised.
template <typename Model>
struct ModelCase;

template <>
struct ModelCase<SmacRadialDecentering> {
  // Seed 004, Table A.4 (terrain lens No. 203).
  static std::vector<double> Params() {
    return {-0.1278842e-05, +0.5264148e-09, -0.5259516e-13, +0.3821279e-06, +0.1168324e-19, 3.371325};
  }
  static constexpr double kHalfFormat_mm = 57.0;
};

template <>
struct ModelCase<BrownConrady> {
  // Seed 000-like Gaussian coefficients, with k2, k3 and p2 non-zero so that every
  // term is exercised.
  static std::vector<double> Params() { return {1.5614e-5, -2.0e-10, 3.0e-14, 3.604e-6, -2.998e-6}; }
  static constexpr double kHalfFormat_mm = 27.5;
};

template <>
struct ModelCase<BrownAffine> {
  // Brown's terms as above plus a 1e-4 scale difference and a 2e-4 shear.
  static std::vector<double> Params() {
    return {1.5614e-5, -2.0e-10, 3.0e-14, 3.604e-6, -2.998e-6, -1.0e-4, 2.0e-4};
  }
  static constexpr double kHalfFormat_mm = 27.5;
};

template <>
struct ModelCase<BrownBalanced> {
  // Seed 000, Table 6 (stellar SMAC, balanced at r = 30 mm).
  static std::vector<double> Params() { return {-0.14741e-1, +0.17241e-4, -0.95765e-9, 0.3858e-5, 0.1241e-5}; }
  static constexpr double kHalfFormat_mm = 27.5;
};

template <>
struct ModelCase<SlamaDistortion> {
  // Seed 001, Table 3 combined: xs, ys relative to the principal point (mm).
  static std::vector<double> Params() {
    return {1.0636 + 0.0205, -1.1637 + 0.00004, 3.6494e-1, -1.1011e+2, 9.5244e+3, 7.8152e-4, 5.0665e-2,
            -271.2 * M_PI / 180.0};
  }
  static constexpr double kHalfFormat_mm = 57.0;
};

template <typename Model>
class DistortionModelConformance : public ::testing::Test {
 protected:
  static std::vector<std::array<double, 2>> Points() {
    // A 9 x 9 grid over the format, the origin included, plus off-grid points.
    std::vector<std::array<double, 2>> points;
    const double h = ModelCase<Model>::kHalfFormat_mm;
    for (int i = -4; i <= 4; ++i) {
      for (int j = -4; j <= 4; ++j) points.push_back({h * i / 4.0, h * j / 4.0});
    }
    points.push_back({0.37 * h, -0.81 * h});
    points.push_back({-0.93 * h, 0.11 * h});
    return points;
  }
};

using Models =
    ::testing::Types<SmacRadialDecentering, BrownConrady, BrownAffine, BrownBalanced, SlamaDistortion>;
TYPED_TEST_SUITE(DistortionModelConformance, Models);

TYPED_TEST(DistortionModelConformance, DeclaresItsParameters) {
  using Model = TypeParam;
  EXPECT_EQ(static_cast<int>(Model::kParamNames.size()), Model::kNumParams);
  EXPECT_EQ(static_cast<int>(ModelCase<Model>::Params().size()), Model::kNumParams);
  DistortionModelId id;
  ASSERT_TRUE(ParseDistortionModel(Model::Name(), &id)) << Model::Name();
  EXPECT_EQ(DistortionModelNumParams(id), Model::kNumParams);
}

TYPED_TEST(DistortionModelConformance, ZeroParametersGiveZeroCorrection) {
  using Model = TypeParam;
  const std::vector<double> zero(Model::kNumParams, 0.0);
  for (const auto& p : this->Points()) {
    double dx = 1.0, dy = 1.0;
    Model::Apply(zero.data(), p[0], p[1], &dx, &dy);
    EXPECT_EQ(dx, 0.0) << p[0] << ", " << p[1];
    EXPECT_EQ(dy, 0.0) << p[0] << ", " << p[1];
    double ix = 0.0, iy = 0.0;
    ASSERT_TRUE(IdealFromMeasured<Model>(zero.data(), p[0], p[1], &ix, &iy));
    EXPECT_EQ(ix, p[0]);
    EXPECT_EQ(iy, p[1]);
  }
}

TYPED_TEST(DistortionModelConformance, NonZeroParametersDistortAtTheFormatEdge) {
  // Guards the round trip below against a model that silently does nothing.
  using Model = TypeParam;
  const std::vector<double> params = ModelCase<Model>::Params();
  const double h = ModelCase<Model>::kHalfFormat_mm;
  double dx = 0.0, dy = 0.0;
  Model::Apply(params.data(), 0.9 * h, 0.7 * h, &dx, &dy);
  EXPECT_GT(std::hypot(dx, dy), 1e-4);  // more than 0.1 um
}

TYPED_TEST(DistortionModelConformance, RoundTripMeasuredIdealMeasured) {
  using Model = TypeParam;
  const std::vector<double> params = ModelCase<Model>::Params();
  for (const auto& p : this->Points()) {
    double ix = 0.0, iy = 0.0, mx = 0.0, my = 0.0;
    ASSERT_TRUE(IdealFromMeasured<Model>(params.data(), p[0], p[1], &ix, &iy));
    ASSERT_TRUE(MeasuredFromIdeal<Model>(params.data(), ix, iy, &mx, &my));
    EXPECT_NEAR(mx, p[0], 1e-10);
    EXPECT_NEAR(my, p[1], 1e-10);
    // And the other way round: an ideal point through measured and back.
    ASSERT_TRUE(MeasuredFromIdeal<Model>(params.data(), p[0], p[1], &mx, &my));
    ASSERT_TRUE(IdealFromMeasured<Model>(params.data(), mx, my, &ix, &iy));
    EXPECT_NEAR(ix, p[0], 1e-10);
    EXPECT_NEAR(iy, p[1], 1e-10);
  }
}

// Central finite difference of f(values) -> 2 outputs with respect to values[k].
template <typename F>
std::array<double, 2> CentralDifference(F f, std::vector<double> values, int k, double h) {
  std::vector<double> plus = values, minus = values;
  plus[k] += h;
  minus[k] -= h;
  const std::array<double, 2> fp = f(plus), fm = f(minus);
  return {(fp[0] - fm[0]) / (2 * h), (fp[1] - fm[1]) / (2 * h)};
}

// Checks the Jet derivatives of g (Apply or an inverse) with respect to all
// parameters and both coordinates at a few points.
template <typename Model, typename G>
void CheckDerivatives(G g, const char* what) {
  constexpr int N = Model::kNumParams + 2;
  using Jet = ceres::Jet<double, N>;
  const std::vector<double> params = ModelCase<Model>::Params();
  const double h = ModelCase<Model>::kHalfFormat_mm;
  for (const auto& point : {std::array<double, 2>{0.8 * h, -0.55 * h}, std::array<double, 2>{-0.3 * h, 0.9 * h},
                            std::array<double, 2>{0.05 * h, 0.02 * h}}) {
    std::array<Jet, Model::kNumParams> jp;
    for (int i = 0; i < Model::kNumParams; ++i) jp[i] = Jet(params[i], i);
    const Jet jx(point[0], Model::kNumParams), jy(point[1], Model::kNumParams + 1);
    Jet ox, oy;
    ASSERT_TRUE(g(jp.data(), jx, jy, &ox, &oy));

    std::vector<double> values = params;
    values.push_back(point[0]);
    values.push_back(point[1]);
    auto f = [&](const std::vector<double>& v) {
      double x = 0.0, y = 0.0;
      EXPECT_TRUE(g(v.data(), v[Model::kNumParams], v[Model::kNumParams + 1], &x, &y));
      return std::array<double, 2>{x, y};
    };
    const std::array<double, 2> value = f(values);
    EXPECT_NEAR(ox.a, value[0], 1e-13);
    EXPECT_NEAR(oy.a, value[1], 1e-13);
    const double magnitude = 1.0 + std::max(std::abs(value[0]), std::abs(value[1]));
    for (int k = 0; k < N; ++k) {
      // Step so that the outputs move by ~1e-7 mm: exact for the parameters the
      // models are linear in, small truncation error for angles and coordinates.
      const double largest = std::max(std::abs(ox.v[k]), std::abs(oy.v[k]));
      // Capped for small derivatives of non-linear parameters (angles, xs, ys).
      const double cap = 1e-4 * std::max(std::abs(values[k]), 1.0);
      const double step = largest > 0.0 ? std::min(1e-7 / largest, cap) : cap;
      const std::array<double, 2> fd = CentralDifference(f, values, k, step);
      for (int c = 0; c < 2; ++c) {
        const double ad = (c == 0 ? ox : oy).v[k];
        // 1e-6 relative, plus the rounding of f (~1e-16 |f|) divided by the step.
        const double tolerance = 1e-6 * std::abs(fd[c]) + 1e-7 * magnitude * largest + 1e-12;
        EXPECT_NEAR(ad, fd[c], tolerance)
            << what << ": d(out " << c << ")/d("
            << (k < Model::kNumParams ? Model::kParamNames[k] : (k == N - 2 ? "x" : "y")) << ") at ("
            << point[0] << ", " << point[1] << ")";
      }
    }
  }
}

TYPED_TEST(DistortionModelConformance, ApplyDerivativesMatchFiniteDifferences) {
  using Model = TypeParam;
  CheckDerivatives<Model>(
      [](const auto* p, const auto& x, const auto& y, auto* dx, auto* dy) {
        Model::Apply(p, x, y, dx, dy);
        return true;
      },
      "Apply");
}

TYPED_TEST(DistortionModelConformance, InverseDerivativesMatchFiniteDifferences) {
  using Model = TypeParam;
  CheckDerivatives<Model>(
      [](const auto* p, const auto& x, const auto& y, auto* ox, auto* oy) {
        return MeasuredFromIdeal<Model>(p, x, y, ox, oy);
      },
      "MeasuredFromIdeal");
  CheckDerivatives<Model>(
      [](const auto* p, const auto& x, const auto& y, auto* ox, auto* oy) {
        return IdealFromMeasured<Model>(p, x, y, ox, oy);
      },
      "IdealFromMeasured");
}

TEST(DistortionInverse, ReportsFailureInsteadOfAnAnswer) {
  // A radial correction so strong that x + dx(x) folds over (d/dx of the map is
  // zero at x = 1/sqrt(3 |k1|)): no measured point gives ideal x = 10 mm.
  const std::vector<double> params = {-0.1, 0.0, 0.0, 0.0, 0.0};
  double mx = 0.0, my = 0.0;
  EXPECT_FALSE(MeasuredFromIdeal<BrownConrady>(params.data(), 10.0, 0.0, &mx, &my));
}

TEST(DistortionInverseOptions, CheckRejectsBadValues) {
  std::string why;
  EXPECT_TRUE(DistortionInverseOptions{}.Check(&why));
  DistortionInverseOptions bad;
  bad.tolerance_mm = 0.0;
  EXPECT_FALSE(bad.Check(&why));
  EXPECT_NE(why.find("tolerance_mm"), std::string::npos);
  bad = {};
  bad.max_iterations = 0;
  EXPECT_FALSE(bad.Check(&why));
}

}  // namespace
}  // namespace platemeter
