// Star detection driver: bands of rows, background mesh, matched filter,
// components, shape tests and the Gaussian fits (star_detector.h).
#include "platemeter/detect/star_detector.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <set>
#include <opencv2/imgproc.hpp>

#include "platemeter/core/error.h"
#include "masked_pixels.h"
#include "star_internal.h"

namespace platemeter {
namespace {

using star_internal::BackgroundMesh;
using star_internal::Component;
using star_internal::FitPixel;
using star_internal::FittedGaussian;
using star_internal::GaussianFitResult;

using star_internal::kFwhmPerSigma;

struct Band {
  const float* raw = nullptr;
  long width = 0, rows = 0;
  long y0_abs = 0;             // absolute row of the buffer's first row
  long keep_y0 = 0, keep_y1 = 0;  // absolute rows whose components this band reports
  long image_height = 0;
  double high_dn = 0, low_dn = 0;  // clip levels
};

// 1 - b/a from Gaussian-weighted second moments (weight sigma w), corrected for the weight.
double Ellipticity(const std::vector<FitPixel>& pixels, double x0, double y0, double offset, double w) {
  double s = 0, sxx = 0, syy = 0, sxy = 0;
  for (const FitPixel& p : pixels) {
    const double dx = p.x_px - x0, dy = p.y_px - y0;
    const double c = (p.value_dn - offset) * std::exp(-0.5 * (dx * dx + dy * dy) / (w * w));
    s += c, sxx += c * dx * dx, syy += c * dy * dy, sxy += c * dx * dy;
  }
  if (s <= 0) return 0.0;
  Eigen::Matrix2d m;
  m << sxx / s, sxy / s, sxy / s, syy / s;
  const Eigen::Vector2d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues();
  auto unweight = [w](double v) { return v < 0.95 * w * w ? v * w * w / (w * w - v) : 20.0 * w * w; };
  const double small = unweight(std::max(l(0), 1e-6)), large = unweight(std::max(l(1), 1e-6));
  return 1.0 - std::sqrt(small / large);
}

// SExtractor's windowed centroid: iterated Gaussian-weighted first moments,
// x <- x + 2 sum(w c (x_i - x)) / sum(w c), within 4 window sigmas; its sigma
// from the propagation of white pixel noise.
struct Windowed {
  bool ok = false;
  double x = 0, y = 0, sigma_x = 0, sigma_y = 0;
};
Windowed WindowedCentroid(const std::vector<FitPixel>& pixels, double x, double y, double offset, double w,
                          double noise) {
  Windowed r;
  for (int iteration = 0; iteration < 16; ++iteration) {
    double s = 0, sx = 0, sy = 0;
    for (const FitPixel& p : pixels) {
      const double dx = p.x_px - x, dy = p.y_px - y, r2 = dx * dx + dy * dy;
      if (r2 > 16 * w * w) continue;
      const double c = (p.value_dn - offset) * std::exp(-0.5 * r2 / (w * w));
      s += c, sx += c * dx, sy += c * dy;
    }
    if (s <= 0) return r;
    const double step_x = 2 * sx / s, step_y = 2 * sy / s;
    x += step_x, y += step_y;
    if (std::hypot(step_x, step_y) < 2e-5) break;
  }
  double s = 0, vx = 0, vy = 0;
  for (const FitPixel& p : pixels) {
    const double dx = p.x_px - x, dy = p.y_px - y, r2 = dx * dx + dy * dy;
    if (r2 > 16 * w * w) continue;
    const double g = std::exp(-0.5 * r2 / (w * w));
    s += (p.value_dn - offset) * g, vx += g * g * dx * dx, vy += g * g * dy * dy;
  }
  if (s <= 0) return r;
  r.ok = true;
  r.x = x, r.y = y;
  r.sigma_x = 2 * noise * std::sqrt(vx) / s;
  r.sigma_y = 2 * noise * std::sqrt(vy) / s;
  return r;
}

// A measured image at a fitted position: the fields every fit fills.
DetectedStar MeasuredImage(double x_px, double y_px, double sigma_x_px, double sigma_y_px, double correlation_xy,
                           double flux_dn, double sigma_flux_dn, double background_dn) {
  DetectedStar d;
  d.point.kind = PointKind::kStar;
  d.point.status = PointStatus::kMeasured;
  d.point.position_px = {x_px, y_px};
  d.point.sigma_x_px = sigma_x_px;
  d.point.sigma_y_px = sigma_y_px;
  d.point.correlation_xy = correlation_xy;
  d.flux_dn = flux_dn;
  d.sigma_flux_dn = sigma_flux_dn;
  d.background_dn = background_dn;
  d.snr = sigma_flux_dn > 0 ? flux_dn / sigma_flux_dn : 0.0;
  return d;
}

// A rejected image; `why` (line, cross, masked: near a known cross, masked_pixels: no values, shape) becomes its reason, the flag says defect.
DetectedStar Defect(double x, double y, const std::string& why) {
  DetectedStar d;
  d.point.kind = PointKind::kStar;
  d.point.status = PointStatus::kRejected;
  d.point.reason = why;
  d.point.position_px = {x, y};
  d.flags = kStarDefect;
  return d;
}

// How far a single image's profile is from the fitted Gaussian: the residual's excess RMS (beyond the
// noise) as a fraction of the image's flux, scaled by its width so that a fixed shape (a disk, a Moffat
// star) gives one value at any flux or width: sqrt(chi^2 - dof) x noise x sigma / flux. 0 when the
// excess is within kMisfitChi2Sigmas of the chi^2's own spread (a Gaussian image within its noise).
constexpr double kMisfitChi2Sigmas = 5.0;
double ProfileMisfit(const GaussianFitResult& fit, const FittedGaussian& g, double noise_dn) {
  const double dof = std::max(1, fit.pixels - 5), excess = fit.chi2 - dof;
  if (excess <= kMisfitChi2Sigmas * std::sqrt(2.0 * dof) || g.flux_dn <= 0) return 0.0;
  return std::sqrt(excess) * noise_dn * g.sigma_px / g.flux_dn;
}

// Star widths on one plate vary (a wide-angle lens's images grow toward the corners, focus and tilt
// vary): psf_fwhm_px is a starting value, and a fitted width is judged against the plate's width model
// (star_width_model.h). While the bands are measured, before the model is settled, a width is kept
// when it lies within kStartWidthSpread times the defect limits of the starting value. Trail mode has
// no model: the limits are the starting value's.
constexpr double kStartWidthSpread = 2.0;
bool WidthPlausible(const StarDetectorOptions& o, double ratio_to_start) {
  const double spread = o.max_dash_length_px > 0 ? 1.0 : kStartWidthSpread;
  return ratio_to_start <= spread * o.max_fwhm_ratio && ratio_to_start >= o.min_fwhm_ratio / spread;
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
  if (o.max_dash_length_px > 0) return;
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

// Distance from (x, y) to the nearer arm line of the cross centred at m (options.mask_arm_axes_px).
double ArmDistance_px(const StarDetectorOptions& o, const PixelPoint& m, double x_px, double y_px) {
  const double dx = x_px - m.x_px, dy = y_px - m.y_px;
  double d = 1e300;
  for (const PixelPoint& a : o.mask_arm_axes_px) d = std::min(d, std::abs(dx * a.y_px - dy * a.x_px));
  return d;
}

// Trail mode: centre, direction and sweep length of a component from the second moments of its
// own (positive-contrast) pixels: a uniform sweep of length L adds L^2 / 12 along its direction.
struct SweepMoments {
  double x = 0, y = 0, angle_rad = 0, length_px = 0, flux_dn = 0;
};
SweepMoments ComponentSweep(const std::vector<FitPixel>& pixels, const cv::Mat& labels, int label, long y0_abs) {
  SweepMoments m;
  double s = 0, sx = 0, sy = 0;
  for (const FitPixel& p : pixels)
    if (p.value_dn > 0 && labels.at<int>(int(p.y_px - y0_abs), int(p.x_px)) == label)
      s += p.value_dn, sx += p.value_dn * p.x_px, sy += p.value_dn * p.y_px;
  if (s <= 0) return m;
  m.x = sx / s, m.y = sy / s, m.flux_dn = s;
  double sxx = 0, syy = 0, sxy = 0;
  for (const FitPixel& p : pixels)
    if (p.value_dn > 0 && labels.at<int>(int(p.y_px - y0_abs), int(p.x_px)) == label) {
      const double dx = p.x_px - m.x, dy = p.y_px - m.y;
      sxx += p.value_dn * dx * dx, syy += p.value_dn * dy * dy, sxy += p.value_dn * dx * dy;
    }
  Eigen::Matrix2d c;
  c << sxx / s, sxy / s, sxy / s, syy / s;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(c);
  m.angle_rad = std::atan2(eig.eigenvectors()(1, 1), eig.eigenvectors()(0, 1));
  m.length_px = std::sqrt(12.0 * std::max(0.0, eig.eigenvalues()(1) - eig.eigenvalues()(0)));
  return m;
}

// Ratio of the major to the minor second moment of a component's mask: large for a line at any
// angle (a slanted dash fills little of its box too), about 1 for a cross.
double MaskElongation(const cv::Mat& labels, const Component& c) {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (int y = c.y; y < c.y + c.height; ++y)
    for (int x = c.x; x < c.x + c.width; ++x)
      if (labels.at<int>(y, x) == c.label) n += 1, sx += x, sy += y, sxx += double(x) * x, syy += double(y) * y, sxy += double(x) * y;
  if (n < 2) return 1.0;
  const double mx = sx / n, my = sy / n;
  Eigen::Matrix2d m;
  m << sxx / n - mx * mx, sxy / n - mx * my, sxy / n - mx * my, syy / n - my * my;
  const Eigen::Vector2d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues();
  return l(1) / std::max(l(0), 1e-3);
}

struct Box {
  double x0, x1, y0, y1;
};

// Trail mode: fits one segment and reports it as a measured elongated image, or as a defect when
// it is too long (line) or too wide (dust, wide scratch) for a dash.
void MeasureSegment(const SweepMoments& m, const std::vector<FitPixel>& pixels, double noise, double psf_sigma,
                    bool clipped, bool truncated, const StarDetectorOptions& o, const BackgroundMesh& mesh, long y0_abs,
                    double sign, const Box& window, std::vector<DetectedStar>* result) {
  star_internal::FittedSegment start;
  start.x_px = m.x, start.y_px = m.y, start.angle_rad = m.angle_rad, start.length_px = m.length_px;
  start.flux_dn = m.flux_dn, start.sigma_px = psf_sigma;
  star_internal::SegmentFitResult fit = star_internal::FitSegment(pixels, start, noise);
  if (!fit.ok) return;
  // A faint image on the segment's wing (the first dot, 10 s after the last leading dash): the
  // largest residual clearly off the segment starts a joint fit, kept when chi^2 drops by 25.
  {
    const star_internal::FittedSegment& g = fit.segment;
    const double se = std::sqrt(g.sigma_px * g.sigma_px + 1.0 / 12.0);
    const double c = std::cos(g.angle_rad), sn = std::sin(g.angle_rad);
    auto off_segment = [&](double x, double y) {
      const double du = x - g.x_px, dv = y - g.y_px;
      const double a = std::abs(du * c + dv * sn) - 0.5 * g.length_px, b = std::abs(-du * sn + dv * c);
      return std::hypot(std::max(a, 0.0), b) > 2.0 * se;
    };
    double worst = 0;
    star_internal::FittedPoint point;
    for (const FitPixel& p : pixels) {
      const double r = p.value_dn - fit.offset_dn - star_internal::SegmentModel(g, p.x_px, p.y_px);
      if (r > worst && off_segment(p.x_px, p.y_px)) worst = r, point.x_px = p.x_px, point.y_px = p.y_px;
    }
    if (worst > 3.0 * noise) {
      point.flux_dn = worst * 2.0 * M_PI * se * se;
      star_internal::SegmentFitResult joint = star_internal::FitSegmentAndPoint(pixels, g, point, noise);
      if (joint.ok && fit.chi2 - joint.chi2 > 25.0 && joint.point.flux_dn > o.min_snr * joint.point.sigma_flux_dn &&
          off_segment(joint.point.x_px, joint.point.y_px) && joint.point.x_px > window.x0 &&
          joint.point.x_px < window.x1 && joint.point.y_px > window.y0 && joint.point.y_px < window.y1)
        fit = std::move(joint);
    }
  }
  const star_internal::FittedSegment& g = fit.segment;
  // A fit whose centre left its window found no image of its own there (seen at 1e8 px).
  const bool inside = g.x_px >= window.x0 && g.x_px <= window.x1 && g.y_px >= window.y0 && g.y_px <= window.y1;
  const double ratio = g.sigma_px / psf_sigma;
  if (ratio > o.max_dash_width_ratio || ratio < o.min_fwhm_ratio) {
    if (inside) result->push_back(Defect(g.x_px, g.y_px, "shape"));
    return;
  }
  if (g.length_px > (1.0 + o.dash_length_tolerance) * o.max_dash_length_px + o.psf_fwhm_px) {
    DetectedStar line = inside ? Defect(g.x_px, g.y_px, "line")
                               : Defect(0.5 * (window.x0 + window.x1), 0.5 * (window.y0 + window.y1), "line");
    // Its extent (a trail linker asks what it may hide), at most the fit window's: a fit of a component
    // unlike a segment may run its length away (88636 px seen on a 6012 px scan).
    line.length_px = std::min(g.length_px, std::hypot(window.x1 - window.x0, window.y1 - window.y0));
    line.angle_deg = g.angle_rad * 180.0 / std::numbers::pi;
    line.box_min_px = {window.x0, window.y0}, line.box_max_px = {window.x1, window.y1};
    result->push_back(line);
    return;
  }
  if (g.flux_dn <= 0 || g.flux_dn < o.min_snr * g.sigma_flux_dn) return;
  if (g.x_px < window.x0 || g.x_px > window.x1 || g.y_px < window.y0 || g.y_px > window.y1) return;
  DetectedStar d = MeasuredImage(g.x_px, g.y_px, g.sigma_x_px, g.sigma_y_px, g.correlation_xy, g.flux_dn,
                                 g.sigma_flux_dn, mesh.LevelAt(g.x_px, g.y_px - y0_abs) + sign * fit.offset_dn);
  // Peak of the swept PSF (the sweep's middle).
  d.peak_dn = g.flux_dn / (std::sqrt(2.0 * M_PI) * g.sigma_px) *
              std::erf(0.5 * g.length_px / (std::sqrt(2.0) * g.sigma_px)) / g.length_px;
  d.fwhm_px = g.sigma_px * kFwhmPerSigma;
  d.length_px = g.length_px;
  d.sigma_length_px = g.sigma_length_px;
  d.angle_deg = g.angle_rad * 180.0 / M_PI;
  // Ellipticity of the swept image: minor sigma over major sigma (sigma^2 + L^2 / 12).
  d.ellipticity = 1.0 - g.sigma_px / std::sqrt(g.sigma_px * g.sigma_px + g.length_px * g.length_px / 12.0);
  if (clipped) d.flags |= kStarSaturated;
  if (truncated) d.flags |= kStarTruncated;
  if (d.ellipticity > o.max_ellipticity && g.length_px > 3.0 * g.sigma_length_px) d.flags |= kStarElongated;
  if (fit.has_point) {
    const star_internal::FittedPoint& q = fit.point;
    d.flags |= kStarBlended;
    DetectedStar e = MeasuredImage(q.x_px, q.y_px, q.sigma_x_px, q.sigma_y_px, q.correlation_xy, q.flux_dn,
                                   q.sigma_flux_dn, mesh.LevelAt(q.x_px, q.y_px - y0_abs) + sign * fit.offset_dn);
    const double se2 = g.sigma_px * g.sigma_px + 1.0 / 12.0;
    e.peak_dn = q.flux_dn / (2.0 * M_PI * se2);
    e.fwhm_px = d.fwhm_px;
    e.flags = kStarBlended | (truncated ? kStarTruncated : 0u);
    result->push_back(e);
  }
  result->push_back(d);
}

// The pair test of a component whose single fit is too wide or leaves a chi^2 excess: two starts (a
// split along the major axis by the excess second moment; the single star plus one at the largest
// residual), the better kept when chi^2 drops by pair_chi2_gain and both are star images of the width
// expected here. True when *fit became the pair.
bool TryPair(const std::vector<FitPixel>& pixels, const cv::Mat& labels, int label, long y0_abs, const FittedGaussian& start,
             double image_sigma, double noise, double min_sigma, const StarDetectorOptions& o, GaussianFitResult* fit) {
  // Two stars along the component's major axis, split by the excess second moment.
  const double cx = fit->stars[0].x_px, cy = fit->stars[0].y_px;
  double sxx = 0, syy = 0, sxy = 0, w = 0;
  for (const FitPixel& p : pixels) {
    const double dx = p.x_px - cx, dy = p.y_px - cy;
    if (p.value_dn <= 0 || dx * dx + dy * dy > 36 * image_sigma * image_sigma) continue;
    w += p.value_dn, sxx += p.value_dn * dx * dx, syy += p.value_dn * dy * dy, sxy += p.value_dn * dx * dy;
  }
  if (w > 0) {
    Eigen::Matrix2d m;
    m << sxx / w, sxy / w, sxy / w, syy / w;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(m);
    const Eigen::Vector2d axis = eig.eigenvectors().col(1);
    const double h = std::sqrt(std::max(eig.eigenvalues()(1) - eig.eigenvalues()(0), 0.5));
    FittedGaussian a = start, c = start;
    a.x_px = cx + h * axis(0), a.y_px = cy + h * axis(1);
    c.x_px = cx - h * axis(0), c.y_px = cy - h * axis(1);
    a.flux_dn = c.flux_dn = 0.5 * fit->stars[0].flux_dn;
    GaussianFitResult pair = star_internal::FitGaussians(pixels, {a, c}, noise, min_sigma);
    // Second start: the single fit plus a star at the largest residual of the
    // component (wider pairs, where the single fit sits on the brighter star).
    {
      const GaussianFitResult& f = *fit;
      const FittedGaussian& g = f.stars[0];
      double worst = -1e30;
      FittedGaussian second = start;
      for (const FitPixel& p : pixels) {
        if (labels.at<int>(int(p.y_px - y0_abs), int(p.x_px)) != label) continue;
        const double model = f.offset_dn + g.flux_dn * std::exp(-0.5 * (std::pow(p.x_px - g.x_px, 2) + std::pow(p.y_px - g.y_px, 2)) /
                                                                (g.sigma_px * g.sigma_px)) / (2 * M_PI * g.sigma_px * g.sigma_px);
        if (p.value_dn - model > worst) worst = p.value_dn - model, second.x_px = p.x_px, second.y_px = p.y_px;
      }
      second.flux_dn = std::max(worst, 0.0) * 2 * M_PI * image_sigma * image_sigma;
      FittedGaussian first = g;
      first.sigma_px = image_sigma;
      GaussianFitResult alt = star_internal::FitGaussians(pixels, {first, second}, noise, min_sigma);
      if (alt.stars.size() == 2 && (pair.stars.size() != 2 || alt.chi2 < pair.chi2)) pair = std::move(alt);
    }
    if (pair.stars.size() == 2 && fit->chi2 - pair.chi2 > o.pair_chi2_gain) {
      bool ok = true;
      for (const FittedGaussian& g : pair.stars)
        if (g.flux_dn <= 0 || g.flux_dn < o.min_snr * g.sigma_flux_dn || g.sigma_px > o.max_fwhm_ratio * image_sigma ||
            g.sigma_px < o.min_fwhm_ratio * image_sigma)
          ok = false;  // a pair of star images, each of the width expected here (not a cross's arms)
      if (std::hypot(pair.stars[0].x_px - pair.stars[1].x_px, pair.stars[0].y_px - pair.stars[1].y_px) < 0.7 * o.psf_fwhm_px)
        ok = false;
      if (ok) {
        *fit = std::move(pair);
        return true;
      }
    }
  }
  return false;
}

// Where a component's point fits are reported from: its pixels, widths, noise, background and fit window.
struct PointFitPlace {
  const std::vector<FitPixel>* pixels;
  double start_sigma, image_sigma, noise_dn;  // px, px, DN
  const BackgroundMesh* mesh;
  double sign;
  long y0_abs;
  Box window;  // absolute px: a fit that left it is dropped
  bool clipped, truncated;
};

// The measured images of a component's fit (one star, or a blended pair): noise dropped, implausible
// widths rejected, the rest measured with their flags.
void ReportPointFits(const GaussianFitResult& fit, bool blended, const PointFitPlace& at, const StarDetectorOptions& o,
                     std::vector<DetectedStar>* result) {
  for (const FittedGaussian& g : fit.stars) {
    // Noise first: a fit below the SNR limit is no image at all, not a defect worth a row.
    if (g.flux_dn <= 0 || g.flux_dn < o.min_snr * g.sigma_flux_dn) continue;
    // Width: only the implausible here; the test against the plate's width model at the image's
    // place follows once every band is measured (JudgeShapes).
    // A fit that left its window found no image of its own there (it may have run off to 1e8 px).
    if (g.x_px < at.window.x0 || g.x_px > at.window.x1 || g.y_px < at.window.y0 || g.y_px > at.window.y1) continue;
    if (!WidthPlausible(o, g.sigma_px / at.start_sigma)) {
      result->push_back(Defect(g.x_px, g.y_px, "shape"));
      continue;
    }
    DetectedStar d = MeasuredImage(g.x_px, g.y_px, g.sigma_x_px, g.sigma_y_px, g.correlation_xy, g.flux_dn,
                                   g.sigma_flux_dn, at.mesh->LevelAt(g.x_px, g.y_px - at.y0_abs) + at.sign * fit.offset_dn);
    d.peak_dn = g.flux_dn / (2.0 * M_PI * g.sigma_px * g.sigma_px);
    d.fwhm_px = g.sigma_px * kFwhmPerSigma;
    if (!blended) {
      d.ellipticity = Ellipticity(*at.pixels, g.x_px, g.y_px, fit.offset_dn, std::max(g.sigma_px, at.image_sigma));
      d.profile_misfit = ProfileMisfit(fit, g, at.noise_dn);
    }
    if (!blended && o.windowed_centroid) {
      const Windowed w = WindowedCentroid(*at.pixels, g.x_px, g.y_px, fit.offset_dn, at.image_sigma, fit.residual_sigma_dn);
      if (w.ok) {
        d.point.position_px = {w.x, w.y};
        d.point.sigma_x_px = w.sigma_x, d.point.sigma_y_px = w.sigma_y, d.point.correlation_xy = 0.0;
      }
    }
    if (at.clipped) d.flags |= kStarSaturated;
    if (blended) d.flags |= kStarBlended;
    if (at.truncated) d.flags |= kStarTruncated;
    if (d.ellipticity > o.max_ellipticity && d.snr > 20) d.flags |= kStarElongated;
    result->push_back(d);
  }
}

void ProcessBand(const Band& b, const StarDetectorOptions& o, const StarWidthModel& width_model, std::vector<DetectedStar>* out,
                 StarDetectionStats* stats) {
  const double sign = o.dark ? -1.0 : 1.0;
  const double psf_sigma = o.psf_fwhm_px / kFwhmPerSigma;
  const BackgroundMesh mesh =
      star_internal::ComputeBackgroundMesh(b.raw, b.width, b.rows, o.mesh_px, o.clip_sigma, b.low_dn, b.high_dn);

  cv::Mat contrast(static_cast<int>(b.rows), static_cast<int>(b.width), CV_32F);
  tbb::parallel_for(0L, b.rows, [&](long y) {
    float* c = contrast.ptr<float>(static_cast<int>(y));
    const float* r = b.raw + y * b.width;
    std::vector<float> level(b.width);
    mesh.LevelRow(y, b.width, level.data());
    for (long x = 0; x < b.width; ++x) c[x] = static_cast<float>(sign * (r[x] - level[x]));
    detect_internal::FillMasked(c, static_cast<size_t>(b.width), 0.0f);  // no value: the background's, to the filter
  });
  // Matched filter: a Gaussian of the PSF's sigma; its noise is sigma * sum(w^2)^(1/2).
  const int ksize = 2 * static_cast<int>(std::ceil(3.0 * psf_sigma)) + 1;
  const cv::Mat kernel = cv::getGaussianKernel(ksize, psf_sigma, CV_64F);
  const double noise_gain = kernel.dot(kernel);  // 2-D sum(w^2) = (1-D sum)^2, its root is the 1-D sum
  cv::Mat filtered;
  cv::GaussianBlur(contrast, filtered, cv::Size(ksize, ksize), psf_sigma, psf_sigma, cv::BORDER_REFLECT);
  cv::Mat mask(filtered.size(), CV_8U);
  tbb::parallel_for(0L, b.rows, [&](long y) {
    const float* f = filtered.ptr<float>(static_cast<int>(y));
    uint8_t* m = mask.ptr<uint8_t>(static_cast<int>(y));
    for (long x = 0; x < b.width; ++x) m[x] = f[x] > o.threshold_sigma * noise_gain * mesh.SigmaAt(x, y) ? 1 : 0;
  });
  cv::Mat labels, comp, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, comp, centroids, 8, CV_32S);
  mask.release();

  std::vector<Component> components;
  for (int l = 1; l < n; ++l) {
    Component c;
    c.label = l;
    c.clump = l;
    c.area = comp.at<int>(l, cv::CC_STAT_AREA);
    c.x = comp.at<int>(l, cv::CC_STAT_LEFT), c.y = comp.at<int>(l, cv::CC_STAT_TOP);
    c.width = comp.at<int>(l, cv::CC_STAT_WIDTH), c.height = comp.at<int>(l, cv::CC_STAT_HEIGHT);
    if (c.area >= o.min_pixels) components.push_back(c);
  }
  // Trail mode: the longest box one dash may have (its length, the tolerance, and the PSF's wings
  // above the threshold at both ends); longer components are split at their gaps first.
  const bool dash_mode = o.max_dash_length_px > 0;
  const double dash_box_px = (1.0 + o.dash_length_tolerance) * o.max_dash_length_px + 6.0 * o.psf_fwhm_px;
  const double line_box_px = dash_mode ? std::max(o.max_component_fwhm * o.psf_fwhm_px, dash_box_px)
                                       : o.max_component_fwhm * o.psf_fwhm_px;
  if (dash_mode) {
    // Deblending (dashes of a run, a faint dot beside a bright dash): a piece must rise 3.5 filtered
    // noise sigmas above its saddle and hold 0.5 % of the component's flux (SExtractor's default).
    std::vector<float> level(components.size()), rise(components.size());
    for (size_t k = 0; k < components.size(); ++k) {
      const double sigma_f = noise_gain * mesh.SigmaAt(components[k].x + 0.5 * components[k].width,
                                                       components[k].y + 0.5 * components[k].height);
      level[k] = static_cast<float>(o.threshold_sigma * sigma_f);
      rise[k] = static_cast<float>(3.5 * sigma_f);
    }
    // Clumps: components longer than a run of five leading dashes (140 s = 7 dash lengths), or large and
    // not line-like (crossing trails; also reseau crosses, dust, scratches). They are deblended too (on a
    // crowded plate they hold a tenth of the measurable dots) and their pieces flagged crowded: a dash
    // crossed by other images may come out in parts, which the linker must not take for empty places. A
    // defect that does not fall apart stays whole and is rejected by the shape tests below.
    std::vector<Component> whole, split;
    std::vector<float> split_level, split_rise;
    for (size_t k = 0; k < components.size(); ++k) {
      Component& c = components[k];
      const double long_side = std::max(c.width, c.height);
      const bool too_long = long_side > 7.0 * (1.0 + o.dash_length_tolerance) * o.max_dash_length_px + 6.0 * o.psf_fwhm_px;
      const bool blob = long_side > 4.0 * o.psf_fwhm_px && MaskElongation(labels, c) <= 3.0;
      const bool cross_like = blob && c.area < 0.3 * c.width * c.height;
      c.crowded = too_long || blob;
      if (!too_long && cross_like) {  // a reseau cross's arms would pass as dashes
        c.crowded = false;
        whole.push_back(c);
      } else {
        split.push_back(c), split_level.push_back(level[k]), split_rise.push_back(rise[k]);
      }
    }
    int next_label = n;
    const int min_piece = std::max(o.min_pixels, static_cast<int>(0.5 * o.psf_fwhm_px * o.psf_fwhm_px));
    components = star_internal::SplitComponents(&labels, filtered, split, split_level, split_rise, 2.0 * o.psf_fwhm_px,
                                                min_piece, 0.005, &next_label);
    components.insert(components.end(), whole.begin(), whole.end());
  }
  const int window_reach = dash_mode ? std::max(40, static_cast<int>(std::ceil(0.5 * dash_box_px + 3.0 * psf_sigma))) : 40;
  // Point mode: below the level that pure noise, filtered, reaches once in ten scans of this size, a
  // peak cannot be told from noise: not fitted, no row (a star that faint has no position worth one).
  constexpr double kNoisePeaksPerScan = 0.1;
  const double noise_peak_level =
      dash_mode ? 0.0
                : star_internal::NoisePeakLevel(static_cast<double>(b.width) * b.image_height, psf_sigma, kNoisePeaksPerScan);
  std::atomic<long> noise_peaks{0};

  std::vector<std::vector<DetectedStar>> found(components.size());
  tbb::parallel_for(size_t{0}, components.size(), [&](size_t ci) {
    const Component& cc = components[ci];
    const int l = cc.label;
    const int area = cc.area;
    const int bx = cc.x, by = cc.y, bw = cc.width, bh = cc.height;
    int px = bx, py = by;
    float best = -1e30f;
    for (int y = by; y < by + bh; ++y)
      for (int x = bx; x < bx + bw; ++x)
        if (labels.at<int>(y, x) == l && filtered.at<float>(y, x) > best) best = filtered.at<float>(y, x), px = x, py = y;
    const long peak_y_abs = b.y0_abs + py;
    if (peak_y_abs < b.keep_y0 || peak_y_abs >= b.keep_y1) return;
    if (best < noise_peak_level * noise_gain * mesh.SigmaAt(px, py)) {
      ++noise_peaks;
      return;
    }
    std::vector<DetectedStar>& result = found[ci];
    // Shape tests on the component: lines (scratches; dashes and trails unless in trail mode), crosses,
    // masked marks.
    const double long_side = std::max(bw, bh);
    const bool line_like = long_side > line_box_px;
    bool sparse = long_side > 4.0 * o.psf_fwhm_px && area < 0.3 * bw * bh;
    if (sparse && dash_mode && MaskElongation(labels, cc) > 3.0) sparse = false;  // a slanted dash, not a cross
    // Masked: a peak near a known cross (on one of its arms, where the arms are known). The crosses near
    // the component keep their arms' pixels out of its fit (crosses of the stars' polarity touching an
    // image make one component with it, a defect by its shape; of the other polarity they are below the
    // threshold but push the fit away from them).
    bool masked = false;
    std::vector<PixelPoint> near_crosses;
    for (const PixelPoint& m : o.mask_px) {
      const double r = std::hypot(m.x_px - px, m.y_px - peak_y_abs);
      if (r < o.mask_radius_px && (o.mask_arm_reach_px <= 0 || ArmDistance_px(o, m, px, peak_y_abs) <= o.mask_arm_reach_px))
        masked = true;
      if (o.mask_arm_reach_px > 0 && r < o.mask_radius_px + window_reach * std::sqrt(2.0)) near_crosses.push_back(m);
    }
    const auto on_arm = [&](int x, long y_abs) {
      for (const PixelPoint& m : near_crosses)
        if (std::hypot(m.x_px - x, m.y_px - y_abs) < o.mask_radius_px &&
            ArmDistance_px(o, m, x, y_abs) <= o.mask_arm_half_width_px)
          return true;
      return false;
    };
    if (line_like || sparse || masked) {
      if (!line_like) {
        result.push_back(Defect(px, peak_y_abs, sparse ? "cross" : "masked"));
        return;
      }
      // A line at the centre of its box, its extent the box's diagonal (what a trail linker asks it may hide).
      DetectedStar line = Defect(bx + 0.5 * (bw - 1), b.y0_abs + by + 0.5 * (bh - 1), "line");
      line.length_px = std::hypot(bw, bh);
      line.box_min_px = {bx - 0.5, b.y0_abs + by - 0.5}, line.box_max_px = {bx + bw - 0.5, b.y0_abs + by + bh - 0.5};
      result.push_back(line);
      return;
    }
    // The width expected here: the plate's model from the bands measured so far (the start value until
    // there are bright stars to fit it to).
    const double image_sigma = width_model.SigmaAt(px, peak_y_abs);
    // Fit window: the component grown by the PSF, and at least +-3 sigma around the peak.
    const int grow = static_cast<int>(std::ceil(image_sigma)) + 1;
    const int half = static_cast<int>(std::ceil(3.0 * image_sigma)) + 1;
    int x0 = std::min(bx, px - half) - grow, x1 = std::max(bx + bw, px + half + 1) + grow;
    int y0 = std::min(by, py - half) - grow, y1 = std::max(by + bh, py + half + 1) + grow;
    x0 = std::max(x0, px - window_reach), x1 = std::min(x1, px + window_reach + 1);
    y0 = std::max(y0, py - window_reach), y1 = std::min(y1, py + window_reach + 1);
    bool truncated = false;
    if (x0 < 0) x0 = 0, truncated = true;
    if (x1 > b.width) x1 = static_cast<int>(b.width), truncated = true;
    if (y0 < 0) { y0 = 0; truncated = truncated || b.y0_abs == 0; }
    if (y1 > b.rows) { y1 = static_cast<int>(b.rows); truncated = truncated || b.y0_abs + b.rows == b.image_height; }
    std::vector<FitPixel> pixels;
    int clipped = 0, masked_px = 0;
    double peak_contrast = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const int lab = labels.at<int>(y, x);
        if (lab != 0 && lab != l) continue;  // another component's pixels
        if (!near_crosses.empty() && on_arm(x, b.y0_abs + y)) continue;
        const float raw = b.raw[long(y) * b.width + x];
        if (std::isnan(raw)) {  // masked: no value in the scan
          ++masked_px;
          continue;
        }
        if (raw >= b.high_dn || raw <= b.low_dn) {
          ++clipped;
          continue;
        }
        const float c = contrast.at<float>(y, x);
        if (lab == l) peak_contrast = std::max<double>(peak_contrast, c);
        pixels.push_back({float(x), float(b.y0_abs + y), c});
      }
    if (masked_px > o.max_masked_fraction * (pixels.size() + clipped + masked_px)) {
      result.push_back(Defect(px, peak_y_abs, "masked_pixels"));
      return;
    }
    const double noise = std::max(1e-3f, mesh.SigmaAt(px, py));
    if (dash_mode) {
      // A sweep clearly longer than the PSF: fitted as a segment (dash, long dot), not as a star.
      const SweepMoments m = ComponentSweep(pixels, labels, l, b.y0_abs);
      if (m.length_px > o.psf_fwhm_px) {
        const size_t first = result.size();
        MeasureSegment(m, pixels, noise, psf_sigma, clipped > 0, truncated, o, mesh, b.y0_abs, sign,
                       {x0 - 0.5, x1 - 0.5, b.y0_abs + y0 - 0.5, b.y0_abs + y1 - 0.5}, &result);
        // A line's box holds its whole component too (the fit window stops window_reach from the peak).
        for (size_t k = first; k < result.size(); ++k) {
          DetectedStar& d = result[k];
          if (d.point.reason != "line") continue;
          d.box_min_px = {std::min(d.box_min_px.x_px, bx - 0.5), std::min(d.box_min_px.y_px, b.y0_abs + by - 0.5)};
          d.box_max_px = {std::max(d.box_max_px.x_px, bx + bw - 0.5),
                          std::max(d.box_max_px.y_px, b.y0_abs + by + bh - 0.5)};
        }
        return;
      }
    }
    FittedGaussian start;
    start.x_px = px;
    start.y_px = peak_y_abs;
    start.sigma_px = image_sigma;
    start.flux_dn = std::max(4.0 * M_PI * image_sigma * image_sigma * best, 2.0 * M_PI * image_sigma * image_sigma * peak_contrast);
    const double min_sigma = o.min_fwhm_ratio * image_sigma * 0.5;
    GaussianFitResult fit = star_internal::FitGaussians(pixels, {start}, noise, min_sigma);
    if (fit.stars.empty()) return;
    const int dof1 = fit.pixels - 5;
    const double ratio1 = fit.stars[0].sigma_px / image_sigma;
    bool blended = false;
    // A second star is tried when the single one is too wide for its SNR or
    // leaves a chi^2 excess of 5 sigma.
    const double snr1 = fit.stars[0].sigma_flux_dn > 0 ? fit.stars[0].flux_dn / fit.stars[0].sigma_flux_dn : 0.0;
    if ((ratio1 > 1.12 && snr1 > 30) || fit.chi2 > dof1 + 5.0 * std::sqrt(2.0 * dof1)) {
      blended = TryPair(pixels, labels, l, b.y0_abs, start, image_sigma, noise, min_sigma, o, &fit);
    }
    const PointFitPlace at{&pixels, psf_sigma, image_sigma, noise, &mesh, sign, b.y0_abs,
                           {x0 - 0.5, x1 - 0.5, b.y0_abs + y0 - 0.5, b.y0_abs + y1 - 0.5}, clipped > 0, truncated};
    ReportPointFits(fit, blended, at, o, &result);
  });
  // A clump still holding a line after deblending holds a scratch: its other pieces are parts of it, or of
  // what it crosses (a reseau cross's arms, cut from it, pass as dashes): all rejected as the line. (A piece
  // too long for its box is seen in every band; a segment fitted too long only in the band of its peak.)
  std::set<int> line_clumps;
  for (size_t ci = 0; ci < components.size(); ++ci) {
    const Component& cc = components[ci];
    if (!cc.crowded) continue;
    if (std::max(cc.width, cc.height) > line_box_px) line_clumps.insert(cc.clump);
    for (const DetectedStar& d : found[ci])
      if (d.point.reason == "line") line_clumps.insert(cc.clump);
  }
  for (size_t ci = 0; ci < components.size(); ++ci) {
    if (!components[ci].crowded) continue;
    for (DetectedStar& d : found[ci]) {
      d.flags |= kStarCrowded;
      if (line_clumps.count(components[ci].clump) && d.point.status == PointStatus::kMeasured)
        d.point.status = PointStatus::kRejected, d.point.reason = "line", d.flags |= kStarDefect;
    }
  }
  for (auto& v : found)
    for (auto& d : v) {
      if (stats && d.point.status == PointStatus::kRejected) ++stats->defects;
      out->push_back(std::move(d));
    }
  if (stats) stats->components += n - 1, stats->noise_peaks += noise_peaks, ++stats->bands;
  if (stats) stats->noise_peak_level_sigma = noise_peak_level;
  if (stats && stats->noise_sigma_dn == 0 && !mesh.sigma_dn.empty()) {
    std::vector<float> s = mesh.sigma_dn;
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    stats->noise_sigma_dn = s[s.size() / 2];
  }
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
  if (!(pair_chi2_gain > 0) || !(min_snr > 0) || !(mask_radius_px >= 0)) return fail("pair_chi2_gain, min_snr must be positive");
  if (!(mask_arm_reach_px >= 0 && mask_arm_half_width_px >= 0)) return fail("mask_arm_reach_px, mask_arm_half_width_px must be >= 0");
  if (mask_arm_reach_px > 0)
    for (const PixelPoint& a : mask_arm_axes_px)
      if (std::abs(std::hypot(a.x_px, a.y_px) - 1.0) > 1e-6) return fail("mask_arm_axes_px must be unit vectors");
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
  const StarWidthModel start = StartWidthModel(width_px, height_px, options.psf_fwhm_px / kFwhmPerSigma);
  ProcessBand(b, options, start, &stars, stats);
  JudgeShapes(options, start, &stars, stats);
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
    ProcessBand(b, options, width_model, &stars, stats);
    // Refined band by band: the pair test and the fits' starts use the width expected at each image.
    if (options.max_dash_length_px == 0) width_model = SettleStarWidthModel(stars, width_model, 1);
  }
  JudgeShapes(options, width_model, &stars, stats);
  Finish(3.0 * options.psf_fwhm_px, &stars);  // 3 x: the start width may be 2 x off the images'
  return stars;
}

}  // namespace platemeter
