// A decoded trail's missing dots measured at its track's prediction (trail_forced.h).
#include "platemeter/detect/trail_forced.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/parallel_for.h>

#include "platemeter/core/error.h"
#include "../median.h"
#include "../scan_window.h"
#include "../star_internal.h"
#include "trail_internal.h"

namespace platemeter {
namespace {

using detect_internal::Median;
using detect_internal::ModelOf;

using trail_internal::Dist;
using trail_internal::Grid;
using trail_internal::Track;

using star_internal::kFwhmPerSigma;

// Pixels this near a clipped pixel (in FWHM) are not fitted: the saturated image's wings there are not in
// its model (fitted to a clipped core), and its light falls off over about one FWHM.
constexpr double kClippedMaskFwhm = 1.5;

// Distance from p to the segment of an image (its sweep: length_px along angle_deg about its centre).
double ToSweep(const PixelPoint& p, const DetectedStar& d) {
  return detect_internal::ToSweep_px(p, d.point.position_px, d.angle_deg * std::numbers::pi / 180.0, d.length_px);
}

// The exposure an assigned image was tagged as.
const ShutterExposure* ExposureOf(const std::vector<ShutterExposure>& trail, const TrailImage& t) {
  for (const ShutterExposure& e : trail)
    if (e.kind == t.kind && (t.kind == ExposureKind::kDot ? e.dot_index == t.dot_index : e.dash_index == t.dash_index))
      return &e;
  return nullptr;
}

// One dot to try: where the track puts it.
struct ForcedCandidate {
  int chain = 0;
  const ShutterExposure* exposure = nullptr;
  PixelPoint predicted;
  double sigma_predicted_px = 0.0;  // radial
  double length_px = 0.0, angle_rad = 0.0, fwhm_px = 0.0, expected_flux_dn = 0.0;
  std::vector<star_internal::FittedSegment> neighbours;  // the detected images whose light reaches its window
  int replaces = -1;  // the unassigned detection at the place, re-measured
};

// What one trail offers: its track and its images' flux per second and width.
struct TrailModel {
  Track track;
  double t0_s = 0, t1_s = 0, flux_per_s = 0, fwhm_px = 0;
  std::vector<bool> has_dot;  // by dot index (1-based)
};

bool BuildModel(const std::vector<DetectedStar>& images, const TrailLinkResult& linked, int k,
                const std::vector<ShutterExposure>& trail, const TrailOptions& to, int min_images, TrailModel* m) {
  std::vector<double> t_s, sx, sy, flux_per_s, fwhm;
  std::vector<PixelPoint> p;
  m->has_dot.assign(trail.size() + 1, false);
  for (int i : linked.chains[k].images) {
    const TrailImage& ti = linked.images[i];
    if (!ti.assigned || ti.chain != k) continue;
    if (ti.kind == ExposureKind::kDot) m->has_dot[ti.dot_index] = true;
    if (ti.bad) continue;
    const DetectedStar& d = images[i];
    const ShutterExposure* e = ExposureOf(trail, ti);
    if (!e) continue;
    t_s.push_back(ti.mid_s);
    p.push_back(d.point.position_px);
    sx.push_back(std::hypot(d.point.sigma_x_px, to.position_floor_px));
    sy.push_back(std::hypot(d.point.sigma_y_px, to.position_floor_px));
    if (d.flux_dn > 0) flux_per_s.push_back(d.flux_dn / e->duration_s);
    if (d.fwhm_px > 0) fwhm.push_back(d.fwhm_px);
  }
  if (static_cast<int>(t_s.size()) < min_images || flux_per_s.empty()) return false;
  if (!m->track.Fit(t_s, p, sx, sy, to.track_degree)) return false;
  m->t0_s = *std::min_element(t_s.begin(), t_s.end());
  m->t1_s = *std::max_element(t_s.begin(), t_s.end());
  m->flux_per_s = Median(flux_per_s);
  m->fwhm_px = fwhm.empty() ? to.psf_fwhm_px : Median(fwhm);
  return true;
}

enum class Outcome { kMeasured, kOutside, kCrowded, kClipped, kFailed, kFaint, kOffPlace, kOffFlux };

// A dot fitted at its prediction and the background under it (DN, as stored).
struct MeasuredDot {
  Outcome outcome = Outcome::kFailed;
  star_internal::FittedSegment segment;
  double background_dn = 0.0;
};

MeasuredDot Refused(Outcome why) {
  MeasuredDot m;
  m.outcome = why;
  return m;
}

// Fits the dot at its prediction (outcome kMeasured: it is there).
MeasuredDot MeasureDot(const ScanPixels& scan, const ForcedCandidate& c, const ForcedDotOptions& o) {
  const double half_px = 0.5 * c.length_px + o.window_fwhm * c.fwhm_px;
  PixelRect rect;
  if (!detect_internal::WindowAbout(scan, c.predicted, half_px, &rect)) return Refused(Outcome::kOutside);
  std::vector<star_internal::FitPixel> pixels;
  std::vector<PixelPoint> clipped;
  detect_internal::ReadContrast(scan, rect, &pixels, &clipped);
  // A saturated neighbour: its clipped pixels hold no measurement, and its model (fitted to a clipped core)
  // not its wings' light. The dot is measured only where such pixels lie in the window's corners, beyond the
  // window's inscribed circle about its sweep, and without the pixels within kClippedMaskFwhm of them (the
  // benchmark plate: +16 dots right, nothing wrong, RMS(error / sigma) unchanged; refused at any clipped
  // pixel before).
  if (!detect_internal::ClearOfClipped(clipped, c.predicted, c.angle_rad, c.length_px, o.window_fwhm * c.fwhm_px))
    return Refused(Outcome::kClipped);
  std::erase_if(pixels, [&](const star_internal::FitPixel& px) {
    return std::any_of(clipped.begin(), clipped.end(), [&](const PixelPoint& q) {
      return std::hypot(px.x_px - q.x_px, px.y_px - q.y_px) < kClippedMaskFwhm * c.fwhm_px;
    });
  });
  // The neighbours' light (their fitted models) taken off; the background: the window's median (the dot
  // covers a small part of it), then fitted.
  std::vector<double> contrast;
  contrast.reserve(pixels.size());
  for (star_internal::FitPixel& px : pixels) {
    for (const star_internal::FittedSegment& n : c.neighbours)
      px.value_dn -= static_cast<float>(star_internal::SegmentModel(n, px.x_px, px.y_px));
    contrast.push_back(px.value_dn);
  }
  const double level = Median(contrast);
  for (auto& px : pixels) px.value_dn = static_cast<float>(px.value_dn - level);
  star_internal::FittedSegment start;
  start.x_px = c.predicted.x_px, start.y_px = c.predicted.y_px;
  start.angle_rad = c.angle_rad, start.length_px = c.length_px;
  start.sigma_px = c.fwhm_px / kFwhmPerSigma;
  start.flux_dn = c.expected_flux_dn;
  // (noise 1 DN: only the chi^2 uses it; the sigmas come from the fit's own residual variance)
  const star_internal::SegmentFitResult fit = star_internal::FitPlacedSegment(pixels, start, 1.0);
  const star_internal::FittedSegment& s = fit.segment;
  if (!fit.ok || !fit.converged || !(s.sigma_flux_dn > 0)) {
    return Refused(Outcome::kFailed);
  }
  if (s.flux_dn < o.min_snr * s.sigma_flux_dn) {
    return Refused(Outcome::kFaint);
  }
  const double offset_px = Dist({s.x_px, s.y_px}, c.predicted);
  const double sigma_px = std::sqrt(s.sigma_x_px * s.sigma_x_px + s.sigma_y_px * s.sigma_y_px +
                                    c.sigma_predicted_px * c.sigma_predicted_px);
  if (offset_px > o.max_offset_px || offset_px > o.max_offset_sigma * sigma_px) {
    return Refused(Outcome::kOffPlace);
  }
  if (std::abs(s.flux_dn - c.expected_flux_dn) > o.flux_tolerance * c.expected_flux_dn + 3.0 * s.sigma_flux_dn) {
    return Refused(Outcome::kOffFlux);
  }
  const double sign = scan.dark ? -1.0 : 1.0;  // (the background as stored)
  return MeasuredDot{Outcome::kMeasured, s, sign * (level + fit.offset_dn)};
}

// The measured dot as a detection (id F000001, ...; `index`: those before it) tagged as its exposure of the
// candidate's trail, at its measured position, its residual the prediction's.
ForcedDot ForcedDotOf(const ForcedCandidate& c, const MeasuredDot& m, const TrailLinkResult& linked,
                      const TrailOptions& trail_options, size_t index) {
  const star_internal::FittedSegment& s = m.segment;
  ForcedDot f;
  DetectedStar& d = f.image;
  d.point.id = fmt::format("F{:06d}", index + 1);
  d.point.kind = PointKind::kStar;
  d.point.status = PointStatus::kMeasured;
  d.point.position_px = {s.x_px, s.y_px};
  d.point.sigma_x_px = s.sigma_x_px, d.point.sigma_y_px = s.sigma_y_px;
  d.point.correlation_xy = s.correlation_xy;
  d.flux_dn = s.flux_dn, d.sigma_flux_dn = s.sigma_flux_dn;
  d.snr = s.flux_dn / s.sigma_flux_dn;
  d.background_dn = m.background_dn;
  d.fwhm_px = c.fwhm_px;
  d.length_px = c.length_px;
  d.angle_deg = std::remainder(c.angle_rad, std::numbers::pi) * 180.0 / std::numbers::pi;
  const double sigma_psf = c.fwhm_px / kFwhmPerSigma;
  d.ellipticity = 1.0 - sigma_psf / std::sqrt(sigma_psf * sigma_psf + c.length_px * c.length_px / 12.0);
  d.peak_dn = s.flux_dn / (std::sqrt(2.0 * std::numbers::pi) * sigma_psf) *
              std::erf(0.5 * c.length_px / (std::numbers::sqrt2 * sigma_psf)) / std::max(c.length_px, 1e-9);
  f.replaces = c.replaces;
  TrailImage& t = f.tag;
  const ShutterExposure& e = *c.exposure;
  t.chain = c.chain;
  t.star = linked.chains[c.chain].star;
  t.assigned = true;
  t.forced = true;
  t.trail = e.trail;
  t.kind = ExposureKind::kDot;
  t.dot_index = e.dot_index;
  t.mid_s = e.mid_s;
  t.refined_px = d.point.position_px;
  t.residual_x_px = s.x_px - c.predicted.x_px, t.residual_y_px = s.y_px - c.predicted.y_px;
  t.residual_px = std::hypot(t.residual_x_px, t.residual_y_px);
  t.sigma_refined_x_px = std::hypot(s.sigma_x_px, trail_options.position_floor_px);
  t.sigma_refined_y_px = std::hypot(s.sigma_y_px, trail_options.position_floor_px);
  return f;
}

}  // namespace

bool ForcedDotOptions::Check(std::string* why) const {
  auto fail = [&](const char* w) {
    if (why) *why = w;
    return false;
  };
  if (!(min_snr > 0)) return fail("min_snr must be > 0");
  if (!(max_offset_px > 0) || !(max_offset_sigma > 0)) return fail("max_offset_px and max_offset_sigma must be > 0");
  if (!(flux_tolerance >= 0)) return fail("flux_tolerance must be >= 0");
  if (!(isolation_fwhm >= 0) || !(window_fwhm > 0)) return fail("isolation_fwhm must be >= 0, window_fwhm > 0");
  if (!(max_extrapolation_s >= 0) || !(max_prediction_sigma_px > 0))
    return fail("max_extrapolation_s must be >= 0, max_prediction_sigma_px > 0");
  if (min_trail_images < 5) return fail("min_trail_images must be >= 5 (a cubic track and its check)");
  return true;
}

std::vector<ForcedDot> MeasureMissingDots(const ScanPixels& scan, const std::vector<DetectedStar>& images,
                                          const TrailLinkResult& linked, const DutyCycleScheduleOptions& program,
                                          const TrailOptions& trail_options, const ForcedDotOptions& o,
                                          ForcedDotStats* stats_out) {
  std::string why;
  if (!o.Check(&why)) throw Error("forced dot options", why);
  ForcedDotStats stats;
  std::vector<ForcedDot> out;
  if (!o.enabled || linked.images.size() != images.size()) {
    if (stats_out) *stats_out = stats;
    return out;
  }
  const std::vector<ShutterExposure> schedule = BuildShutterSchedule(program);
  std::vector<std::vector<ShutterExposure>> per_trail(program.leading_dashes.size());
  for (const ShutterExposure& e : schedule) per_trail[e.trail - 1].push_back(e);

  // Every image (rejected ones too: a defect's light is not the dot's) and the longest sweep among them.
  std::vector<PixelPoint> p;
  std::vector<int> ids, lines;  // (rejected lines reach as far as their boxes: LineReaches)
  double longest_px = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    p.push_back(images[i].point.position_px);
    if (trail_internal::IsLine(images[i])) {
      lines.push_back(static_cast<int>(i));
      continue;
    }
    ids.push_back(static_cast<int>(i));
    longest_px = std::max(longest_px, images[i].length_px);
  }
  const Grid all(p, ids, 32.0);

  std::vector<ForcedCandidate> candidates;
  for (int k = 0; k < static_cast<int>(linked.chains.size()); ++k) {
    const TrailChain& chain = linked.chains[k];
    if (chain.trail <= 0 || chain.decoded_by == TrailStep::kFlowFill) continue;
    const std::vector<ShutterExposure>& trail = per_trail[chain.trail - 1];
    TrailModel m;
    if (!BuildModel(images, linked, k, trail, trail_options, o.min_trail_images, &m)) continue;
    for (const ShutterExposure& e : trail) {
      if (e.kind != ExposureKind::kDot) continue;
      const double beyond_s = std::max(m.t0_s - e.mid_s, e.mid_s - m.t1_s);
      if (m.has_dot[e.dot_index] || beyond_s > o.max_extrapolation_s) continue;
      ForcedCandidate c;
      c.chain = k, c.exposure = &e;
      c.predicted = m.track.At(e.mid_s);
      double sx = 0, sy = 0;
      m.track.SigmaAt(e.mid_s, &sx, &sy);
      c.sigma_predicted_px = std::hypot(sx, sy);
      // Beyond the trail's images the track is carried: only as far as it stays sure.
      if (beyond_s > 0 && c.sigma_predicted_px > o.max_prediction_sigma_px) continue;
      const PixelPoint v = m.track.VelocityAt(e.mid_s);
      c.length_px = e.duration_s * std::hypot(v.x_px, v.y_px);
      c.angle_rad = std::atan2(v.y_px, v.x_px);
      c.fwhm_px = m.fwhm_px;
      c.expected_flux_dn = m.flux_per_s * e.duration_s;
      ++stats.tried;
      const double reach_px = 0.5 * c.length_px + o.isolation_fwhm * c.fwhm_px;
      if (!trail_internal::Inside(trail_options, c.predicted, reach_px)) {
        ++stats.outside;
        continue;
      }
      // The images within reach: none, or (remeasure) one the linker left unassigned right at the place.
      std::vector<int> within;
      all.Near(c.predicted.x_px, c.predicted.y_px, reach_px + 0.5 * longest_px, [&](int j) {
        if (ToSweep(c.predicted, images[j]) <= reach_px) within.push_back(j);
      });
      bool crowded = !within.empty();
      if (o.remeasure && within.size() == 1) {
        const int j = within.front();
        const TrailImage& tj = linked.images[j];
        if (!tj.assigned && tj.reason != TrailReason::kContested && images[j].flux_dn > 0 &&
            Dist(images[j].point.position_px, c.predicted) <= o.remeasure_radius_px)
          c.replaces = j, crowded = false;
      }
      for (int j : lines) crowded = crowded || trail_internal::LineReaches(images[j], c.predicted, reach_px);
      const double window_px = 0.5 * c.length_px + o.window_fwhm * c.fwhm_px;
      all.Near(c.predicted.x_px, c.predicted.y_px, 1.5 * window_px + 0.5 * longest_px + 3.0 * c.fwhm_px, [&](int j) {
        if (j != c.replaces && images[j].flux_dn > 0 && images[j].fwhm_px > 0) c.neighbours.push_back(ModelOf(images[j]));
      });
      if (crowded) {
        ++stats.crowded;
        continue;
      }
      candidates.push_back(c);
    }
  }
  // Two trails' predicted dots near each other (crossing trails): neither is measured.
  std::vector<PixelPoint> cp;
  std::vector<int> cids;
  for (const ForcedCandidate& c : candidates) cids.push_back(static_cast<int>(cp.size())), cp.push_back(c.predicted);
  const Grid predicted(cp, cids, 32.0);
  std::vector<bool> near_other(candidates.size(), false);
  for (size_t a = 0; a < candidates.size(); ++a) {
    const ForcedCandidate& c = candidates[a];
    const double reach_px = c.length_px + o.isolation_fwhm * c.fwhm_px;
    predicted.Near(c.predicted.x_px, c.predicted.y_px, reach_px, [&](int b) {
      if (b != static_cast<int>(a)) near_other[a] = true;
    });
  }

  // The fits (independent: in parallel; the scan's reads are thread-safe), then their tally in order.
  std::vector<MeasuredDot> measured(candidates.size());
  tbb::parallel_for(size_t{0}, candidates.size(), [&](size_t a) {
    measured[a] = near_other[a] ? Refused(Outcome::kCrowded) : MeasureDot(scan, candidates[a], o);
  });
  for (size_t a = 0; a < candidates.size(); ++a) {
    const ForcedCandidate& c = candidates[a];
    const MeasuredDot& m = measured[a];
    switch (m.outcome) {
      case Outcome::kOutside: ++stats.outside; continue;
      case Outcome::kCrowded: ++stats.crowded; continue;
      case Outcome::kClipped: ++stats.clipped; continue;
      case Outcome::kFailed: ++stats.failed; continue;
      case Outcome::kFaint: ++stats.faint; continue;
      case Outcome::kOffPlace: ++stats.off_place; continue;
      case Outcome::kOffFlux: ++stats.off_flux; continue;
      case Outcome::kMeasured: break;
    }
    out.push_back(ForcedDotOf(c, m, linked, trail_options, out.size()));
    ++stats.measured;
  }
  if (stats_out) *stats_out = stats;
  return out;
}

}  // namespace platemeter
