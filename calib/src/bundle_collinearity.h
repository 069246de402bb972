#pragma once
// Seed 000 eq. (1) with its Jacobians written out (bundle_equations.h
// CollinearityEquation is the same residual differentiated automatically):
// the bundle's one observation equation, evaluated 400 000 times per
// iteration on a large block, where Jet<19> arithmetic cost four times what
// the closed form does; each thread also keeps every frame's rotation matrix
// and its derivatives between observations (bundle_collinearity.cpp
// RotationOf). The residual's value is computed by the same code in the same
// order as the automatic form, so the two agree to the last bit;
// tests/calib/bundle_collinearity_test.cpp holds the Jacobians to the
// automatic ones.
// Blocks: camera (c_mm, xp_mm, yp_mm, then BrownAffine's k1_per_mm2,
// k2_per_mm4, k3_per_mm6, p1_per_mm, p2_per_mm, b1, b2), frame (X_m, Y_m,
// Z_m, phi_rad, omega_rad, kappa_rad: seed 000's T matrix), point (X_m, Y_m,
// Z_m). Residual: mm in the measured plane.
#include <ceres/sized_cost_function.h>

namespace platemeter::bundle_internal {

class CollinearityCost final : public ceres::SizedCostFunction<2, 10, 6, 3> {
 public:
  // frame_slot: the frame's index in the bundle (0, 1, ...), where each thread
  // keeps the frame's rotation matrix between evaluations (only a hint: the
  // matrix is reused only for the same angles).
  CollinearityCost(double x_mm, double y_mm, int frame_slot) : x_mm_(x_mm), y_mm_(y_mm), frame_slot_(frame_slot) {}
  bool Evaluate(double const* const* parameters, double* residuals_mm, double** jacobians) const override;

 private:
  double x_mm_;  // the measured point, plate mm
  double y_mm_;
  int frame_slot_;
};

}  // namespace platemeter::bundle_internal
