// A reading's predicted dash places, counted (trail_internal.h; docs/trails.md "Empty dash places"): where a
// reading of a star puts its dashes, and how many of those places the plate shows empty. A right reading's
// places hold its dashes except where a crowd hides one; a wrong reading's lie where the star was not
// exposed for a dash, and many are empty.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "evidence.h"
#include "trail_internal.h"

namespace platemeter::trail_internal {

namespace {

// Whether an image much brighter than a dash of dash_flux_dn reaches near q (within its half length plus
// PlaceReach_px): its light (wings, clipped pixels, the deblender's share) hides or halves the dash there,
// so the place says nothing either way.
bool Dominated(const Context& c, const Grid& all, const PixelPoint& q, double dash_flux_dn, double dash_length_px) {
  const double fwhm_px = c.o.psf_fwhm_px;
  bool dominated = false;
  all.Near(q.x_px, q.y_px, DominatedReach_px(fwhm_px, 1e9) + dash_length_px, [&](int i) {
    const DetectedStar& d = c.images[i];
    const double ratio = d.flux_dn / dash_flux_dn;
    if (dominated || !(ratio >= kDominatingRatio)) return;
    const double a_rad = d.angle_deg * M_PI / 180.0, half_px = 0.5 * d.length_px;
    const double dx = c.p[i].x_px - q.x_px, dy = c.p[i].y_px - q.y_px;
    const double along_px = std::clamp(-(dx * std::cos(a_rad) + dy * std::sin(a_rad)), -half_px, half_px);
    dominated = std::hypot(dx + along_px * std::cos(a_rad), dy + along_px * std::sin(a_rad)) <=
                DominatedReach_px(fwhm_px, ratio);
  });
  return dominated;
}

}  // namespace

DashPlaces CountDashPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                           int s, double flux_per_s, const std::function<int(int)>& trail_of) {
  const TrailOptions& o = c.o;
  DashPlaces places;
  for (const ShutterExposure& e : c.per_trail[s]) {
    if (e.kind != ExposureKind::kDash) continue;
    const double dt = e.mid_s - seed_s;
    if (!path.Covers(dt)) continue;
    const PixelPoint q = path.At(dt), v = path.VelocityAt(dt);
    if (!Inside(o, q, o.edge_margin_px)) continue;
    const double dash_flux_dn = flux_per_s * e.duration_s;
    if (Dominated(c, all, q, dash_flux_dn, std::hypot(v.x_px, v.y_px) * e.duration_s)) continue;
    ++places.inside;
    // Only where trail s was exposed: another star's image of it tagged nearby (a cloud or a shutter fault
    // during one trail empties its places on every star).
    bool exposed = false;
    all.Near(q.x_px, q.y_px, kExposedRadius_px, [&](int i) { exposed = exposed || trail_of(i) == s + 1; });
    const double tol_px = FlowTolerance_px(o, q, p);
    // (An image tagged as another trail number of another star, whose flux leaves no room for this dash,
    // holds none of it; one tagged with trail s may be the star's own.)
    const auto explained = [&](int i) {
      return trail_of(i) > 0 && trail_of(i) != s + 1 && CannotHideDash(c, i, dash_flux_dn);
    };
    places.empty += exposed && DashPlaceEmpty(c, all, q, v, dash_flux_dn, e.duration_s, tol_px, true, explained);
  }
  return places;
}

DashPlaces ReadingPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                         double flux_per_s, const std::function<int(int)>& trail_of) {
  DashPlaces sum;
  for (int s = 0; s < static_cast<int>(c.per_trail.size()); ++s) {
    const DashPlaces places = CountDashPlaces(c, all, path, p, seed_s, s, flux_per_s, trail_of);
    sum.inside += places.inside, sum.empty += places.empty;
  }
  return sum;
}

double FaintestDashRate(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken,
                        double flux_per_s) {
  double rate = flux_per_s;
  for (size_t t = 0; t < taken.size(); ++t)
    for (const auto& [j, i] : taken[t])
      if (c.per_trail[t][j].kind == ExposureKind::kDash && IsEvidence(c, i) && c.images[i].flux_dn > 0)
        rate = std::min(rate, c.images[i].flux_dn / c.per_trail[t][j].duration_s);
  return rate;
}

double EmptyPlacesLogOdds(const DashPlaces& places) {
  const int held = places.inside - places.empty;
  return places.empty * std::log(kEmptyWhenWrong / kEmptyWhenRight) +
         held * std::log((1.0 - kEmptyWhenWrong) / (1.0 - kEmptyWhenRight));
}

}  // namespace platemeter::trail_internal
