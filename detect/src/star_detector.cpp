// Star detection driver: the bands of rows, the plate's width model, the shape tests against it, and
// the detector's public entry points (star_detector.h). A band's measurement: star_band.cpp.
#include "platemeter/detect/star_detector.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "platemeter/core/error.h"
#include "star_band.h"

namespace platemeter {
namespace {

using star_internal::Band;
using star_internal::PendingPair;

// Point mode fits the plate's width model (trail mode keeps the starting value: its dashes and dots
// are not what the model describes).
bool PointMode(const StarDetectorOptions& o) { return o.max_dash_length_px == 0; }

// The pair tests that waited for the width model (star_band.h), with the model of every band's stars:
// the first bands' would otherwise be made against the starting value, which on a plate whose widths
// differ from it by more than 12 % sends nearly every bright star to a pair test.
void DecidePendingPairs(const StarDetectorOptions& o, std::vector<PendingPair>* pending, StarWidthModel* model,
                        std::vector<DetectedStar>* stars, StarDetectionStats* stats) {
  if (pending->empty()) return;
  *model = SettleStarWidthModel(*stars, *model);
  star_internal::ResolvePendingPairs(o, *model, pending, stars, stats);
}

// The shape tests against the plate's own stars (point images only; trail mode keeps its start-value
// tests, whose dashes and dots the model does not describe): an image wider than max_fwhm_ratio or
// narrower than min_fwhm_ratio times the model's width at its place, or whose profile departs from a
// Gaussian kMisfitFactor times more than the bright stars' do (a dust disk as wide as the stars: flat,
// sharp-edged), is a defect.
constexpr double kMisfitFactor = 3.0;
constexpr double kMisfitFloor = 0.01;  // a star's shape is not known better than this
void JudgeShapes(const StarDetectorOptions& o, const StarWidthModel& running, std::vector<DetectedStar>* stars,
                 StarDetectionStats* stats) {
  if (!PointMode(o)) return;
  const StarWidthModel model = SettleStarWidthModel(*stars, running);
  for (DetectedStar& d : *stars) {
    if (d.point.status != PointStatus::kMeasured || d.length_px > 0) continue;
    const double ratio = d.fwhm_px / kFwhmPerSigma / model.SigmaAt(d.point.position_px.x_px, d.point.position_px.y_px);
    const bool misfit = d.profile_misfit > std::max(kMisfitFloor, kMisfitFactor * model.profile_misfit);
    if (ratio <= o.max_fwhm_ratio && ratio >= o.min_fwhm_ratio && !misfit) continue;
    d.point.status = PointStatus::kRejected, d.point.reason = "shape", d.flags |= kStarDefect;
    if (stats) ++stats->defects;
  }
  if (stats) stats->width_model = model;
}

// Ids in reading order; a measured image whose formal sigma is no sigma (zero, not finite, or above
// max_sigma_px: an SNR below 1, a degenerate joint fit) is no measurement: rejected, poor_fit.
void Finish(double max_sigma_px, std::vector<DetectedStar>* stars) {
  for (DetectedStar& d : *stars) {
    const DetectedPoint& p = d.point;
    const bool usable = p.sigma_x_px > 0 && p.sigma_y_px > 0 && p.sigma_x_px < max_sigma_px && p.sigma_y_px < max_sigma_px;
    if (p.status != PointStatus::kMeasured || usable) continue;
    d.point.status = PointStatus::kRejected, d.point.reason = "poor_fit";
    d.point.sigma_x_px = d.point.sigma_y_px = d.point.correlation_xy = 0.0;
  }
  std::sort(stars->begin(), stars->end(), [](const DetectedStar& a, const DetectedStar& b) {
    return a.point.position_px.y_px != b.point.position_px.y_px ? a.point.position_px.y_px < b.point.position_px.y_px
                                                                : a.point.position_px.x_px < b.point.position_px.x_px;
  });
  for (size_t i = 0; i < stars->size(); ++i) (*stars)[i].point.id = fmt::format("P{:06d}", i + 1);
}

void CheckOrThrow(const StarDetectorOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("star detector options", why);
}

}  // namespace

std::string StarFlagNames(unsigned flags) {
  static const char* names[] = {"saturated", "blended", "truncated", "elongated", "defect", "crowded"};
  std::string s;
  for (int i = 0; i < 6; ++i)
    if (flags & (1u << i)) s += (s.empty() ? "" : ",") + std::string(names[i]);
  return s;
}

double StarMask::ArmDistance_px(const PixelPoint& m, const PixelPoint& p) const {
  const double dx = p.x_px - m.x_px, dy = p.y_px - m.y_px;
  double d = 1e300;
  for (const PixelPoint& a : arm_axes_px) d = std::min(d, std::abs(dx * a.y_px - dy * a.x_px));
  return d;
}

bool StarMask::Covers(const PixelPoint& p, double extent_px) const {
  for (const PixelPoint& m : points_px)
    if (std::hypot(p.x_px - m.x_px, p.y_px - m.y_px) < radius_px + extent_px &&
        (arm_reach_px <= 0 || ArmDistance_px(m, p) <= arm_reach_px + extent_px))
      return true;
  return false;
}

bool StarMask::Check(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = "mask: " + m;
    return false;
  };
  if (!(radius_px >= 0)) return fail("radius_px must be >= 0");
  if (!(arm_reach_px >= 0 && arm_half_width_px >= 0)) return fail("arm_reach_px, arm_half_width_px must be >= 0");
  if (arm_reach_px > 0)
    for (const PixelPoint& a : arm_axes_px)
      if (std::abs(std::hypot(a.x_px, a.y_px) - 1.0) > 1e-6) return fail("arm_axes_px must be unit vectors");
  return true;
}

bool StarDetectorOptions::Check(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(psf_fwhm_px >= 0.8 && psf_fwhm_px <= 50)) return fail("psf_fwhm_px must be 0.8..50");
  if (mesh_px < 8) return fail("mesh_px must be at least 8");
  if (!(clip_sigma > 1)) return fail("clip_sigma must exceed 1");
  if (!(max_masked_fraction >= 0 && max_masked_fraction < 1)) return fail("max_masked_fraction must be in [0, 1)");
  if (!(threshold_sigma > 0)) return fail("threshold_sigma must be positive");
  if (min_pixels < 1) return fail("min_pixels must be at least 1");
  if (band_rows < 16) return fail("band_rows must be at least 16");
  if (!(max_fwhm_ratio > 1 && min_fwhm_ratio > 0 && min_fwhm_ratio < 1)) return fail("fwhm ratio limits must bracket 1");
  if (!(max_ellipticity > 0 && max_ellipticity < 1)) return fail("max_ellipticity must be in (0, 1)");
  if (!(max_component_fwhm > 2)) return fail("max_component_fwhm must exceed 2");
  if (!(pair_chi2_gain > 0) || !(min_snr > 0)) return fail("pair_chi2_gain, min_snr must be positive");
  if (!mask.Check(why)) return false;
  if (!(max_dash_length_px >= 0 && max_dash_length_px <= 2000)) return fail("max_dash_length_px must be 0..2000");
  if (!(dash_length_tolerance >= 0 && dash_length_tolerance <= 2)) return fail("dash_length_tolerance must be 0..2");
  if (!(max_dash_width_ratio > 1)) return fail("max_dash_width_ratio must exceed 1");
  return true;
}

std::vector<DetectedStar> DetectStarsInBuffer(const float* values_dn, long width_px, long height_px, double full_scale_dn,
                                              const StarDetectorOptions& options, StarDetectionStats* stats) {
  CheckOrThrow(options);
  Band b;
  b.raw = values_dn;
  b.width = width_px, b.rows = height_px, b.image_height = height_px;
  b.keep_y0 = 0, b.keep_y1 = height_px;
  b.high_dn = options.saturation_dn.value_or(full_scale_dn);
  b.low_dn = options.floor_dn;
  std::vector<DetectedStar> stars;
  StarWidthModel width_model = StartWidthModel(width_px, height_px, options.psf_fwhm_px / kFwhmPerSigma);
  std::vector<PendingPair> pending;
  star_internal::ProcessBand(b, options, width_model, &stars, stats, PointMode(options) ? &pending : nullptr);
  DecidePendingPairs(options, &pending, &width_model, &stars, stats);
  JudgeShapes(options, width_model, &stars, stats);
  Finish(3.0 * options.psf_fwhm_px, &stars);  // 3 x: the start width may be 2 x off the images'
  return stars;
}

std::vector<DetectedStar> DetectStars(const Image& image, const StarDetectorOptions& options, StarDetectionStats* stats) {
  CheckOrThrow(options);
  const long width = image.info().width_px, height = image.info().height_px;
  const long cell = options.mesh_px;
  const long band = (options.band_rows + cell - 1) / cell * cell;
  const long margin = cell;  // fit windows reach at most 40 px beyond a component
  std::vector<float> buffer;
  std::vector<DetectedStar> stars;
  StarWidthModel width_model = StartWidthModel(width, height, options.psf_fwhm_px / kFwhmPerSigma);
  std::vector<PendingPair> pending;
  long have_y0 = 0, have_y1 = 0;  // rows in the buffer from the previous band
  for (long yc = 0; yc < height; yc += band) {
    Band b;
    b.y0_abs = std::max(0L, yc - margin);
    const long y_end = std::min(height, yc + band + margin);
    b.rows = y_end - b.y0_abs;
    b.width = width;
    // The rows shared with the previous band are moved, not decoded again.
    const long reuse = have_y1 > b.y0_abs && have_y0 <= b.y0_abs ? have_y1 - b.y0_abs : 0;
    if (reuse > 0)
      std::copy(buffer.begin() + (b.y0_abs - have_y0) * width, buffer.begin() + (have_y1 - have_y0) * width, buffer.begin());
    buffer.resize(static_cast<size_t>(b.rows * width));
    if (b.rows > reuse) image.ReadRowsDirect(b.y0_abs + reuse, b.rows - reuse, buffer.data() + reuse * width);
    have_y0 = b.y0_abs, have_y1 = y_end;
    b.raw = buffer.data();
    b.keep_y0 = yc, b.keep_y1 = std::min(height, yc + band);
    b.image_height = height;
    b.high_dn = options.saturation_dn.value_or(image.info().full_scale_dn);
    b.low_dn = options.floor_dn;
    star_internal::ProcessBand(b, options, width_model, &stars, stats, PointMode(options) ? &pending : nullptr);
    // Refined band by band: the fits' starts use the width expected at each image.
    if (PointMode(options)) width_model = SettleStarWidthModel(stars, width_model, 1);
  }
  DecidePendingPairs(options, &pending, &width_model, &stars, stats);
  JudgeShapes(options, width_model, &stars, stats);
  Finish(3.0 * options.psf_fwhm_px, &stars);  // 3 x: the start width may be 2 x off the images'
  return stars;
}

}  // namespace platemeter
