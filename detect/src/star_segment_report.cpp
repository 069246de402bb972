// Trail-mode images of the star detector (star_band.h): a component's sweep and its segment fit.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "star_band.h"

namespace platemeter::star_internal {

// The second moments of the component's own positive-contrast pixels: a uniform sweep of length L adds
// L^2 / 12 along its direction.
SweepMoments ComponentSweep(const ComponentPixels& c) {
  const std::vector<FitPixel>& pixels = c.pixels;
  SweepMoments m;
  double s = 0, sx = 0, sy = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const FitPixel& p = pixels[i];
    if (p.value_dn > 0 && c.own[i]) s += p.value_dn, sx += p.value_dn * p.x_px, sy += p.value_dn * p.y_px;
  }
  if (s <= 0) return m;
  m.x = sx / s, m.y = sy / s, m.flux_dn = s;
  double sxx = 0, syy = 0, sxy = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const FitPixel& p = pixels[i];
    if (p.value_dn > 0 && c.own[i]) {
      const double dx = p.x_px - m.x, dy = p.y_px - m.y;
      sxx += p.value_dn * dx * dx, syy += p.value_dn * dy * dy, sxy += p.value_dn * dx * dy;
    }
  }
  Eigen::Matrix2d moments;
  moments << sxx / s, sxy / s, sxy / s, syy / s;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(moments);
  m.angle_rad = std::atan2(eig.eigenvectors()(1, 1), eig.eigenvectors()(0, 1));
  m.length_px = std::sqrt(12.0 * std::max(0.0, eig.eigenvalues()(1) - eig.eigenvalues()(0)));
  return m;
}

void MeasureSegment(const SweepMoments& m, const ComponentPixels& c, double noise, double psf_sigma, bool truncated,
                    const StarDetectorOptions& o, const BackgroundMesh& mesh, long y0_abs, double sign,
                    const Box& window, std::vector<DetectedStar>* result) {
  const std::vector<FitPixel>& pixels = c.pixels;
  FittedSegment start;
  start.x_px = m.x, start.y_px = m.y, start.angle_rad = m.angle_rad, start.length_px = m.length_px;
  start.flux_dn = m.flux_dn, start.sigma_px = psf_sigma;
  SegmentFitResult fit = FitSegment(pixels, start, noise);
  if (!fit.ok) return;
  // A faint image on the segment's wing (the first dot, 10 s after the last leading dash): the
  // largest residual clearly off the segment starts a joint fit, kept when chi^2 drops by 25.
  {
    const FittedSegment& g = fit.segment;
    const double se = std::sqrt(g.sigma_px * g.sigma_px + 1.0 / 12.0);
    const double cs = std::cos(g.angle_rad), sn = std::sin(g.angle_rad);
    auto off_segment = [&](double x, double y) {
      const double du = x - g.x_px, dv = y - g.y_px;
      const double a = std::abs(du * cs + dv * sn) - 0.5 * g.length_px, b = std::abs(-du * sn + dv * cs);
      return std::hypot(std::max(a, 0.0), b) > 2.0 * se;
    };
    double worst = 0;
    FittedPoint point;
    for (const FitPixel& p : pixels) {
      const double r = p.value_dn - fit.offset_dn - SegmentModel(g, p.x_px, p.y_px);
      if (r > worst && off_segment(p.x_px, p.y_px)) worst = r, point.x_px = p.x_px, point.y_px = p.y_px;
    }
    if (worst > 3.0 * noise) {
      point.flux_dn = worst * 2.0 * M_PI * se * se;
      SegmentFitResult joint = FitSegmentAndPoint(pixels, g, point, noise);
      if (joint.ok && fit.chi2 - joint.chi2 > 25.0 && joint.point.flux_dn > o.min_snr * joint.point.sigma_flux_dn &&
          off_segment(joint.point.x_px, joint.point.y_px) && joint.point.x_px > window.x0 &&
          joint.point.x_px < window.x1 && joint.point.y_px > window.y0 && joint.point.y_px < window.y1)
        fit = std::move(joint);
    }
  }
  const FittedSegment& g = fit.segment;
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
  if (c.clipped > 0) d.flags |= kStarSaturated;
  if (truncated) d.flags |= kStarTruncated;
  if (d.ellipticity > o.max_ellipticity && g.length_px > 3.0 * g.sigma_length_px) d.flags |= kStarElongated;
  if (fit.has_point) {
    const FittedPoint& q = fit.point;
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

}  // namespace platemeter::star_internal
