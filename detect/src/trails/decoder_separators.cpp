// Step 6 (decoder.h): trails with no run found and no decoded sibling, grown from an unassigned dash read as
// each separator (trail_pattern.cpp), then numbered by their siblings' raw images: the track under trail
// number u carried across the breaks must grow a sibling under exactly one number (trail_pattern.cpp,
// NumberBySiblings). A slow star (10 s of motion, the offset of a wrong number, within twice the tolerance)
// is not numbered (docs/trails.md, "Separators").
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "decoder.h"

namespace platemeter::trail_internal {

void TrailDecoder::SeparatorTrails() {
  std::vector<int> seeds;
  for (int i : dash_ids_)
    if (result_.images[i].chain < 0) seeds.push_back(i);
  std::sort(seeds.begin(), seeds.end(), [&](int x, int y) { return images_[x].flux_dn > images_[y].flux_dn; });
  const auto excluded = [&](int i) { return Excluded(i); };
  // The local direction of motion: the decoded trails' velocities near a point, when at least two agree
  // (within ~25 deg of their mean).
  std::vector<PixelPoint> mid_of(result_.chains.size()), heading(result_.chains.size());
  std::vector<int> moving;
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k) {
    if (!Decoded(k)) continue;
    double t0 = 0, t1 = 0;
    Ends(k, &t0, &t1);
    const PixelPoint v = chain_[k].track.VelocityAt(0.5 * (t0 + t1));
    const double speed = std::hypot(v.x_px, v.y_px);
    if (speed <= 0) continue;
    mid_of[k] = chain_[k].track.At(0.5 * (t0 + t1));
    heading[k] = {v.x_px / speed, v.y_px / speed};
    moving.push_back(k);
  }
  const Grid mids(mid_of, moving, o_.tuning.motion_radius_px);
  const auto motion_at = [&](const PixelPoint& p, PixelPoint* unit) {
    double sx = 0, sy = 0;
    int n = 0;
    mids.Near(p.x_px, p.y_px, o_.tuning.motion_radius_px, [&](int k) { sx += heading[k].x_px, sy += heading[k].y_px, ++n; });
    const double len = std::hypot(sx, sy);
    if (n < 2 || len < 0.9 * n) return false;
    *unit = {sx / len, sy / len};
    return true;
  };
  for (int dash : seeds) {
    if (result_.images[dash].chain >= 0) continue;
    PatternTrail pt;
    PixelPoint unit;
    const bool known = motion_at(c_.p[dash], &unit);
    if (!GrowFromSeparator(c_, *all_, dash, reference_, known ? &unit : nullptr, excluded, &pt)) continue;
    SiblingGrowth grown;
    const int best = NumberOf(pt, &grown);
    if (best < 0) continue;
    const int shift = program_.leading_dashes[best] - program_.leading_dashes[reference_];
    Taken taken;
    for (const auto& [j, i] : pt.taken)
      if (j + shift >= 0) taken.push_back({j + shift, i});
    const int cid = static_cast<int>(result_.chains.size());
    if (AddChain(TrailStep::kSeparators, best, taken, pt.flux_per_s, grown.rate_px_per_s, 0))
      JoinSeparatorTrail(cid, best, grown);
  }
}

// A separator trail's sibling's images taken by a decoded trail of that number: the two join when they lie
// on one arc.
void TrailDecoder::JoinSeparatorTrail(int cid, int number, const SiblingGrowth& grown) {
  std::unordered_map<int, int> votes;
  for (const auto& [j, i] : grown.images)
    if (result_.images[i].chain >= 0) ++votes[result_.images[i].chain];
  for (const auto& [k, n] : votes) {
    if (2 * n < static_cast<int>(grown.images.size()) || !Decoded(k) || (chain_[Root(k)].numbers >> number & 1)) continue;
    double k0 = 0, k1 = 0, n0 = 0, n1 = 0;
    Ends(k, &k0, &k1);
    Ends(cid, &n0, &n1);
    const Track &tk = chain_[k].track, &tn = chain_[cid].track;
    if (grown.sibling < number ? OnOneArc(tk, k1, tn, n0) : OnOneArc(tn, n1, tk, k0)) {
      const int root = Root(k);
      Unite(Root(cid), root);
    }
  }
}

}  // namespace platemeter::trail_internal
