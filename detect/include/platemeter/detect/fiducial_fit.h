#pragma once
// Least-squares matching of a parametric fiducial mark on a scan's own pixels,
// for every mark type of the definitions (grids/definitions.h MarkType):
//   I(x, y) = b0 + bx (x - xc) + by (y - yc) + g * S(x, y)
// (plus quadratic background terms for corners, whose long arms cross terrain)
// with S the unit-contrast mark, blurred by an isotropic Gaussian of sigma s
// and averaged over each pixel's area (pixel units throughout):
// - dot: a disk of diameter D. Its blurred radial profile has no closed form;
//   it is tabulated per parameter set by 1D quadrature of its closed-form
//   radial derivative (Bessel functions) and averaged over the pixel square
//   with a composite Gauss-Legendre rule (sub-cells no wider than 2.5 s).
//   Shape parameters: D, s.
// - ring: the disk of diameter D minus the concentric disk of diameter D - 2 w.
//   Shape parameters: D, w, s.
// - corner: an L of two straight arms of widths w1, w2 meeting at the corner
//   point (x0, y0), where the arms' centre lines cross; arm 1 runs along angle
//   theta, arm 2 along theta + 90 deg (handedness +1) or theta - 90 deg (-1) in
//   pixel axes; each arm reaches w/2 behind the corner point (the L's outer
//   corner) and length L ahead. Blurred bars are products of closed-form
//   pixel-averaged profiles (as in the cross fit, the pixel average is over a
//   square aligned with the arms). Only the part of each arm within
//   MarkFitOptions::max_corner_arm_px of the corner (and short of its far end)
//   is fitted, so an arm longer than the window, or of unknown length, does not
//   matter. Shape parameters: theta, w1, w2, s.
// - cross: FitCross (cross_fit.h) through the same call.
// The position's formal covariance is the Schur complement of the normal
// matrix on every other parameter, scaled by the fit's residual variance.
#include <string>

#include "platemeter/core/image.h"
#include "platemeter/core/pixel.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

struct MarkFitOptions {
  double margin_px = 3.0;              // px; background pixels this far beyond the blurred mark
  double min_blur_sigma_px = 0.15;     // px; lower bound of the fitted blur
  double outlier_threshold = 4.0;      // pixels with |residual| above this many sigma are dropped in the final fit
  double min_outlier_contrast = 0.05;  // a pixel is never an outlier below this share of the contrast
  double max_outlier_fraction = 0.08;  // share of dropped pixels above which the caller should call it a defect
  double max_masked_fraction = 0.25;   // share of masked pixels (image.h) above which the mark is not fitted
  double max_corner_arm_px = 200.0;    // px; corner arms are fitted this far from the corner point at most
  bool quadratic_corner_background = true;  // corner arms are long: a quadratic background follows terrain under them
  bool fit_corner_rotation = true;     // false: the corner's rotation is held at the start's (known from the layout)
  int max_iterations = 50;             // per solve
  bool Check(std::string* why) const;
};

struct MarkFitStart {
  MarkType type = MarkType::kDot;
  PixelPoint centre_px;        // approximate centre / corner point (within about a line width, or D/4 for dots)
  double line_width_px = 4.0;  // cross, ring and corner line width
  double size_px = 20.0;       // cross tip to tip; dot and ring outer diameter; corner arm length from the corner point
  double rotation_rad = 0.0;   // cross: arm rotation (mod 90 deg); corner: direction of arm 1, atan2(dy, dx) in pixels
  int corner_handedness = 1;   // corner: arm 2 = arm 1 turned by +90 deg (+1: (dx, dy) -> (-dy, dx)) or -90 deg (-1)
  double blur_sigma_px = 0.7;  // starting blur
};

struct MarkFitResult {
  bool converged = false;
  MarkType type = MarkType::kDot;
  PixelPoint centre_px;
  double sigma_x_px = 0.0;  // formal, scaled by the fit's own residual sigma
  double sigma_y_px = 0.0;
  double correlation_xy = 0.0;
  double size_px = 0.0;          // fitted diameter (dot, ring) or tip-to-tip length (cross); corner: the start's
  double line_width_px = 0.0;    // ring width; cross: horizontal bar; corner: arm 1
  double line_width_2_px = 0.0;  // cross: vertical bar; corner: arm 2
  double rotation_rad = 0.0;     // cross, corner
  double blur_sigma_px = 0.0;
  double gain_dn = 0.0;          // contrast (negative: dark mark)
  double background_dn = 0.0;
  double residual_sigma_dn = 0.0;
  double outlier_fraction = 0.0;
  int pixels_used = 0;
  int pixels_masked = 0;          // masked pixels in the fit region, left out
  double masked_fraction = 0.0;   // their share of the fit region
  bool too_many_masked = false;   // masked_fraction > max_masked_fraction: not fitted
  std::string summary;
};

// The window FitMark needs around a start (not clipped to the image).
PixelRect MarkFitWindow(const MarkFitStart& start, const MarkFitOptions& options = {});
// Fits the mark of start.type; pixels outside the window are simply not used.
MarkFitResult FitMark(const ImageWindow& window, const MarkFitStart& start, const MarkFitOptions& options = {});

}  // namespace platemeter
