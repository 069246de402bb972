// Step 8 (decoder.h): an image holding more light than its star gives an exposure of its length holds
// another image's too (two images closer than the PSF resolves, measured as one): its position is the
// blend's, not the star's, so it is taken back (kBlended) and the trail's track refitted without it.
#include <algorithm>
#include <map>

#include "decoder.h"
#include "evidence.h"

namespace platemeter::trail_internal {

void TrailDecoder::DropMergedImages() {
  std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) trails_of[Root(k)].push_back(k);
  for (const auto& [root, ks] : trails_of) {
    std::vector<std::pair<int, double>> image_durations;
    for (int k : ks)
      for (const auto& [j, i] : chain_[k].kept)
        image_durations.push_back({i, c_.per_trail[result_.chains[k].trail - 1][j].duration_s});
    // (the median over its tagged images: those that may have lost light, clipped or cut from a crowd, left out)
    const double flux_per_s = MedianFluxPerSecond(c_, image_durations).first;
    if (flux_per_s <= 0) continue;
    for (int k : ks) {
      const std::vector<ShutterExposure>& ex = c_.per_trail[result_.chains[k].trail - 1];
      Taken kept;
      for (const auto& [j, i] : chain_[k].kept) {
        if (HoldsMergedLight(images_[i].flux_dn, images_[i].sigma_flux_dn, flux_per_s * ex[j].duration_s))
          Untag(i, TrailReason::kBlended);
        else
          kept.push_back({j, i});
      }
      if (kept.size() == chain_[k].kept.size()) continue;
      RefitWithout(k, kept);
    }
  }
}

// Chain k keeps `kept` (its other tags taken back): the track refitted to the images it fitted before (the
// flow's images keep their measured positions); refused when too few are left for it.
void TrailDecoder::RefitWithout(int k, const Taken& kept) {
  TrailChain& tc = result_.chains[k];
  if (kept.empty()) {
    Refuse(k, TrailReason::kBlended);
    return;
  }
  Taken tracked;
  for (const auto& [j, i] : kept)
    if (!result_.images[i].flow_checked) tracked.push_back({j, i});
  chain_[k].kept = kept;
  tc.images.clear();
  for (const auto& [j, i] : kept) tc.images.push_back(i);
  std::sort(tc.images.begin(), tc.images.end(),
            [&](int a, int b) { return result_.images[a].mid_s < result_.images[b].mid_s; });
  if (tracked.empty()) {
    RecountMissed(k);
    return;
  }
  tc.bad_images = 0;
  for (const auto& [j, i] : tracked) result_.images[i].bad = false, result_.images[i].reason = TrailReason::kNone;
  if (!FitTrail(c_, tracked, &tc, &result_.images, &chain_[k].track)) {
    Refuse(k, TrailReason::kBlended);
    return;
  }
  RecountMissed(k);
}

}  // namespace platemeter::trail_internal
