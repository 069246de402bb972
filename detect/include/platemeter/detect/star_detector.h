#pragma once
// Point-image (star) detection over a whole scan in bands of rows with bounded
// memory, as SExtractor does it but with a PSF fit at the end:
//   1. background and noise on a mesh of cells (sigma-clipped mode per cell,
//      3x3 median of the mesh, bilinear interpolation);
//   2. a matched filter (Gaussian of the PSF's sigma) and a threshold in units
//      of the filtered noise;
//   3. connected components (8-connected) with shape tests (line-like,
//      cross-like and oversized components are defects, not stars);
//   4. per component a least-squares fit of pixel-integrated circular Gaussians
//      (position, flux, width per star, one background); a second star is added
//      when it lowers chi^2 significantly (close pairs, fitted jointly);
//      saturated pixels are left out, so saturated stars are fitted from
//      their wings.
// In trail mode (max_dash_length_px > 0) elongated components are split at
// the gaps between dashes and fitted as PSFs swept along segments instead.
// Formal sigmas are the position block of (J^T J)^-1 scaled by the fit's own
// residual variance. Algorithm details in docs/stars.md.
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/pixel.h"
#include "platemeter/detect/point.h"
#include "platemeter/detect/star_width_model.h"

namespace platemeter {

// Bit flags of a detected star.
enum StarFlag : unsigned {
  kStarSaturated = 1u << 0,   // pixels at the clip levels were left out of the fit
  kStarBlended = 1u << 1,     // fitted jointly with a neighbour
  kStarTruncated = 1u << 2,   // fit window cut by the image edge
  kStarElongated = 1u << 3,   // ellipticity above the limit (dash, trail, double)
  kStarDefect = 1u << 4,      // shape far from the PSF, line- or cross-like, or masked: not a star
  kStarCrowded = 1u << 5,     // trail mode: cut from a clump of images too long or too wide for one
                              // trail image (crossing trails); parts of one image may be measured apart
};
// "saturated,blended,..." (empty for none).
std::string StarFlagNames(unsigned flags);

// Known non-star marks the detector masks (reseau crosses). A component peaking within radius_px of a
// point is a defect; with arms (arm_reach_px > 0) the points are crosses with arms along the two unit
// vectors arm_axes_px (the grid's x and y axes in the scan), and only a peak within arm_reach_px of an arm
// line is masked, while no star's fit takes pixels within arm_half_width_px of them: star images between
// the arms are measured (whole V <= 8 Orbigon plate: +136 trail dots right). What the mask covers the
// detector cannot see: the trail decoder holds no place there empty (TrailOptions::blind).
struct StarMask {
  std::vector<PixelPoint> points_px;
  double radius_px = 10.0;                          // px
  PixelPoint arm_axes_px[2] = {{1.0, 0.0}, {0.0, 1.0}};
  double arm_reach_px = 0.0;                        // px; 0: the whole disk is masked
  double arm_half_width_px = 0.0;                   // px; half the arm's line plus its blur
  // Distance from p to the nearer arm line of the cross at m.
  double ArmDistance_px(const PixelPoint& m, const PixelPoint& p) const;
  // Whether an image at p reaching extent_px around it touches what the mask hides (a peak there is masked).
  bool Covers(const PixelPoint& p, double extent_px) const;
  bool Check(std::string* why) const;
};

struct StarDetectorOptions {
  bool dark = true;                       // stars darker than the background (negative plate)
  // px; a point image's FWHM to start from (matched filter, start of the fits). Not a limit: every image's
  // width is fitted, and the shape test compares it with the plate's width model (star_width_model.h).
  double psf_fwhm_px = 2.5;
  int mesh_px = 64;                       // px; side of a background mesh cell
  double clip_sigma = 3.0;                // sigma-clipping limit of the mesh statistics
  double threshold_sigma = 4.0;           // detection threshold in sigma of the matched-filtered noise
  int min_pixels = 2;                     // px; smallest component kept
  int band_rows = 512;                    // px; rows processed at once (memory ~ 20 bytes x width x (band + 2 mesh))
  std::optional<double> saturation_dn;    // DN; pixels at or above are clipped (default: the file's full scale)
  double floor_dn = 0.0;                  // DN; pixels at or below are clipped (dark stars on a negative)
  // Masked pixels (core/image.h: no value in the scan) are background to the matched filter and left out
  // of the fits; an image whose fit window has more than this share of them is rejected (masked_pixels).
  double max_masked_fraction = 0.25;
  // Fitted FWHM / the width model's at the image's place (trail mode: / psf_fwhm_px) above this: defect
  // (dust, blob); below min_fwhm_ratio: defect (hot pixel, grain).
  double max_fwhm_ratio = 1.8;
  double min_fwhm_ratio = 0.4;
  double max_ellipticity = 0.3;           // 1 - b/a above this: elongated
  double max_component_fwhm = 12.0;       // component bounding box longer than this many PSF FWHM: defect (line, cross)
  double pair_chi2_gain = 30.0;           // chi^2 decrease needed to accept a second star in a component
  double min_snr = 5.0;                   // flux / sigma(flux) below this: dropped
  bool windowed_centroid = false;         // true: SExtractor's windowed centroid (XWIN, Gaussian window of the PSF's
                                          // sigma) for unblended stars instead of the PSF fit's position
  // Trail mode (duty-cycle plates): > 0 enables it. Segment images up to this long (px; the longest
  // dash: 20 s x the sidereal rate in px/s at the plate's fastest star) are measured, not rejected:
  // a component whose second moments show a sweep longer than the PSF's FWHM is fitted with a PSF
  // swept along a straight segment (centre = mid-exposure position, length, angle) and flagged
  // elongated when its ellipticity exceeds max_ellipticity. Components too long for one dash are
  // first split at the gaps between dashes (raising the level inside the component). Defects stay
  // defects: fitted length above (1 + dash_length_tolerance) x max_dash_length_px + psf_fwhm_px
  // (scratches, lines), width above max_dash_width_ratio x the PSF (dust, wide scratches), crosses.
  // 0: off (every elongated component is judged as a star, as without trails).
  double max_dash_length_px = 0.0;        // px
  double dash_length_tolerance = 0.3;     // fraction of max_dash_length_px a segment may exceed it by
  double max_dash_width_ratio = 1.5;      // fitted segment PSF FWHM / psf_fwhm_px above this: defect
  StarMask mask;                          // known non-star marks (reseau crosses)
  bool Check(std::string* why) const;
};

struct DetectedStar {
  DetectedPoint point;          // kind star; measured, or rejected (flag defect) with reason line, cross, masked, masked_pixels or shape
  double flux_dn = 0.0;         // DN px^2; total flux of the fitted Gaussian (positive contrast)
  double sigma_flux_dn = 0.0;   // DN px^2; formal
  double peak_dn = 0.0;         // DN; fitted peak contrast
  double background_dn = 0.0;   // DN; local background (mesh + fitted offset)
  double fwhm_px = 0.0;         // px; fitted FWHM
  double ellipticity = 0.0;     // 1 - b/a from Gaussian-weighted second moments
  // The profile's departure from the fitted Gaussian, unblended point images: excess residual RMS x
  // sigma / flux (0: within the noise); a dust disk gives ~0.05, a Gaussian star 0.
  double profile_misfit = 0.0;
  double snr = 0.0;             // flux / sigma_flux
  double length_px = 0.0;       // px; trail mode: fitted sweep length of a segment image (0: fitted as a point)
  double sigma_length_px = 0.0; // px; formal sigma of length_px
  double angle_deg = 0.0;       // deg; trail mode: direction of the segment from +x toward +y (row), -90..90
  unsigned flags = 0;           // StarFlag bits
  // Trail mode, rejected lines: the box holding the line's pixels (a trail linker asks what it may hide;
  // a line along the format's edge is hundreds of px long but a few wide). Empty (min > max) otherwise.
  PixelPoint box_min_px{0.0, 0.0}, box_max_px{-1.0, -1.0};
};

struct StarDetectionStats {
  double noise_sigma_dn = 0.0;  // median per-cell background sigma (the image's sigma)
  long components = 0;          // connected components above the threshold
  long defects = 0;             // components or fits rejected as defects
  // Point mode: components whose filtered peak lies below the level pure noise reaches once in ten
  // scans of this size (in filtered noise sigmas; 0 in trail mode): dropped before any fit, no row.
  long noise_peaks = 0;
  double noise_peak_level_sigma = 0.0;
  StarWidthModel width_model;   // the plate's star widths (not fitted in trail mode: degree -1)
  long bands = 0;
};

// Detects and measures the point images of a whole scan. Throws Error for
// invalid options.
std::vector<DetectedStar> DetectStars(const Image& image, const StarDetectorOptions& options = {},
                                      StarDetectionStats* stats = nullptr);

// The same on rows already in memory (row-major, width x height DN values):
// for tests and for callers that hold a window.
std::vector<DetectedStar> DetectStarsInBuffer(const float* values_dn, long width_px, long height_px,
                                              double full_scale_dn, const StarDetectorOptions& options = {},
                                              StarDetectionStats* stats = nullptr);

}  // namespace platemeter
