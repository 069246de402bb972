// A trail grown from one of its separator dashes, for trails whose leading run was not found
// (trail_internal.h). The dash's measured length gives the star's speed (20 s of motion), its
// angle the track's direction, its flux the star's flux per second: the neighbouring exposure's
// image (a dot of known duration at a known time) is then predicted, and the growth does the rest.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "../median.h"
#include "evidence.h"
#include "trail_internal.h"

namespace platemeter::trail_internal {

bool GrowFromSeparator(const Context& c, const Grid& all, int dash, int reference, const PixelPoint* motion,
                       const std::function<bool(int)>& excluded, PatternTrail* out) {
  const TrailOptions& o = c.o;
  const std::vector<ShutterExposure>& ex = c.per_trail[reference];
  const DetectedStar& d = c.images[dash];
  // A blend's flux and length would misread every exposure after it.
  if (d.length_px <= 0 || d.flux_dn <= 0 || (d.flags & kStarBlended)) return false;
  const double a = d.angle_deg * std::numbers::pi / 180.0;
  int found = 0;
  PatternTrail best;
  for (int j = 0; j < static_cast<int>(ex.size()); ++j) {
    if (ex[j].kind != ExposureKind::kDash || ex[j].group == 0) continue;  // separators only
    const double rate = d.length_px / ex[j].duration_s;                 // px/s
    const double flux_per_s = d.flux_dn / ex[j].duration_s;
    if (!Compatible(c, dash, ex[j], {std::cos(a) * rate, std::sin(a) * rate}, 0.0)) continue;  // its length
    for (int dir : {1, -1}) {
      const double ux = dir * std::cos(a), uy = dir * std::sin(a);
      if (motion && ux * motion->x_px + uy * motion->y_px <= 0) continue;  // the sky turns one way
      // The neighbouring exposure (the next one, else the previous) holding exactly one compatible image.
      int nb_exposure = -1, nb_image = -1;
      for (int nb : {j + 1, j - 1}) {
        if (nb < 0 || nb >= static_cast<int>(ex.size())) continue;
        const double dt = ex[nb].mid_s - ex[j].mid_s;
        const PixelPoint q{c.p[dash].x_px + ux * rate * dt, c.p[dash].y_px + uy * rate * dt};
        const double tol = std::max(o.tuning.min_tolerance_px, o.match_tolerance * std::abs(dt) * rate);
        int count = 0, image = -1;
        all.Near(q.x_px, q.y_px, tol, [&](int i) {
          if (i == dash || !c.usable[i] || (excluded && excluded(i)) ||
              !Compatible(c, i, ex[nb], {ux * rate, uy * rate}, flux_per_s))
            return;
          ++count, image = i;
        });
        if (count == 1) {
          nb_exposure = nb, nb_image = image;
          break;
        }
      }
      if (nb_exposure < 0) continue;
      GrowSpec spec;
      spec.exposures = &ex;
      spec.seed = {{std::min(j, nb_exposure), nb_exposure < j ? nb_image : dash},
                   {std::max(j, nb_exposure), nb_exposure < j ? dash : nb_image}};
      spec.flux_per_s = flux_per_s;
      spec.max_missed_in_row = o.tuning.max_missed_in_row;
      spec.excluded = excluded;
      spec.first = std::max(j, nb_exposure) + 1;
      spec.step = 1;
      const Growth later = Grow(c, all, spec);
      spec.seed = later.taken;
      spec.first = std::min(j, nb_exposure) - 1;
      spec.step = -1;
      const Growth both = Grow(c, all, spec);
      if (static_cast<int>(both.taken.size()) < 1 + o.tuning.min_exposures_after_run) continue;
      // The seed's flux must be the trail's: the median flux per second of the other images taken.
      std::vector<double> per_s;
      for (const auto& [k, i] : both.taken)
        if (i != dash) per_s.push_back(c.images[i].flux_dn / ex[k].duration_s);
      std::nth_element(per_s.begin(), per_s.begin() + per_s.size() / 2, per_s.end());
      const double median_per_s = per_s[per_s.size() / 2];
      if (std::abs(flux_per_s - median_per_s) > o.tuning.run_flux_tolerance * median_per_s + 4.0 * d.sigma_flux_dn / ex[j].duration_s)
        continue;
      if (++found > 1) return false;  // two readings of one dash: neither is trusted
      best.taken = both.taken;
      best.flux_per_s = flux_per_s;
    }
  }
  if (found != 1) return false;
  std::sort(best.taken.begin(), best.taken.end());
  *out = best;
  return true;
}

std::pair<double, double> MedianFluxPerSecond(const Context& c, const std::vector<std::pair<int, double>>& image_durations) {
  std::vector<double> rates;
  for (const auto& [i, duration_s] : image_durations) {
    const DetectedStar& d = c.images[i];
    if (IsEvidence(c, i) && d.flux_dn > 0 && !(d.flags & (kStarSaturated | kStarCrowded)))
      rates.push_back(d.flux_dn / duration_s);
  }
  if (static_cast<int>(rates.size()) < kMinFluxImages) return {0.0, 0.0};
  const double median = detect_internal::Median(rates);
  std::vector<double> deviations;
  for (double r : rates) deviations.push_back(std::abs(r - median));
  const double sigma = 1.4826 * detect_internal::Median(deviations) * 1.2533 / std::sqrt(static_cast<double>(rates.size()));
  return {median, sigma};
}

std::pair<double, double> FluxPerSecond(const Context& c, const std::vector<std::pair<int, int>>& images, int t) {
  std::vector<std::pair<int, double>> image_durations;
  for (const auto& [j, i] : images) image_durations.push_back({i, c.per_trail[t][j].duration_s});
  return MedianFluxPerSecond(c, image_durations);
}

bool OtherStarsFlux(const Context& c, const std::vector<std::pair<int, int>>& a, int ta,
                    const std::vector<std::pair<int, int>>& b, int tb) {
  const auto [ra, sa] = FluxPerSecond(c, a, ta);
  const auto [rb, sb] = FluxPerSecond(c, b, tb);
  return ra > 0 && rb > 0 && std::abs(ra - rb) > kStarFluxSpread * std::min(ra, rb) + 4.0 * std::hypot(sa, sb);
}

namespace {

// Whether the trail's run refutes number u: a leading dash it did not take lies inside the format where
// nothing could hold it (a trail of 2 leading dashes read as the last two of 5).
bool RunRefutes(const Context& c, const Grid& all, const Track& track, const std::vector<std::pair<int, int>>& as_u,
                int u, double flux_per_s) {
  const TrailOptions& o = c.o;
  const std::vector<ShutterExposure>& ex = c.per_trail[u];
  const PixelPoint first = c.p[as_u.front().second];
  for (int j = 0; j < static_cast<int>(ex.size()) && ex[j].kind == ExposureKind::kDash && ex[j].group == 0; ++j) {
    if (std::any_of(as_u.begin(), as_u.end(), [&](const std::pair<int, int>& ji) { return ji.first == j; })) continue;
    const PixelPoint q = track.At(ex[j].mid_s);
    if (!Inside(o, q, o.edge_margin_px)) continue;
    const double tol_px = o.tuning.sibling_tolerance_px + o.tuning.sibling_tolerance_fraction * Dist(q, first);
    const PixelPoint v = track.VelocityAt(ex[j].mid_s);
    if (DashPlaceEmpty(c, all, q, v, flux_per_s * ex[j].duration_s, ex[j].duration_s, tol_px)) return true;
  }
  return false;
}

}  // namespace

int NumberBySiblings(const Context& c, const Grid& all, const PatternTrail& pt, int reference,
                     const std::vector<int>& leading_dashes, const std::function<bool(int, int)>& other_number,
                     SiblingGrowth* grown) {
  const TrailOptions& o = c.o;
  const int trails = static_cast<int>(leading_dashes.size());
  // The trail's images re-timed as each trail u (exposure j of the reference is j + N_u - N_ref of trail u).
  struct Reading {
    std::vector<std::pair<int, int>> as_u;
    std::vector<double> ts;
    Track track;
    bool fitted = false, refuted = false;
  };
  std::vector<Reading> readings(trails);
  for (int u = 0; u < trails; ++u) {
    Reading& r = readings[u];
    const int shift = leading_dashes[u] - leading_dashes[reference];
    std::vector<PixelPoint> ps;
    for (const auto& [j, i] : pt.taken)
      if (j + shift >= 0) {
        r.as_u.push_back({j + shift, i});
        r.ts.push_back(c.per_trail[u][j + shift].mid_s);
        ps.push_back(c.p[i]);
      }
    const double span_s = r.ts.empty() ? 0.0 : r.ts.back() - r.ts.front();
    const int degree = DegreeFor(static_cast<int>(r.ts.size()), span_s, o.track_degree);
    r.fitted = r.ts.size() >= 4 && r.track.Fit(r.ts, ps, {}, {}, degree);
    r.refuted = r.fitted && RunRefutes(c, all, r.track, r.as_u, u, pt.flux_per_s);
  }
  // The run tells only where some number's run is there: a trail whose leading dashes are all lost
  // without trace (none of it on the plate) is left to its siblings.
  const bool runs_tell =
      std::any_of(readings.begin(), readings.end(), [](const Reading& r) { return r.fitted && !r.refuted; });
  int best = -1, count = 0;
  for (int u = 0; u < trails; ++u) {
    const Reading& r = readings[u];
    if (!r.fitted || (runs_tell && r.refuted)) continue;
    const std::vector<std::pair<int, int>>& as_u = r.as_u;
    const std::vector<double>& ts = r.ts;
    const Track& track = r.track;
    const PixelPoint v = track.VelocityAt(0.5 * (ts.front() + ts.back()));
    const double rate = std::hypot(v.x_px, v.y_px);
    const double gap_s = trails > 1 ? c.per_trail[1].front().mid_s - c.per_trail[0].back().mid_s : 0.0;
    const double far_tol_px = o.tuning.sibling_tolerance_px + o.tuning.sibling_tolerance_fraction * rate * (gap_s + o.tuning.sibling_window_s);
    if (10.0 * rate < 2.0 * far_tol_px) return -1;
    bool grows = false;
    for (int s : {u - 1, u + 1}) {
      if (s < 0 || s >= trails || grows) continue;
      std::vector<std::pair<int, int>> sibling;
      const Growth g = GrowSibling(c, all, as_u, u, s, pt.flux_per_s, [&](int i) { return other_number(i, s); }, &sibling);
      // (evidence only: a crowded clump offers a piece near almost any prediction)
      if (g.after_run < o.tuning.min_exposures_after_run || EvidenceCount(c, sibling) < o.tuning.min_exposures_after_run) continue;
      // The sibling's own track: its images on it to their precision, and on one arc with the trail's.
      std::vector<double> st;
      std::vector<PixelPoint> sp;
      for (const auto& [j, i] : sibling) st.push_back(c.per_trail[s][j].mid_s), sp.push_back(c.p[i]);
      Track sibling_track;
      if (!sibling_track.Fit(st, sp, {}, {}, DegreeFor(static_cast<int>(st.size()), st.back() - st.front(), o.track_degree)))
        continue;
      std::vector<double> residual_px;
      for (size_t k = 0; k < st.size(); ++k) residual_px.push_back(Dist(sibling_track.At(st[k]), sp[k]));
      std::nth_element(residual_px.begin(), residual_px.begin() + residual_px.size() / 2, residual_px.end());
      if (residual_px[residual_px.size() / 2] > std::max(o.tuning.max_median_residual_px, o.tuning.max_median_residual_fwhm * o.psf_fwhm_px))
        continue;
      if (!(s < u ? OnOneArc(o, sibling_track, st.back(), track, ts.front()) : OnOneArc(o, track, ts.back(), sibling_track, st.front())))
        continue;
      if (OtherStarsFlux(c, pt.taken, reference, sibling, s)) continue;  // another star on the path
      grows = true;
      if (count == 0) *grown = {s, sibling, rate};
    }
    if (grows) best = u, ++count;
  }
  return count == 1 ? best : -1;
}

}  // namespace platemeter::trail_internal
