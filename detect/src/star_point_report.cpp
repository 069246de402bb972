// Point images of the star detector (star_band.h): the single fit's report, the pair test, and the
// pair tests that wait for the plate's width model.
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "star_band.h"

namespace platemeter::star_internal {
namespace {

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

}  // namespace

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

DetectedStar Defect(double x_px, double y_px, const std::string& why) {
  DetectedStar d;
  d.point.kind = PointKind::kStar;
  d.point.status = PointStatus::kRejected;
  d.point.reason = why;
  d.point.position_px = {x_px, y_px};
  d.flags = kStarDefect;
  return d;
}

// Too wide: 1.12 x the width expected here at an SNR above 30 (a pair 3 px apart widens a single fit
// by more; the width of an SNR-30 image is known to about 5 %); a chi^2 excess: 5 sigmas of its spread.
bool PairTestWanted(const GaussianFitResult& single, double image_sigma_px) {
  const FittedGaussian& g = single.stars[0];
  const int dof = single.pixels - 5;
  const double snr = g.sigma_flux_dn > 0 ? g.flux_dn / g.sigma_flux_dn : 0.0;
  return (g.sigma_px / image_sigma_px > 1.12 && snr > 30) || single.chi2 > dof + 5.0 * std::sqrt(2.0 * dof);
}

// Two starts: a split along the major axis by the excess second moment; the single star plus one at
// the largest residual of the component's own pixels.
bool TryPair(const ComponentPixels& c, const FittedGaussian& start, double image_sigma, double noise, double min_sigma,
             const StarDetectorOptions& o, GaussianFitResult* fit) {
  const std::vector<FitPixel>& pixels = c.pixels;
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
    FittedGaussian a = start, b = start;
    a.x_px = cx + h * axis(0), a.y_px = cy + h * axis(1);
    b.x_px = cx - h * axis(0), b.y_px = cy - h * axis(1);
    a.flux_dn = b.flux_dn = 0.5 * fit->stars[0].flux_dn;
    GaussianFitResult pair = FitGaussians(pixels, {a, b}, noise, min_sigma);
    // Second start: the single fit plus a star at the largest residual of the
    // component (wider pairs, where the single fit sits on the brighter star).
    {
      const GaussianFitResult& f = *fit;
      const FittedGaussian& g = f.stars[0];
      double worst = -1e30;
      FittedGaussian second = start;
      for (size_t i = 0; i < pixels.size(); ++i) {
        if (!c.own[i]) continue;
        const FitPixel& p = pixels[i];
        const double model = f.offset_dn + g.flux_dn * std::exp(-0.5 * (std::pow(p.x_px - g.x_px, 2) + std::pow(p.y_px - g.y_px, 2)) /
                                                                (g.sigma_px * g.sigma_px)) / (2 * M_PI * g.sigma_px * g.sigma_px);
        if (p.value_dn - model > worst) worst = p.value_dn - model, second.x_px = p.x_px, second.y_px = p.y_px;
      }
      second.flux_dn = std::max(worst, 0.0) * 2 * M_PI * image_sigma * image_sigma;
      FittedGaussian first = g;
      first.sigma_px = image_sigma;
      GaussianFitResult alt = FitGaussians(pixels, {first, second}, noise, min_sigma);
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

void ReportPointFits(const GaussianFitResult& fit, bool blended, const std::vector<FitPixel>& pixels,
                     const PointFitPlace& at, const StarDetectorOptions& o, std::vector<DetectedStar>* result) {
  for (const FittedGaussian& g : fit.stars) {
    // Noise first: a fit below the SNR limit is no image at all, not a defect worth a row.
    if (g.flux_dn <= 0 || g.flux_dn < o.min_snr * g.sigma_flux_dn) continue;
    // Width: only the implausible here; the test against the plate's width model at the image's
    // place follows once every band is measured (JudgeShapes).
    // A fit that left its window found no image of its own there (it may have run off to 1e8 px).
    if (g.x_px < at.window.x0 || g.x_px > at.window.x1 || g.y_px < at.window.y0 || g.y_px > at.window.y1) continue;
    if (!WidthPlausible(o, g.sigma_px / at.start_sigma_px)) {
      result->push_back(Defect(g.x_px, g.y_px, "shape"));
      continue;
    }
    DetectedStar d = MeasuredImage(g.x_px, g.y_px, g.sigma_x_px, g.sigma_y_px, g.correlation_xy, g.flux_dn,
                                   g.sigma_flux_dn, at.mesh->LevelAt(g.x_px, g.y_px - at.y0_abs) + at.sign * fit.offset_dn);
    d.peak_dn = g.flux_dn / (2.0 * M_PI * g.sigma_px * g.sigma_px);
    d.fwhm_px = g.sigma_px * kFwhmPerSigma;
    if (!blended) {
      d.ellipticity = Ellipticity(pixels, g.x_px, g.y_px, fit.offset_dn, std::max(g.sigma_px, at.image_sigma_px));
      d.profile_misfit = ProfileMisfit(fit, g, at.noise_dn);
    }
    if (!blended && o.windowed_centroid) {
      const Windowed w = WindowedCentroid(pixels, g.x_px, g.y_px, fit.offset_dn, at.image_sigma_px, fit.residual_sigma_dn);
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

void ResolvePendingPairs(const StarDetectorOptions& o, const StarWidthModel& model, std::vector<PendingPair>* pending,
                         std::vector<DetectedStar>* stars, StarDetectionStats* stats) {
  if (pending->empty()) return;
  std::vector<char> provisional(stars->size(), 0);
  for (const PendingPair& p : *pending) std::fill_n(provisional.begin() + p.first_row, p.row_count, 1);
  size_t kept = 0;
  for (size_t i = 0; i < stars->size(); ++i) {
    if (provisional[i]) continue;
    if (kept != i) (*stars)[kept] = std::move((*stars)[i]);  // no self-move: its strings would be left unspecified
    ++kept;
  }
  stars->resize(kept);
  std::vector<std::vector<DetectedStar>> found(pending->size());
  tbb::parallel_for(size_t{0}, pending->size(), [&](size_t i) {
    PendingPair& p = (*pending)[i];
    const double image_sigma = model.SigmaAt(p.start.x_px, p.start.y_px);
    p.place.image_sigma_px = image_sigma;
    p.start.sigma_px = image_sigma;
    bool blended = false;
    if (PairTestWanted(p.single, image_sigma))
      blended = TryPair(p.component, p.start, image_sigma, p.place.noise_dn, o.min_fwhm_ratio * image_sigma * 0.5, o,
                        &p.single);
    ReportPointFits(p.single, blended, p.component.pixels, p.place, o, &found[i]);
  });
  for (std::vector<DetectedStar>& v : found)
    for (DetectedStar& d : v) {
      if (stats && d.point.status == PointStatus::kRejected) ++stats->defects;
      stars->push_back(std::move(d));
    }
  pending->clear();
}

}  // namespace platemeter::star_internal
