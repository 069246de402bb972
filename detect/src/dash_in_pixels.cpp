// A dash's thirds fitted where the flow puts it (dash_in_pixels.h).
#include "platemeter/detect/dash_in_pixels.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "median.h"
#include "scan_window.h"
#include "star_internal.h"

namespace platemeter {
namespace {

using star_internal::kFwhmPerSigma;
constexpr double kSigmaPerMad = 1.4826;  // a Gaussian's sigma per median absolute deviation
// A detection with less than this fraction of its light in the window is not modelled (its column would
// be next to zero).
constexpr double kMinLightInWindow = 0.02;

// Whether a detection may hold the dash, merged with other light: centred within on_sweep_fwhm of the sweep,
// and no further from it than such a merge's centre can lie. Another image of a share e of the merge's flux
// merges with the dash only within about a FWHM, so the merge's centre lies within e FWHM of the true sweep
// (and that within the place's tolerance of this one). A detection further off is another star's image, even
// where its light reaches every third (Cairo: another star's dash 1.6 px beside the track, 1.57 times the
// dash's flux, counted as the dash before a run: a trail numbered one too high, 15 wrong tags).
bool MayHoldDash(const DashPlace& dash, const DetectedStar& d, const DashInPixelsOptions& o) {
  const double off_px = detect_internal::ToSweep_px(d.point.position_px, dash.centre_px, dash.angle_rad, dash.length_px);
  const double other_share = std::max(0.0, 1.0 - dash.flux_dn / d.flux_dn);
  return off_px <= std::min(o.on_sweep_fwhm * dash.fwhm_px, other_share * dash.fwhm_px + dash.tolerance_px);
}

// The templates: the sweep's thirds, then every other detection whose light reaches the window (its shape as
// fitted); unit flux each.
std::vector<star_internal::FittedSegment> Templates(const DashPlace& dash, const PixelRect& rect,
                                                    const std::vector<DetectedStar>& images, const DashInPixelsOptions& o) {
  const double c = std::cos(dash.angle_rad), s = std::sin(dash.angle_rad);
  std::vector<star_internal::FittedSegment> templates;
  for (int k = -1; k <= 1; ++k) {
    star_internal::FittedSegment third;
    third.x_px = dash.centre_px.x_px + k * dash.length_px / 3.0 * c;
    third.y_px = dash.centre_px.y_px + k * dash.length_px / 3.0 * s;
    third.angle_rad = dash.angle_rad, third.length_px = dash.length_px / 3.0;
    third.flux_dn = 1.0, third.sigma_px = dash.fwhm_px / kFwhmPerSigma;
    templates.push_back(third);
  }
  for (const DetectedStar& d : images) {
    if (!(d.flux_dn > 0) || !(d.fwhm_px > 0)) continue;
    if (MayHoldDash(dash, d, o)) continue;
    star_internal::FittedSegment m = detect_internal::ModelOf(d);
    // (its light in the window: beyond the window's edge by more than its reach, none)
    const double reach_px = 0.5 * m.length_px + 3.0 * d.fwhm_px;
    if (m.x_px < rect.x0_px - reach_px || m.x_px > rect.x_end_px() + reach_px || m.y_px < rect.y0_px - reach_px ||
        m.y_px > rect.y_end_px() + reach_px)
      continue;
    m.flux_dn = 1.0;
    templates.push_back(m);
  }
  return templates;
}

// The templates' fluxes fitted with a constant background by linear least squares.
struct FluxFit {
  bool ok = false;
  Eigen::MatrixXd unit;              // the design matrix, columns scaled to unit norm: background, templates
  Eigen::VectorXd flux_dn, sigma_dn;  // per column
};

FluxFit FitFluxes(const std::vector<star_internal::FitPixel>& pixels,
                  const std::vector<star_internal::FittedSegment>& templates) {
  FluxFit fit;
  // Each column scaled to unit norm (the background's is larger than a star's by the window's area); a
  // detection with next to none of its light in the window is dropped (its column would be next to zero).
  const long rows = static_cast<long>(pixels.size());
  Eigen::MatrixXd a(rows, 1 + static_cast<long>(templates.size()));
  Eigen::VectorXd b(rows);
  a.col(0).setOnes();
  long cols = 1;
  for (size_t j = 0; j < templates.size(); ++j) {
    double in_window = 0;
    for (long r = 0; r < rows; ++r) {
      const star_internal::FitPixel& px = pixels[static_cast<size_t>(r)];
      a(r, cols) = star_internal::SegmentModel(templates[j], px.x_px, px.y_px);
      in_window += a(r, cols);
    }
    if (j < 3 || in_window >= kMinLightInWindow) ++cols;
  }
  for (long r = 0; r < rows; ++r) b(r) = pixels[static_cast<size_t>(r)].value_dn;
  a.conservativeResize(rows, cols);
  if (rows <= cols + 3) return fit;
  const Eigen::VectorXd scale = a.colwise().norm().transpose();
  if ((scale.array() <= 0).any()) return fit;
  fit.unit = a * scale.cwiseInverse().asDiagonal();
  // The normal equations (a few columns); a singular system (two detections' models alike) fits nothing.
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(fit.unit.transpose() * fit.unit);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.rcond() < 1e-9) return fit;
  fit.flux_dn = ldlt.solve(fit.unit.transpose() * b).cwiseQuotient(scale);
  // The noise from the residuals' median absolute value: light no detection models (a piece of a neighbour
  // merged into the holder) lies in a few pixels and would inflate their mean square over the window.
  const Eigen::VectorXd residual = b - a * fit.flux_dn;
  std::vector<double> absolute(residual.data(), residual.data() + rows);
  for (double& v : absolute) v = std::abs(v);
  const double noise_dn = kSigmaPerMad * detect_internal::Median(absolute) *
                          std::sqrt(static_cast<double>(rows) / static_cast<double>(rows - cols));
  fit.sigma_dn = ldlt.solve(Eigen::MatrixXd::Identity(cols, cols)).diagonal().cwiseMax(0.0).cwiseSqrt().cwiseQuotient(scale) *
                 noise_dn;
  fit.ok = true;
  return fit;
}

}  // namespace

bool ClippedOnSweep(const ScanPixels& scan, const DashPlace& dash, const DetectedStar* own) {
  PixelRect rect;
  std::vector<star_internal::FitPixel> pixels;
  std::vector<PixelPoint> clipped;
  if (!detect_internal::WindowAbout(scan, dash.centre_px, 0.5 * dash.length_px + dash.fwhm_px, &rect) ||
      !detect_internal::ReadContrast(scan, rect, &pixels, &clipped))
    return false;
  // (from `own` towards the place: the sweep's far half lies ahead of its centre)
  const PixelPoint away = own ? PixelPoint{dash.centre_px.x_px - own->point.position_px.x_px,
                                           dash.centre_px.y_px - own->point.position_px.y_px}
                              : PixelPoint{0.0, 0.0};
  return std::any_of(clipped.begin(), clipped.end(), [&](const PixelPoint& q) {
    const double ahead = (q.x_px - dash.centre_px.x_px) * away.x_px + (q.y_px - dash.centre_px.y_px) * away.y_px;
    return ahead >= 0.0 && detect_internal::ToSweep_px(q, dash.centre_px, dash.angle_rad, dash.length_px) <= dash.fwhm_px;
  });
}

DashInPixels MeasureDashInPixels(const ScanPixels& scan, const DashPlace& dash, const std::vector<DetectedStar>& images,
                                 const DashInPixelsOptions& o) {
  DashInPixels out;
  if (!(dash.length_px > 0) || !(dash.fwhm_px > 0) || !(dash.flux_dn > 0)) return out;
  PixelRect rect;
  std::vector<star_internal::FitPixel> pixels;
  std::vector<PixelPoint> clipped;
  if (!detect_internal::WindowAbout(scan, dash.centre_px, 0.5 * dash.length_px + o.window_fwhm * dash.fwhm_px, &rect) ||
      !detect_internal::ReadContrast(scan, rect, &pixels, &clipped))
    return out;
  // (a saturated neighbour's core is left out; light of the dash's own lost there would read as less)
  if (!detect_internal::ClearOfClipped(clipped, dash.centre_px, dash.angle_rad, dash.length_px,
                                       o.clear_of_clipped_fwhm * dash.fwhm_px))
    return out;
  const FluxFit fit = FitFluxes(pixels, Templates(dash, rect, images, o));
  if (!fit.ok) return out;

  // How far a modelled detection could stand in for the dash: the largest cosine between its column and the
  // whole dash's (the thirds summed).
  const long cols = fit.unit.cols();
  const Eigen::VectorXd whole = (fit.unit.col(1) + fit.unit.col(2) + fit.unit.col(3)).normalized();
  for (long j = 4; j < cols; ++j) out.max_overlap = std::max(out.max_overlap, fit.unit.col(j).dot(whole));
  out.modelled = static_cast<int>(cols) - 4;
  const double third_dn = dash.flux_dn / 3.0;
  out.measured = true;
  out.shown = true;
  bool none = true;  // every third within max_absent of no light
  for (int k = 0; k < 3; ++k) {
    out.third_flux_dn[k] = fit.flux_dn(1 + k);
    out.third_sigma_dn[k] = fit.sigma_dn(1 + k);
    none = none && std::abs(out.third_flux_dn[k]) <= o.max_absent * third_dn;
    out.measured = out.measured && out.third_sigma_dn[k] <= o.max_third_sigma * third_dn;
    out.shown = out.shown && out.third_flux_dn[k] >= o.min_third * third_dn && out.third_flux_dn[k] <= o.max_third * third_dn;
  }
  out.shown = out.shown && out.measured;
  out.absent = out.measured && out.max_overlap < o.max_overlap_absent && none;
  return out;
}

}  // namespace platemeter
