#pragma once
// The diurnal motion of star images over a whole plate (docs/trails.md, "The plate's flow").
//
// A star camera is fixed to the ground while the sky turns about the pole: the
// direction of every star rotates at the sidereal rate, and refraction and the
// lens map a direction to the plate the same way at every instant. So the image
// of every star moves with one autonomous flow, dp/dt = V(p), a smooth field over
// the format (for a distortion-free lens without refraction, a rotation is a
// homography and V a quadratic polynomial exactly). Two stars passing one point
// of the plate move alike; a star's image at one time gives its image at any
// other. SkyFlow fits V as 2D polynomials to decoded tracks' velocities and
// carries points along it (Runge-Kutta 4).
#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "platemeter/core/pixel.h"

namespace platemeter {

class SkyFlow {
 public:
  // Least-squares fit of Vx and Vy (px/s) as polynomials of total degree `degree` in the plate
  // coordinates, robust: samples beyond 5 robust sigmas are dropped, repeatedly. false when the
  // samples cannot determine the polynomials (too few, or not spread over the plate).
  bool Fit(const std::vector<PixelPoint>& p, const std::vector<PixelPoint>& velocity_px_per_s, int degree);
  bool ok() const { return ok_; }
  PixelPoint Velocity(const PixelPoint& p) const;
  // Where an image at p now is dt_s later (negative: earlier), integrated in steps of at most step_s.
  PixelPoint Carry(const PixelPoint& p, double dt_s, double step_s = 10.0) const;
  // The fit's robust residual spread (px/s, per axis) and the samples kept.
  double residual_px_per_s() const { return residual_px_per_s_; }
  int samples_used() const { return samples_used_; }

 private:
  Eigen::VectorXd Basis(const PixelPoint& p) const;
  int degree_ = 0;
  PixelPoint centre_;
  double scale_px_ = 1.0;
  Eigen::VectorXd ax_, ay_;
  bool ok_ = false;
  double residual_px_per_s_ = 0.0;
  int samples_used_ = 0;
};

// The path of one image through the flow: its position at any time offset within [-span_s, span_s]
// of the moment it was at p, sampled every step_s and interpolated (cubic Hermite with the flow's
// velocities: an image moves ~10-30 px in 30 s on a field that bends over thousands of pixels, so the
// interpolation errs far below 0.001 px; tests/detect/sky_flow_test.cpp compares 10 s and 30 s steps).
// `inside` (optional) ends the path where it leaves the area of interest (a scan): Covers() tells.
class FlowPath {
 public:
  FlowPath(const SkyFlow& flow, const PixelPoint& p, double span_s, double step_s = 30.0,
           const std::function<bool(const PixelPoint&)>& inside = {});
  PixelPoint At(double dt_s) const;
  PixelPoint VelocityAt(double dt_s) const;
  bool Covers(double dt_s) const { return dt_s >= from_s_ && dt_s <= to_s_; }

 private:
  size_t Interval(double dt_s, double* fraction) const;  // the sample interval holding dt_s, and where in it
  double span_s_, step_s_, from_s_ = 0.0, to_s_ = 0.0;
  std::vector<PixelPoint> p_, v_;  // at -span_s + k step_s
};

}  // namespace platemeter
