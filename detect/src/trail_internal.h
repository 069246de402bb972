#pragma once
// Internals of the trail linker shared by its source files (not installed).
#include <Eigen/Dense>
#include <vector>

#include "platemeter/core/pixel.h"

namespace platemeter::trail_internal {

// A star's track on the plate: x and y polynomials in the mid-exposure time,
// fitted by weighted least squares (trail_fit.cpp).
class Track {
 public:
  // Fits points (t_s, x, y) with per-point sigmas (px; empty: unit weights) with polynomials of
  // `degree` (lowered to what the points support: at least degree + 2 points). false if singular.
  bool Fit(const std::vector<double>& t_s, const std::vector<PixelPoint>& p, const std::vector<double>& sigma_x_px,
           const std::vector<double>& sigma_y_px, int degree);
  PixelPoint At(double t_s) const;
  PixelPoint VelocityAt(double t_s) const;  // px/s
  // Formal sigmas of At(t_s): from the fit's covariance, scaled by its reduced chi^2 when above 1.
  void SigmaAt(double t_s, double* sigma_x_px, double* sigma_y_px) const;
  // Leverage (hat-matrix diagonal, 0..1) of a point at t_s with these sigmas, per coordinate: how much
  // the fit follows it. A residual r has the sigma sigma sqrt(1 - h).
  void LeverageAt(double t_s, double sigma_x_px, double sigma_y_px, double* h_x, double* h_y) const;
  int degree() const { return degree_; }
  double reduced_chi2() const { return reduced_chi2_; }

 private:
  Eigen::VectorXd Basis(double t_s) const;
  double t0_s_ = 0.0, scale_s_ = 1.0;
  int degree_ = 0;
  Eigen::VectorXd ax_, ay_;
  Eigen::MatrixXd cov_x_, cov_y_;  // (A^T W A)^-1 per coordinate
  double reduced_chi2_ = 1.0;
};

}  // namespace platemeter::trail_internal
