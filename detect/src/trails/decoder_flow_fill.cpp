// Step 7's last part (decoder.h): exposures still without an image filled along the plate's flow, each
// image found there tagged at its measured position (docs/trails.md, "The plate's flow").
#include <algorithm>
#include <cmath>

#include "decoder.h"
#include "evidence.h"

namespace platemeter::trail_internal {

// An exposure's place along the flow (q, carried from origin): exactly one image (assigned or not) within the
// flow's tolerance, unassigned, refused by no check but a track's (kUnlinked, kUnverified, or kOffTrack: more
// than tight_tolerance_px off a track fitted among other stars' images -- then within that of the place: the
// flow from a trail's end predicts what its track does, and the image its own track dropped must not come
// back), compatible (length, flux) and no piece shared in a clump; -1 otherwise.
int TrailDecoder::FlowPlaceImage(const FlowPath& path, double dt_s, const PixelPoint& origin,
                                 const ShutterExposure& e, double flux_per_s) const {
  const PixelPoint q = path.At(dt_s);
  const double tol_px = FlowTolerance_px(o_, q, origin);
  int near = 0, i = -1;
  all_->Near(q.x_px, q.y_px, tol_px, [&](int other) {
    if (c_.usable[other]) ++near, i = other;
  });
  if (near != 1) return -1;
  const TrailReason why = result_.images[i].reason;  // (unassigned, and refused by no check but a track's)
  const bool shared = (images_[i].flags & kStarCrowded) && (images_[i].flags & kStarBlended);
  const bool off_track = why == TrailReason::kOffTrack && Dist(c_.p[i], q) <= o_.tuning.tight_tolerance_px;
  if ((why != TrailReason::kUnlinked && why != TrailReason::kUnverified && !off_track) || shared ||
      !Compatible(c_, i, e, path.VelocityAt(dt_s), flux_per_s))
    return -1;
  return i;
}

// Image i tagged as exposure je of chain k, found along the flow at q: its measured position and sigmas (the
// fit's weights: FitSigmaOf).
void TrailDecoder::TagFlowChecked(int k, int je, int i, const PixelPoint& q) {
  Untag(i, TrailReason::kNone);
  Tag(k, je, i);
  TrailImage& ti = result_.images[i];
  ti.flow_checked = true;
  ti.residual_x_px = c_.p[i].x_px - q.x_px, ti.residual_y_px = c_.p[i].y_px - q.y_px;
  ti.residual_px = Dist(c_.p[i], q);
  ti.refined_px = c_.p[i];
  const FitSigma sigma = FitSigmaOf(o_, images_[i]);
  ti.sigma_refined_x_px = sigma.x_px, ti.sigma_refined_y_px = sigma.y_px;
  Taken& kept = chain_[k].kept;
  kept.push_back({je, i});
  std::sort(kept.begin(), kept.end());
  std::vector<int>& chain_images = result_.chains[k].images;
  chain_images.push_back(i);
  std::sort(chain_images.begin(), chain_images.end(),
            [&](int a, int b) { return result_.images[a].mid_s < result_.images[b].mid_s; });
}

void TrailDecoder::RecountMissed(int k) {
  const Taken& kept = chain_[k].kept;
  const auto [lo, hi] = std::minmax_element(kept.begin(), kept.end());
  result_.chains[k].missed_exposures = hi->first - lo->first + 1 - static_cast<int>(kept.size());
}

// Each decoded trail's exposures without an image, filled along the flow: carried from the trail's image
// nearest in time (the track there), an exposure's place must hold one image as FlowPlaceImage says. Such
// images lie beyond the growth's reach (after exposures missed in a row, where a crossing star took the
// trail's images) or beyond the track's (a long gap at its end: kUnverified); the flow checks them. In a gap
// inside the trail only an image nothing refused (kUnlinked) within tight_tolerance_px of the track (the flow
// alone took a dash merged with a crossing star's there: 1 wrong tag).
void TrailDecoder::FillTrailsAlongFlow() {
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k) {
    if (!Decoded(k)) continue;
    const std::vector<ShutterExposure>& ex = c_.per_trail[result_.chains[k].trail - 1];
    const Taken& kept = chain_[k].kept;
    const auto [first_it, last_it] = std::minmax_element(kept.begin(), kept.end());
    const int first = first_it->first, last = last_it->first;
    for (int je = 0; je < static_cast<int>(ex.size()); ++je) {
      const bool inside = je >= first && je <= last;
      const auto held = [&](const std::pair<int, int>& ji) { return ji.first == je; };
      if (inside && std::any_of(kept.begin(), kept.end(), held)) continue;
      const ShutterExposure& e = ex[je];
      int nearest = -1;
      for (const auto& [j, other] : kept)  // (the track's own images: it reaches them)
        if (!result_.images[other].bad && !result_.images[other].flow_checked &&
            (nearest < 0 || std::abs(ex[j].mid_s - e.mid_s) < std::abs(ex[nearest].mid_s - e.mid_s)))
          nearest = j;
      if (nearest < 0) break;
      const double dt_s = e.mid_s - ex[nearest].mid_s;
      const PixelPoint origin = chain_[k].track.At(ex[nearest].mid_s);
      const FlowPath path(flow_, origin, std::abs(dt_s) + 30.0);
      if (!path.Covers(dt_s)) continue;
      const int i = FlowPlaceImage(path, dt_s, origin, e, chain_[k].flux_per_s);
      // (a gap inside: the track knows the place too; an image it or a crowd check refused stays out)
      if (i < 0 || (inside && (result_.images[i].reason != TrailReason::kUnlinked ||
                               Dist(c_.p[i], chain_[k].track.At(e.mid_s)) > o_.tuning.tight_tolerance_px)))
        continue;
      TagFlowChecked(k, je, i, path.At(dt_s));
    }
    RecountMissed(k);
  }
}

// A decoded star's trails still missing (too few images for a track of their own, or refused by its fit among
// other stars' images): each exposure's place carried along the flow from the end of the star's trail nearest
// in time, filled as above. At least kSiblingFillImages of them, of two exposure lengths (or
// kSiblingFillOneDuration of one), make the trail. An exposure whose neighbours' places lie within two
// tolerances of its own (a slow star) is skipped; a place holding an image tagged with that trail number (the
// trail decoded as another star's) leaves the trail alone.
void TrailDecoder::FillMissingSiblings() {
  ForMissingTrails([&](int root, int s, int k, double t_end_s, const PixelPoint& origin) {
    const std::vector<ShutterExposure>& ex = c_.per_trail[s];
    const double reach_s = std::max(std::abs(ex.front().mid_s - t_end_s), std::abs(ex.back().mid_s - t_end_s));
    const FlowPath path(flow_, origin, reach_s + 30.0);
    Taken found;
    std::vector<PixelPoint> places;
    for (int je = 0; je < static_cast<int>(ex.size()); ++je) {
      const double dt_s = ex[je].mid_s - t_end_s;
      if (!path.Covers(dt_s)) continue;
      const PixelPoint q = path.At(dt_s);
      const double tol_px = FlowTolerance_px(o_, q, origin);
      // (the trail decoded as another star's: not filled twice)
      bool decoded_there = false;
      all_->Near(q.x_px, q.y_px, tol_px, [&](int other) {
        decoded_there = decoded_there || (result_.images[other].assigned && result_.images[other].trail == s + 1);
      });
      if (decoded_there) return;
      bool apart = true;  // (from the neighbouring exposures' places)
      for (int jn : {je - 1, je + 1})
        if (jn >= 0 && jn < static_cast<int>(ex.size()) && path.Covers(ex[jn].mid_s - t_end_s))
          apart = apart && Dist(path.At(ex[jn].mid_s - t_end_s), q) > 2.0 * tol_px;
      const int i = apart ? FlowPlaceImage(path, dt_s, origin, ex[je], chain_[k].flux_per_s) : -1;
      const auto taken = [&](const std::pair<int, int>& ji) { return ji.second == i; };
      if (i < 0 || std::any_of(found.begin(), found.end(), taken)) continue;
      found.push_back({je, i});
      places.push_back(q);
    }
    std::vector<double> durations_s;  // (a chance image at each place would rarely fit two exposure lengths)
    for (const auto& [je, i] : found) durations_s.push_back(ex[je].duration_s);
    const int n = static_cast<int>(found.size());
    if (n < kSiblingFillImages || (DistinctCount(durations_s) < 2 && n < kSiblingFillOneDuration)) return;
    const PixelPoint v = flow_.Velocity(origin);
    // (no track of its own: its images are the flow's) joined to the star
    const int cid = OpenChain(TrailStep::kFlowFill, s, chain_[k].flux_per_s, std::hypot(v.x_px, v.y_px));
    Unite(cid, Root(root));
    for (size_t n = 0; n < found.size(); ++n) TagFlowChecked(cid, found[n].first, found[n].second, places[n]);
    RecountMissed(cid);
  });
}

}  // namespace platemeter::trail_internal
