// Growth of a trail along its predicted track, exposure by exposure (trail_internal.h).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "trail_internal.h"

namespace platemeter::trail_internal {

int DegreeFor(int n, double span_s, int max_degree) {
  int d = 1;
  if (n >= 6 && span_s > 150) d = 2;
  if (n >= 12 && span_s > 500) d = 3;
  return std::min(d, max_degree);
}

bool Compatible(const Context& c, int i, const ShutterExposure& e, const PixelPoint& velocity_px_per_s, double flux_per_s) {
  const double rate_px_per_s = std::hypot(velocity_px_per_s.x_px, velocity_px_per_s.y_px);
  if (flux_per_s > 0) {
    const double expect = flux_per_s * e.duration_s;
    if (std::abs(c.images[i].flux_dn - expect) > c.o.flux_tolerance * expect + 4.0 * c.images[i].sigma_flux_dn)
      return false;
  }
  if (c.use_lengths) {
    const double expect = e.duration_s * rate_px_per_s;
    const double tol = c.o.tuning.dash_length_tolerance * expect + c.o.psf_fwhm_px + 3.0 * c.images[i].sigma_length_px;
    // (whole V <= 8 plate: +110 dots right with point images taken as short dashes)
    const bool point_fits = c.images[i].length_px <= 0 && PointMayBeSwept(c.o, expect);
    if (!point_fits && std::abs(c.images[i].length_px - expect) > tol) return false;
    // A segment of two FWHM or more lies along the track (a crossing star's dash does not).
    if (c.images[i].length_px >= 2.0 * c.o.psf_fwhm_px && rate_px_per_s > 0) {
      const double track_deg = std::atan2(velocity_px_per_s.y_px, velocity_px_per_s.x_px) * 180.0 / std::numbers::pi;
      const double off_deg = std::abs(std::remainder(c.images[i].angle_deg - track_deg, 180.0));
      if (off_deg > c.o.tuning.max_run_bend_deg) return false;
    }
    return true;
  }
  return !(c.elongated[i] && e.duration_s < c.o.tuning.min_elongated_exposure_s);
}

Growth Grow(const Context& c, const Grid& all, const GrowSpec& spec) {
  const std::vector<ShutterExposure>& ex = *spec.exposures;
  const TrailOptions& o = c.o;
  Growth g;
  g.taken = spec.seed;
  // Images taken so far (a trail takes at most ~35: a short list, not a flag per input image).
  std::vector<int> used;
  for (const auto& [j, i] : spec.seed) used.push_back(i);
  auto is_used = [&used](int i) { return std::find(used.begin(), used.end(), i) != used.end(); };
  auto taken_t = [&](size_t k) { return ex[g.taken[k].first].mid_s; };
  Track track;
  std::vector<double> ts;
  std::vector<PixelPoint> ps;
  int missed_in_row = 0, last_new = -1;
  const int n = static_cast<int>(ex.size());
  for (int j = spec.first; j >= 0 && j < n; j += spec.step) {
    // The images within the window (all of them for a trail grown from its run).
    ts.clear(), ps.clear();
    size_t nearest_k = 0;
    for (size_t k = 0; k < g.taken.size(); ++k) {
      if (std::abs(taken_t(k) - ex[j].mid_s) > spec.window_s) continue;
      ts.push_back(taken_t(k)), ps.push_back(c.p[g.taken[k].second]);
      if (std::abs(taken_t(k) - ex[j].mid_s) < std::abs(taken_t(nearest_k) - ex[j].mid_s)) nearest_k = k;
    }
    if (ts.size() < 2) break;
    const auto [lo, hi] = std::minmax_element(ts.begin(), ts.end());
    int degree = DegreeFor(static_cast<int>(ts.size()), *hi - *lo, o.track_degree);
    // Far beyond the images (across a break) a cubic's end wanders: a parabola carries the arc further.
    if (spec.extrapolated && std::min(std::abs(ex[j].mid_s - *lo), std::abs(ex[j].mid_s - *hi)) > 0.2 * (*hi - *lo) &&
        (ex[j].mid_s < *lo || ex[j].mid_s > *hi))
      degree = std::min(degree, 2);
    if (!track.Fit(ts, ps, {}, {}, degree)) break;
    const PixelPoint v = track.VelocityAt(ex[j].mid_s);
    const double rate = std::hypot(v.x_px, v.y_px);
    // The smaller spacing to the neighbouring exposures (the previous one in the growth direction first).
    const int prev = j - spec.step, next = j + spec.step;
    double spacing_s = 1e300;
    if (prev >= 0 && prev < n) spacing_s = std::abs(ex[j].mid_s - ex[prev].mid_s);
    if (next >= 0 && next < n) spacing_s = std::min(spacing_s, std::abs(ex[next].mid_s - ex[j].mid_s));
    double tol = std::max(o.tuning.min_tolerance_px, o.match_tolerance * spacing_s * rate);
    const PixelPoint q = track.At(ex[j].mid_s);
    if (spec.extrapolated)
      tol = std::min(tol, o.tuning.sibling_tolerance_px + o.tuning.sibling_tolerance_fraction * Dist(q, c.p[g.taken[nearest_k].second]));
    int found = -1, count = 0;
    double nearest = 1e300, second = 1e300;
    all.Near(q.x_px, q.y_px, tol, [&](int i) {
      if (!c.usable[i] || is_used(i) || (spec.excluded && spec.excluded(i)) ||
          !Compatible(c, i, ex[j], v, spec.flux_per_s))
        return;
      const double d = Dist(c.p[i], q);
      if (d < nearest) second = nearest, nearest = d, found = i;
      else second = std::min(second, d);
      ++count;
    });
    // Once the track is established its prediction is far better than `tol`: an image off it by more
    // than the prediction allows, with other images around (a crowded field), may be another star's
    // (this trail's own image missing or merged): not taken. Several candidates (a crossing trail):
    // the nearest is taken when it lies within that limit and every other beyond three times it.
    double limit = 1e300;
    if (ts.size() >= 8) {
      double ss = 0;
      for (size_t k = 0; k < ts.size(); ++k) ss += std::pow(Dist(track.At(ts[k]), ps[k]), 2);
      const double rms = std::sqrt(ss / ts.size());
      double sx = 0, sy = 0;
      track.SigmaAt(ex[j].mid_s, &sx, &sy);
      const double chi = std::sqrt(track.reduced_chi2());
      const double sigma_pred = std::hypot(sx, sy) * (chi < 1 ? chi : 1.0);
      limit = std::max(o.tuning.tight_tolerance_px, 5.0 * std::hypot(sigma_pred, rms));
      // Across a break the track's model error, not its formal sigma, limits the first predictions.
      if (spec.extrapolated && g.after_run < 3) limit = std::max(limit, tol);
      if (count > 1 && nearest <= limit && second > 3.0 * limit) count = 1;
    }
    if (count == 1 && nearest > o.tuning.tight_tolerance_px && nearest > limit) {
      bool crowded = false;
      all.Near(c.p[found].x_px, c.p[found].y_px, 2.5 * o.psf_fwhm_px,
               [&](int i) { crowded = crowded || (i != found && !is_used(i)); });
      if (crowded) count = 0;
    }
    if (count != 1) {  // nothing (a missing image), or a stray beside it: the exposure stays untaken
      if (++missed_in_row > spec.max_missed_in_row) break;
      continue;
    }
    missed_in_row = 0;
    used.push_back(found);
    g.taken.push_back({j, found});
    last_new = j;
    ++g.after_run;
  }
  // Exposures past the last one taken are not missing (the trail may leave the scan).
  if (last_new >= 0) g.missed = std::abs(last_new - spec.first) + 1 - g.after_run;
  std::vector<double> all_t;
  std::vector<PixelPoint> all_p;
  for (size_t k = 0; k < g.taken.size(); ++k) all_t.push_back(taken_t(k)), all_p.push_back(c.p[g.taken[k].second]);
  // The speed at the growing end (linear fit).
  if (track.Fit(all_t, all_p, {}, {}, 1)) {
    const PixelPoint end_v = track.VelocityAt(ex[g.taken.back().first].mid_s);
    g.rate_px_per_s = std::hypot(end_v.x_px, end_v.y_px);
  }
  return g;
}

Growth GrowSibling(const Context& c, const Grid& all, const std::vector<std::pair<int, int>>& images, int t, int s,
                   double flux_per_s, const std::function<bool(int)>& excluded, std::vector<std::pair<int, int>>* taken) {
  // Trails t and s as one exposure sequence; the trail's images seed it at their place.
  const bool earlier = s < t;
  std::vector<ShutterExposure> ex = c.per_trail[earlier ? s : t];
  ex.insert(ex.end(), c.per_trail[earlier ? t : s].begin(), c.per_trail[earlier ? t : s].end());
  const int offset = earlier ? static_cast<int>(c.per_trail[s].size()) : 0;
  GrowSpec spec;
  spec.exposures = &ex;
  for (const auto& [j, i] : images) spec.seed.push_back({j + offset, i});
  spec.first = earlier ? offset - 1 : static_cast<int>(c.per_trail[t].size());
  spec.step = earlier ? -1 : 1;
  spec.flux_per_s = flux_per_s;
  spec.max_missed_in_row = c.o.tuning.max_missed_in_row;
  spec.window_s = c.o.tuning.sibling_growth_window_s;
  spec.extrapolated = true;
  spec.excluded = excluded;
  const Growth g = Grow(c, all, spec);
  taken->clear();
  for (size_t q = spec.seed.size(); q < g.taken.size(); ++q) {
    const auto [j, i] = g.taken[q];
    taken->push_back({earlier ? j : j - static_cast<int>(c.per_trail[t].size()), i});
  }
  std::sort(taken->begin(), taken->end());
  return g;
}

}  // namespace platemeter::trail_internal
