// Where a trail may be seen (Inside) and sibling evidence: a trail's track carried across the breaks to
// its neighbours' exposures (trail_internal.h).
#include <algorithm>
#include <cmath>

#include "trail_internal.h"

namespace platemeter::trail_internal {

bool Blind(const TrailOptions& o, const PixelPoint& p, double length_px) {
  return o.blind.Covers(p, 0.5 * length_px + o.psf_fwhm_px);
}

bool Inside(const TrailOptions& o, const PixelPoint& p, double margin_px) {
  if (o.image_max_px.x_px > o.image_min_px.x_px &&
      (p.x_px < o.image_min_px.x_px + margin_px || p.y_px < o.image_min_px.y_px + margin_px ||
       p.x_px > o.image_max_px.x_px - margin_px || p.y_px > o.image_max_px.y_px - margin_px))
    return false;
  // A convex outline of either winding: p on the inner side of every edge, by the margin.
  const std::vector<PixelPoint>& v = o.exposed_outline_px;
  const size_t n = v.size();
  if (n < 3) return true;
  double area2 = 0;
  for (size_t k = 0; k < n; ++k) area2 += v[k].x_px * v[(k + 1) % n].y_px - v[(k + 1) % n].x_px * v[k].y_px;
  const double sign = area2 > 0 ? 1.0 : -1.0;
  for (size_t k = 0; k < n; ++k) {
    const PixelPoint& a = v[k];
    const PixelPoint& b = v[(k + 1) % n];
    const double len = Dist(a, b);
    if (len <= 0) continue;
    const double inside_px = sign * ((b.x_px - a.x_px) * (p.y_px - a.y_px) - (b.y_px - a.y_px) * (p.x_px - a.x_px)) / len;
    if (inside_px < margin_px) return false;
  }
  return true;
}

bool DashPlaceEmpty(const Context& c, const Grid& all, const PixelPoint& q, const PixelPoint& velocity_px_per_s,
                    double dash_flux_dn, double duration_s, double tol_px, bool by_flux,
                    const std::function<bool(int)>& explained) {
  const TrailOptions& o = c.o;
  const double speed = std::hypot(velocity_px_per_s.x_px, velocity_px_per_s.y_px);
  if (!(speed > 0)) return false;
  const double dash_length_px = speed * duration_s;
  if (Blind(o, q, dash_length_px)) return false;
  const double along_px = 0.5 * dash_length_px + 2.0 * o.psf_fwhm_px + tol_px, across_px = 1.5 * o.psf_fwhm_px + tol_px;
  DashHolder holder{dash_flux_dn, dash_length_px};
  holder.by_flux = by_flux;
  ForReaching(c, all, q, along_px, [&](int i) {
    if (explained && explained(i)) return;
    const double dx = c.p[i].x_px - q.x_px, dy = c.p[i].y_px - q.y_px;
    if (IsLine(c.images[i]) || std::abs(dx * velocity_px_per_s.y_px - dy * velocity_px_per_s.x_px) / speed <= across_px)
      holder.Add(c.images[i]);
  });
  return !holder.Holds();
}

bool OnOneArc(const TrailOptions& o, const Track& a, double a1_s, const Track& b, double b0_s) {
  const PixelPoint pa = a.At(b0_s), pb = b.At(b0_s), qa = a.At(a1_s), qb = b.At(a1_s);
  const double tol = o.join_tolerance_px + o.tuning.join_tolerance_fraction * Dist(pa, qa);
  return Dist(pa, pb) <= tol && Dist(qa, qb) <= tol;
}

SiblingEvidence SiblingsOf(const Context& c, const Grid& all, const Track& track, double t0_s, double t1_s, int u,
                           double flux_per_s, const std::function<bool(int)>& own) {
  const TrailOptions& o = c.o;
  const int trails = static_cast<int>(c.per_trail.size());
  SiblingEvidence ev;
  for (int s : {u - 1, u + 1}) {
    if (s < 0 || s >= trails) continue;
    const double te = s < u ? t0_s : t1_s;
    const double gap_s = s < u ? c.per_trail[u].front().mid_s - c.per_trail[s].back().mid_s
                               : c.per_trail[s].front().mid_s - c.per_trail[u].back().mid_s;
    const PixelPoint end = track.At(te);
    for (const ShutterExposure& e : c.per_trail[s]) {
      // Leading dashes are 30 s apart, the shift between adjacent trail numbers: under a wrong number the
      // prediction lands on the sibling's neighbouring dash. They are not evidence.
      if (e.kind == ExposureKind::kDash && e.group == 0) continue;
      if (std::abs(e.mid_s - te) > gap_s + o.tuning.sibling_window_s) continue;
      const PixelPoint q = track.At(e.mid_s);
      if (!Inside(o, q, 0.0)) continue;
      const double tol = o.tuning.sibling_tolerance_px + o.tuning.sibling_tolerance_fraction * Dist(q, end);
      const PixelPoint v = track.VelocityAt(e.mid_s);
      bool hit = false;
      all.Near(q.x_px, q.y_px, tol, [&](int i) {
        if (c.usable[i] && !own(i) && Compatible(c, i, e, v, flux_per_s)) hit = true;
      });
      ev.hits += hit;
    }
  }
  return ev;
}

}  // namespace platemeter::trail_internal
