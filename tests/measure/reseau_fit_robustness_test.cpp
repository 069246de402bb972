// Issue #28: the reseau fit never crashes on what reaches it. Values no reader lets
// through today (non-finite, 1e200 mm) still end as a one-line Error or as a rejected
// cross, and the emulsion geometry stays finite for any principal distance.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/measure/emulsion_depth.h"
#include "platemeter/measure/reseau_fit.h"

namespace platemeter {
namespace {

// A 5 x 5 grid, 10 mm apart, measured without error (1 um sigmas).
std::vector<ReseauObservation> Grid() {
  std::vector<ReseauObservation> obs;
  for (int row = 0; row < 5; ++row) {
    for (int col = 0; col < 5; ++col) {
      ReseauObservation o;
      o.id = "X" + std::to_string(col + 1) + "Y" + std::to_string(row + 1);
      o.grid_x_mm = 10.0 * (col - 2);
      o.grid_y_mm = 10.0 * (row - 2);
      o.measured = {o.grid_x_mm * 1.0001 + 0.3, o.grid_y_mm * 0.9999 - 0.2, {1e-6, 0.0, 1e-6}};
      obs.push_back(o);
    }
  }
  return obs;
}

TEST(ReseauFitRobustness, ANonFiniteCrossIsAnErrorNamingIt) {
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    std::vector<ReseauObservation> obs = Grid();
    obs[7].measured.x = bad;
    try {
      FitReseau(obs, {});
      FAIL() << "a non-finite cross was fitted";
    } catch (const Error& e) {
      EXPECT_EQ(e.reason(), "cross X3Y2 has a non-finite position or covariance");
    }
  }
}

TEST(ReseauFitRobustness, AWildButFiniteCrossIsRejectedOrRefusedNeverACrash) {
  for (double wild_mm : {1e6, 1e100, 1e200, 1e300}) {
    SCOPED_TRACE(wild_mm);
    std::vector<ReseauObservation> obs = Grid();
    obs[12].measured.x = wild_mm;
    try {
      const ReseauFit fit = FitReseau(obs, {});
      // Fitted: the wild cross is rejected and the others fit the true transformation.
      EXPECT_TRUE(fit.is_rejected[12]);
      EXPECT_EQ(fit.used, 24);
      EXPECT_NEAR(fit.scale_x.value, 1.0001, 1e-9);
      EXPECT_LT(fit.rms_mm, 1e-9);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("reseau fit"), std::string::npos) << e.what();
    }
  }
}

TEST(ReseauFitRobustness, EmulsionGeometryStaysFiniteForAnyPrincipalDistance) {
  for (double c_mm : {50.0, 1e6, 1e200}) {
    EmulsionDepthModel model;
    model.depth_um = 10.0;
    model.refractive_index = 1.65;
    model.principal_distance_mm = c_mm;
    const double r = model.TrueRadiusMm(40.0);
    EXPECT_TRUE(std::isfinite(r)) << c_mm;
    // r + shift(r) = 40 mm, shift(r) = d sin(theta) / sqrt(n^2 - sin^2(theta)), tan(theta) = r / c (0 for a
    // distant camera).
    const double theta = std::atan(r / c_mm);
    const double expected_shift_mm = 10e-3 * std::sin(theta) / std::sqrt(1.65 * 1.65 - std::sin(theta) * std::sin(theta));
    EXPECT_NEAR(40.0 - r, expected_shift_mm, 1e-9) << c_mm;
  }
}

}  // namespace
}  // namespace platemeter
