// The full-resolution fit of one passpoint candidate and its verdict
// (passpoint_internal.h): is it the mark we look for, and is it good enough.
#include <algorithm>
#include <cmath>

#include "passpoint_internal.h"

namespace platemeter::internal {

CandidateFit FitPasspointCandidate(const Image& image, const PasspointDetectorOptions& options, const PixelPoint& start) {
  CandidateFit c;
  c.start_px = start;
  MarkFitStart s;
  s.type = options.shape;
  s.centre_px = start;
  s.size_px = options.diameter_px;
  s.line_width_px = options.shape == MarkType::kRing ? options.line_width_px : 0.0;
  s.blur_sigma_px = options.blur_sigma_px;
  const PixelRect wanted = MarkFitWindow(s, options.fit);
  const PixelRect rect = image.Clip(wanted);
  c.clipped = rect.x0_px != wanted.x0_px || rect.y0_px != wanted.y0_px || rect.width_px != wanted.width_px ||
              rect.height_px != wanted.height_px;
  if (rect.width_px < 3 || rect.height_px < 3) {
    c.reason = "not_converged";
    return c;
  }
  c.fit = FitMark(image.ReadWindow(rect), s, options.fit);
  const MarkFitResult& f = c.fit;
  if (f.too_many_masked) {
    c.reason = "masked_pixels";  // the scan holds no values there
    return c;
  }
  if (!f.converged) {
    c.reason = "not_converged";
    return c;
  }
  // Shape checks first: a fit that fails one of them is some other thing (dust, a star, terrain).
  const bool dark = f.gain_dn < 0.0;
  // The fit keeps its centre within a quarter diameter (+1 px) of the start; ending at that box's edge means it slid off.
  const double box = 0.25 * options.diameter_px + 1.0;
  const double shift = std::hypot(f.centre_px.x_px - start.x_px, f.centre_px.y_px - start.y_px);
  double max_blur = options.max_blur_sigma_px;
  if (max_blur <= 0.0)
    max_blur = std::max(1.5, options.shape == MarkType::kRing ? options.line_width_px / 3.0 : options.diameter_px / 6.0);
  if (dark != options.dark) {
    c.reason = "polarity";
  } else if (shift > 0.98 * box) {
    c.reason = "off_start";
  } else if (std::abs(f.size_px / options.diameter_px - 1.0) > options.size_tolerance) {
    c.reason = "size";
  } else if (options.shape == MarkType::kRing &&
             std::abs(f.line_width_px - options.line_width_px) >
                 std::max(options.line_width_tolerance * options.line_width_px, 0.75)) {
    c.reason = "line_width";
  } else if (f.blur_sigma_px > max_blur) {
    c.reason = "blur";
  } else {
    // It is the mark; now how well it is measured.
    c.is_mark = true;
    const double snr = std::abs(f.gain_dn) / std::max(f.residual_sigma_dn, 1e-9);
    if (snr < options.min_contrast_snr) {
      c.reason = "low_contrast";
    } else if (f.outlier_fraction > options.fit.max_outlier_fraction) {
      c.reason = "defect";
    }
  }
  return c;
}

}  // namespace platemeter::internal
