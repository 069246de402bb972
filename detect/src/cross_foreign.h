#pragma once
// The pixels of a cross fit that do not belong to the model (dust, scratches,
// damage, star images): found from the fit's residuals, grown by a margin, and
// their peaks made the starts of foreign images to fit with the cross
// (cross_model.h).
#include <vector>

#include "cross_model.h"
#include "platemeter/core/pixel.h"

namespace platemeter::internal {

// The samples whose |residual| from the model lies beyond max(threshold x the
// robust sigma of the samples not yet dropped, min_contrast x |gain|).
std::vector<char> FlagOutliers(const std::vector<CrossSample>& samples, const std::vector<char>& dropped,
                               const std::vector<double>& p, const SceneLayout& layout, double xc, double yc, double threshold,
                               double min_contrast);

// The samples that no cross of the given polarity (+1 bright, -1 dark) on a flat
// background could explain: beyond the background (the samples' median) by more
// than threshold x the noise (their scaled MAD) on the side away from the cross.
// Star images of the other polarity, whatever their contrast.
std::vector<char> FlagOppositeSide(const std::vector<CrossSample>& samples, int polarity, double threshold);

// The flagged samples grown by margin_px (a square) on the window's pixel grid.
std::vector<char> GrowFlags(const std::vector<CrossSample>& samples, const std::vector<char>& flags,
                            const PixelRect& rect, long margin_px);

std::vector<CrossSample> Kept(const std::vector<CrossSample>& samples, const std::vector<char>& dropped);

// A foreign image's start: centre, flux (signed DN) and Gaussian sigma (both
// axes; the fit frees its covariance).
struct ForeignImageStart {
  double x_px, y_px, flux_dn, sigma_px;
};

// Starts of foreign images at the flagged samples' peaks of |value - model|, the
// largest first, none within min_separation_px (either axis) of another, at most
// max_images; the residuals are the samples' model - value.
std::vector<ForeignImageStart> ForeignImageStarts(const std::vector<CrossSample>& samples,
                                                  const std::vector<char>& flags, const std::vector<double>& residuals,
                                                  double min_separation_px, int max_images);

// A missing piece's start: its arm (SceneLayout::gap_arms) and its middle and length (px).
struct MissingPieceStart {
  int arm;
  double middle_px, length_px;
};

// Where an arm of the fitted cross p shows the background instead of the line: along each arm, in
// 1 px steps from the other arm's edge to the tip, the share of the cross's signal its core pixels
// hold (least squares of value - background on model - background); the longest run of steps
// whose share lies within +-1/2 of zero (the line gone, nothing else there: a star on the arm goes
// beyond the background), at least min_length_px long, starts a missing piece. The clipped
// samples are not looked at.
std::vector<MissingPieceStart> MissingPieceStarts(const std::vector<CrossSample>& samples,
                                                  const std::vector<char>& clipped, const std::vector<double>& p,
                                                  double xc, double yc, double min_length_px);

}  // namespace platemeter::internal
