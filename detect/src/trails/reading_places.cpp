// A reading's predicted places, counted (trail_internal.h; docs/trails.md "Empty places"): where a reading of
// a star puts its dashes and its bright dots, and how many of those places the plate shows empty. A right
// reading's places hold its images except where a crowd hides one; a wrong reading's lie where the star was
// not exposed so (a dot for a dash, a dash or the break for a dot), and many are empty.
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

// Exposure e of trail s predicted along `path` (the seed at p at seed_s), counted in *places as DashPlaces
// (trail_internal.h) says: whether it lies inside, and whether it is empty.
void CountPlace(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s, int s,
                const ShutterExposure& e, double flux_per_s, const TagOf& tag_of,
                DashPlaces* places) {
  const TrailOptions& o = c.o;
  const double dt = e.mid_s - seed_s;
  if (!path.Covers(dt)) return;
  const PixelPoint q = path.At(dt), v = path.VelocityAt(dt);
  if (!Inside(o, q, o.edge_margin_px)) return;
  const double image_flux_dn = flux_per_s * e.duration_s;
  const double length_px = std::hypot(v.x_px, v.y_px) * e.duration_s;
  if (Dominated(c, all, q, image_flux_dn, length_px) || Blind(o, q, length_px)) return;
  const bool dash = e.kind == ExposureKind::kDash;
  ++(dash ? places->inside : places->dot_inside);
  // Only where trail s was exposed: another star's image of it tagged nearby (a cloud or a shutter fault
  // during one trail empties its places on every star).
  bool exposed = false;
  all.Near(q.x_px, q.y_px, kExposedRadius_px, [&](int i) { exposed = exposed || tag_of(i).trail == s + 1; });
  const double tol_px = FlowTolerance_px(o, q, p);
  // (An image tagged as another exposure of another star, whose flux leaves no room for this image, holds
  // none of it; one tagged with this very exposure may be the star's own, decoded as another star's. The
  // same star read one group off has its images tagged with other exposures: they do not hold its places.)
  const auto explained = [&](int i) {
    const ImageTag tag = tag_of(i);
    return tag.trail > 0 && !(tag.trail == s + 1 && std::abs(tag.mid_s - e.mid_s) < kSameExposure_s) &&
           CannotHideDash(c, i, image_flux_dn);
  };
  const bool empty = exposed && DashPlaceEmpty(c, all, q, v, image_flux_dn, e.duration_s, tol_px, true, explained);
  (dash ? places->empty : places->dot_empty) += empty;
}

}  // namespace

DashPlaces CountDashPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                           int s, double flux_per_s, const TagOf& tag_of) {
  DashPlaces places;
  for (const ShutterExposure& e : c.per_trail[s])
    if (e.kind == ExposureKind::kDash) CountPlace(c, all, path, p, seed_s, s, e, flux_per_s, tag_of, &places);
  return places;
}

DashPlaces ReadingPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                         double flux_per_s, double min_dot_flux_dn, const TagOf& tag_of, int max_empty) {
  DashPlaces places;
  for (int s = 0; s < static_cast<int>(c.per_trail.size()); ++s)
    for (const ShutterExposure& e : c.per_trail[s]) {
      if (e.kind == ExposureKind::kDash || flux_per_s * e.duration_s >= min_dot_flux_dn)
        CountPlace(c, all, path, p, seed_s, s, e, flux_per_s, tag_of, &places);
      if (places.empty + places.dot_empty > max_empty) return places;
    }
  return places;
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

bool OtherReadingLikelier(const DashPlaces& own, const DashPlaces& other) {
  const int fewer_empty = own.empty + own.dot_empty - other.empty - other.dot_empty;
  const bool as_many_places = other.inside + other.dot_inside >= own.inside + own.dot_inside;
  return (as_many_places || EmptyPlacesLogOdds(own) > 0.0) &&
         fewer_empty * std::log(kEmptyWhenWrong / kEmptyWhenRight) >= std::log(kRefuteOdds) - 1e-9;
}

double EmptyPlacesLogOdds(const DashPlaces& places) {
  const int empty = places.empty + places.dot_empty;
  const int held = places.inside + places.dot_inside - empty;
  return empty * std::log(kEmptyWhenWrong / kEmptyWhenRight) +
         held * std::log((1.0 - kEmptyWhenWrong) / (1.0 - kEmptyWhenRight));
}

}  // namespace platemeter::trail_internal
