// Step 5 (decoder.h): siblings grown from the decoded trails. A trail whose own run was not found (its
// leading dashes merged with crossing images, its first dots lost) is grown from its decoded neighbour's
// track carried across the break: its number is the neighbour's +-1, its exposures' times are known, and every
// image must lie within the sibling tolerance of the prediction (trail_grow.cpp). The grown trail passes
// Settle and must join its neighbour; it then seeds the next sibling (docs/trails.md, "Siblings").
#include "decoder.h"

namespace platemeter::trail_internal {

void TrailDecoder::GrowSiblings() {
  std::vector<int> frontier;
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) frontier.push_back(k);
  while (!frontier.empty()) {
    std::vector<int> next;
    for (int k : frontier) {
      const int t = result_.chains[k].trail - 1;
      for (int s : {t - 1, t + 1}) {
        if (!Decoded(k) || s < 0 || s >= trails_ || (chain_[Root(k)].numbers >> s & 1)) continue;
        Taken taken;  // exposures of trail s
        const Growth g = GrowSibling(c_, *all_, chain_[k].kept, t, s, chain_[k].flux_per_s,
                                     [&](int i) { return Excluded(i); }, &taken);
        if (g.after_run < o_.tuning.min_exposures_after_run) continue;
        const int cid = static_cast<int>(result_.chains.size());
        if (!AddChain(TrailStep::kSibling, s, taken, chain_[k].flux_per_s, g.rate_px_per_s, g.missed)) continue;
        // It must join k: each track carried to the other's end lands on it.
        double k0 = 0, k1 = 0, n0 = 0, n1 = 0;
        Ends(k, &k0, &k1);
        Ends(cid, &n0, &n1);
        const Track &tk = chain_[k].track, &tn = chain_[cid].track;
        if (!(s < t ? OnOneArc(tn, n1, tk, k0) : OnOneArc(tk, k1, tn, n0))) {
          Refuse(cid, TrailReason::kUnjoined);
          continue;
        }
        Unite(cid, Root(k));
        next.push_back(cid);
      }
    }
    frontier = next;
  }
}

}  // namespace platemeter::trail_internal
