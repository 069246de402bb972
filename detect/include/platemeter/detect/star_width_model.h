#pragma once
// The plate's star-image width as a smooth function of the place: PSFEx's idea (a point-spread model
// that varies over the field, estimated from the plate's own bright isolated stars) for the circular
// Gaussian the star detector fits. A wide-angle lens's images grow toward the corners, focus and tilt
// vary; a fixed width would call the wide images defects. The star detector fits every image's width,
// fits this model to the bright isolated ones, and calls an image a defect (`shape`) by its width
// against the model at its place (star_detector.h: min_fwhm_ratio, max_fwhm_ratio).
#include <vector>

namespace platemeter {

struct DetectedStar;

inline constexpr double kFwhmPerSigma = 2.3548200450309493;  // a Gaussian's FWHM per sigma

struct StarWidthModel {
  // 2: sigma quadratic in (u, v); 1: linear; 0: constant (the stars' median); -1: no model (fewer than
  // 3 bright isolated stars): the starting value (psf_fwhm_px) everywhere.
  int degree = -1;
  // sigma_px = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2, u = (x - centre_x) / half_width (likewise v):
  // -1..1 over the scan.
  std::vector<double> coefficients;
  double centre_x_px = 0, centre_y_px = 0, half_width_px = 1, half_height_px = 1;
  // The model is held within the widths of the stars it was fitted to (a quadratic must not run away
  // in an empty corner).
  double min_sigma_px = 0, max_sigma_px = 0;
  long stars_used = 0;      // bright isolated stars left after the clipping
  double scatter_px = 0;    // robust RMS of their widths about the model (1.4826 MAD), sigma px
  double profile_misfit = 0;  // their median DetectedStar::profile_misfit: how far a star is from a Gaussian
  double SigmaAt(double x_px, double y_px) const;
};

// The stars the model is fitted to: measured single point images (no segment, no neighbour fitted
// with them, not saturated, truncated, elongated or crowded) with flux SNR >= kWidthModelMinSnr and a
// width within kWidthModelSpread of the reference model's at their place, either way. The reference
// is the previous model (the starting value at first): refitted, the model follows widths that change
// over the plate step by step, while a plate of dust and no stars cannot make the dust its model.
inline constexpr double kWidthModelMinSnr = 50.0;  // width fitted to ~2 % (sigma_w / w ~ 1 / SNR)
inline constexpr double kWidthModelSpread = 1.5;

// No model yet: the starting value everywhere on a width_px x height_px scan.
StarWidthModel StartWidthModel(long width_px, long height_px, double start_sigma_px);

// Fits the model (iteratively, dropping widths more than 3 robust sigmas from it); the degree grows
// with the stars available: 2 from 60 stars (10 per coefficient), 1 from 15, 0 from 3; fewer: the
// reference itself.
StarWidthModel FitStarWidthModel(const std::vector<DetectedStar>& stars, const StarWidthModel& reference);

// The model refitted until its stars no longer change (at most `rounds` times), from `reference`.
StarWidthModel SettleStarWidthModel(const std::vector<DetectedStar>& stars, StarWidthModel reference, int rounds = 4);

}  // namespace platemeter
