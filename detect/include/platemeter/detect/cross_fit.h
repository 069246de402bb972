#pragma once
// Least-squares matching of a parametric cross model on a scan's own pixels.
//
// Model (pixel units): a cross of two bars of widths w_h (the bar along u) and
// w_v (along v), both of tip-to-tip length L, rotated by theta, blurred by an
// isotropic Gaussian of sigma s and averaged over each pixel's area, on a
// planar background:
//   I(x, y) = b0 + bx (x - xc) + by (y - yc) + g * C(u, v)
//   C = P(v; w_h) P(u; L) + P(u; w_v) P(v; L) - P(v; w_h) P(u; w_v)
//   u = cos(theta) dx + sin(theta) dy,  v = -sin(theta) dx + cos(theta) dy,  d = (x, y) - (x0, y0)
// where P(t; w) is the pixel-averaged blurred 1D bar profile (closed form with
// the integral of erf). A blurred rectangle is exactly the product of its two
// profiles, so C is the exact blurred cross. The pixel average is taken over a
// unit square aligned with the cross rather than with the pixel grid: for the
// small rotations of a scanner this changes only the symmetric kernel, so the
// centre stays unbiased (the cross and both kernels are point-symmetric).
// Parameters: x0, y0, theta, w_h, w_v, L, s, g, b0, bx, by. The gain g is
// negative for dark crosses.
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/pixel.h"

namespace platemeter {

struct CrossFitOptions {
  double margin_px = 3.0;          // px; pixels this far beyond the blurred arms are used for the background
  double min_blur_sigma_px = 0.15; // px; lower bound of the fitted blur (keeps the profile smooth)
  double outlier_threshold = 4.0;  // pixels with |residual| above this many sigma are dropped in the final fit
  double min_outlier_contrast = 0.05;  // a pixel is never an outlier if it deviates by less than this share of the contrast
  // Around every dropped pixel, pixels within this many blur sigmas of the cross
  // (rounded to whole pixels) are dropped too: a foreign image's blurred edge.
  double foreign_margin_blurs = 3.0;
  // The pixels kept must hold at least this share of the centre's information
  // (1 / variance, the worse axis) that the whole region would: below it too
  // little of the cross is left, and the caller rejects it as a defect.
  double min_information_kept = 0.2;
  // Foreign pixels (star images, a trail's dots, dust specks) are fitted with the
  // cross as pixel-integrated Gaussian images, one started at each peak of the
  // outliers' residuals at least min_foreign_image_separation_px apart, at most
  // max_foreign_images, instead of being dropped: a star image on an arm then
  // costs only the information its own parameters take. What the joint model
  // still misses (scratches, saturated cores) is dropped as above.
  int max_foreign_images = 20;
  double min_foreign_image_separation_px = 3.0;
  // Masked pixels (image.h) are left out of the fit; they cost precision (the
  // sigma is the used pixels') but bias nothing. Beyond this share of the fit
  // region the cross's shape is not held by its own pixels: not fitted.
  double max_masked_fraction = 0.25;
  int max_iterations = 50;         // per solve
  bool Check(std::string* why) const;
};

struct CrossFitStart {
  PixelPoint centre_px;        // approximate centre (within about a line width)
  double rotation_rad = 0.0;   // approximate rotation of the arms against the pixel axes (mod 90 deg)
  double line_width_px = 4.0;  // nominal line width
  double arm_length_px = 100.0;  // nominal tip-to-tip length
  double blur_sigma_px = 0.7;  // starting blur
  // The widths (both line_width_px), length and blur are known (e.g. the plate's
  // own crosses' shape) and held: only the place, rotation, contrast and
  // background are fitted. For faint crosses, whose pixels cannot pin the shape.
  bool shape_known = false;
  // +1: a bright cross, -1: a dark one, 0: unknown (taken from the pixels). A
  // known polarity keeps the gain's sign, and pixels beyond the background on the
  // other side (star images on a plate whose crosses are the other way) are left
  // out of the first fit.
  int polarity = 0;
  // The scan's full scale (ImageInfo::full_scale_dn), 0 if unknown. With the
  // polarity known, pixels a foreign image drove to the clip level on the side
  // away from the cross (0, or full scale) are never fitted.
  double full_scale_dn = 0.0;
};

struct CrossFitResult {
  bool converged = false;
  PixelPoint centre_px;
  double sigma_x_px = 0.0;       // formal, scaled by the fit's own residual sigma
  double sigma_y_px = 0.0;
  double correlation_xy = 0.0;
  double rotation_rad = 0.0;
  double width_h_px = 0.0;
  double width_v_px = 0.0;
  double arm_length_px = 0.0;
  double blur_sigma_px = 0.0;
  double gain_dn = 0.0;          // cross contrast (negative: dark cross)
  double background_dn = 0.0;
  double residual_sigma_dn = 0.0;   // RMS residual of the final fit (its sigma0)
  // Formal sigma of gain_dn with the place and shape held at the fit and the plane
  // background free (scaled by sigma0): |gain_dn| / gain_sigma_dn is the cross's
  // matched-filter SNR, the noise limit of telling it from background.
  double gain_sigma_dn = 0.0;
  double outlier_fraction = 0.0;    // share of pixels dropped as foreign (outliers and their margins)
  double information_kept = 1.0;    // share of the centre's information in the pixels kept (see min_information_kept)
  int foreign_images = 0;           // foreign images fitted with the cross (see max_foreign_images)
  int missing_pieces = 0;           // missing arm pieces fitted (a damaged cross: the line gone over a stretch)
  int pixels_used = 0;
  int pixels_masked = 0;            // masked pixels in the fit region, left out
  double masked_fraction = 0.0;     // their share of the fit region
  bool too_many_masked = false;     // masked_fraction > max_masked_fraction: not fitted
  std::string summary;              // one sentence: what happened
};

// The window must hold the whole cross plus the margin (see CrossFitWindow).
CrossFitResult FitCross(const ImageWindow& window, const CrossFitStart& start, const CrossFitOptions& options = {});

// The window FitCross needs around a start position (not clipped to the image).
PixelRect CrossFitWindow(const CrossFitStart& start, const CrossFitOptions& options = {});

}  // namespace platemeter
