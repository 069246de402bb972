// Step 4 (decoder.h): the decoded trails joined into stars, and every trail's number confirmed -- by a join,
// by its siblings' images, or by a clean field before its run -- or refused (docs/trails.md, "Numbers").
#include <algorithm>
#include <cmath>

#include "decoder.h"

namespace platemeter::trail_internal {

void TrailDecoder::CheckNumbers() {
  NumberCheck nc = RetimeTracks();
  FindJoins(&nc);
  ConfirmNumbers(&nc);
  const int m = static_cast<int>(result_.chains.size());
  for (int k = 0; k < m; ++k) {
    if (!nc.doubtful[k]) continue;
    const TrailReason reason = result_.chains[k].reason == TrailReason::kNone ? TrailReason::kDoubtfulNumber
                                                                             : result_.chains[k].reason;
    Refuse(k, reason);
  }
  for (const auto& [a, b] : nc.joins) {
    const int ta = result_.chains[a].trail, tb = result_.chains[b].trail;
    if (Decoded(a) && Decoded(b) && nc.partner_count[a][tb] == 1 && nc.partner_count[b][ta] == 1)
      chain_[Root(a)].parent = Root(b);
  }
  for (int k = 0; k < m; ++k)  // the trail numbers each star holds
    if (Decoded(k)) chain_[Root(k)].numbers |= 1u << (result_.chains[k].trail - 1);
}

// Every decoded trail's track under every trail number (its images re-timed: exposure j of a trail with N
// dashes is exposure j + N' - N of one with N').
TrailDecoder::NumberCheck TrailDecoder::RetimeTracks() const {
  const int m = static_cast<int>(result_.chains.size());
  NumberCheck nc;
  nc.retimed.assign(m, std::vector<Retimed>(trails_));
  nc.doubtful.assign(m, false);
  nc.joined.assign(m, false);
  nc.partner_count.assign(m, std::vector<int>(trails_ + 1, 0));
  for (int k = 0; k < m; ++k) {
    if (!Decoded(k)) continue;
    nc.decoded.push_back(k);
    const int t = result_.chains[k].trail - 1;
    for (int u = 0; u < trails_; ++u) {
      Retimed& rt = nc.retimed[k][u];
      if (u == t) {
        rt.ok = true, rt.track = chain_[k].track;
        Ends(k, &rt.t0_s, &rt.t1_s);
        continue;
      }
      const int shift = program_.leading_dashes[u] - program_.leading_dashes[t];
      std::vector<double> ts;
      std::vector<PixelPoint> ps;
      for (const auto& [j, i] : chain_[k].kept) {
        const int jj = j + shift;
        if (jj < 0 || jj >= static_cast<int>(c_.per_trail[u].size())) continue;
        ts.push_back(c_.per_trail[u][jj].mid_s);
        ps.push_back(c_.p[i]);
      }
      if (ts.size() < 4 || !rt.track.Fit(ts, ps, {}, {}, chain_[k].track.degree())) continue;
      rt.ok = true;
      rt.t0_s = *std::min_element(ts.begin(), ts.end()), rt.t1_s = *std::max_element(ts.begin(), ts.end());
    }
  }
  return nc;
}

// Two trails on one arc under numbers other than theirs (a leading dash lost without trace makes trail N+1
// look like trail N): both numbers are doubtful, both trails refused. Under their own numbers: a join. Only
// adjacent numbers are compared (the extrapolation spans one break; trails further apart join through their
// neighbours). Candidates: B's first image (its run's first dash: exposure N_ub - N_tb under number ub) near
// A's track at that exposure's time.
void TrailDecoder::FindJoins(NumberCheck* nc) const {
  const int m = static_cast<int>(result_.chains.size());
  std::vector<PixelPoint> head(m);
  for (int k : nc->decoded) head[k] = c_.p[chain_[k].kept.front().second];
  const Grid heads(head, nc->decoded, 64.0);
  for (int a : nc->decoded) {
    const int ta = result_.chains[a].trail - 1;
    for (int ua = 0; ua + 1 < trails_; ++ua) {
      const int ub = ua + 1;
      const Retimed& ra = nc->retimed[a][ua];
      if (!ra.ok) continue;
      const PixelPoint end = ra.track.At(ra.t1_s);
      for (int tb = 0; tb < trails_; ++tb) {
        const int jj = program_.leading_dashes[ub] - program_.leading_dashes[tb];
        if (jj < 0 || jj >= static_cast<int>(c_.per_trail[ub].size())) continue;
        const PixelPoint q = ra.track.At(c_.per_trail[ub][jj].mid_s);
        heads.Near(q.x_px, q.y_px, 10.0 + 0.05 * Dist(q, end), [&](int b) {
          if (b == a || result_.chains[b].trail - 1 != tb || !nc->retimed[b][ub].ok) return;
          const Retimed& rb = nc->retimed[b][ub];
          if (!OnOneArc(ra.track, ra.t1_s, rb.track, rb.t0_s)) return;
          if (ua == ta && ub == tb) {
            ++nc->partner_count[a][tb + 1], ++nc->partner_count[b][ta + 1];
            nc->joins.push_back({a, b});
          } else {
            nc->doubtful[a] = nc->doubtful[b] = true;
          }
        });
      }
    }
  }
  for (const auto& [a, b] : nc->joins)
    if (!nc->doubtful[a] && !nc->doubtful[b]) nc->joined[a] = nc->joined[b] = true;
}

// Sibling evidence from the raw images (the sibling trails need not be decoded): under its own number a
// trail's track carried to its neighbours' exposures near its ends must find images of the right length
// there; under a wrong number (a lost or a stray leading dash) it lands 30 s x the rate off. Siblings that
// prefer a neighbouring number make it doubtful; a join, or a sibling grown under its number and no other,
// confirms it; else ConfirmedAlone decides.
void TrailDecoder::ConfirmNumbers(NumberCheck* nc) {
  const auto sibling_score = [&](int k, int u) {
    const Retimed& r = nc->retimed[k][u];
    if (!r.ok) return 0;
    return SiblingsOf(c_, *all_, r.track, r.t0_s, r.t1_s, u, chain_[k].flux_per_s,
                      [&](int i) { return result_.images[i].chain == k; }).hits;
  };
  for (int k : nc->decoded) {
    if (nc->doubtful[k]) continue;
    const int t = result_.chains[k].trail - 1;
    const int own = sibling_score(k, t);
    int alt = 0;
    for (int u : {t - 1, t + 1})
      if (u >= 0 && u < trails_) alt = std::max(alt, sibling_score(k, u));
    if (alt >= o_.tuning.min_sibling_images && 2 * alt > own) {
      nc->doubtful[k] = true;  // its siblings say another number
      continue;
    }
    if (nc->joined[k]) continue;
    // Confirmed by a sibling grown from its track (on one arc, well fitted) under its number and no other;
    // single images on sibling exposures (`own`) do not confirm: in a crowded field other stars' images lie
    // within the tolerance of a few of them.
    const int number = NumberBySiblingsOf(k);
    if (number == t) continue;
    if (number >= 0 || !ConfirmedAlone(k)) nc->doubtful[k] = true, nc->joined[k] = false;
  }
  if (o_.require_joined)
    for (int k : nc->decoded)
      if (!nc->doubtful[k] && !nc->joined[k]) nc->doubtful[k] = true, result_.chains[k].reason = TrailReason::kLoneTrail;
}

// An unconfirmed trail is kept only where nothing could have hidden a leading dash before its run (or posed
// as one): no detection, and the pixels (where given) showing neither a dash nor a saturated core there;
// else its reason says what left the number in doubt.
bool TrailDecoder::ConfirmedAlone(int k) {
  const ChainState& cs = chain_[k];
  DashHolder holder{cs.dash_flux_dn, cs.dash_length_px};
  ForReaching(c_, *all_, cs.before_px, o_.tuning.clean_radius_spacings * cs.spacing_px, [&](int i) {
    if (result_.images[i].chain != k) holder.Add(images_[i]);
  });
  DashPlace before;
  before.centre_px = cs.before_px;
  before.angle_rad = cs.run_angle_rad;
  before.length_px = cs.dash_length_px;
  before.fwhm_px = o_.psf_fwhm_px;
  before.flux_dn = cs.dash_flux_dn;
  before.tolerance_px = o_.tuning.min_tolerance_px;
  const DetectedStar* first_dash = cs.first_dash_image >= 0 ? &images_[cs.first_dash_image] : nullptr;
  const bool clean = !holder.Holds() && !PixelsMayHoldDash(c_, *all_, before, first_dash);
  // A slow star's 10 s gaps (a third of the spacing) within the PSF: its dashes merge, a lost one leaves no
  // trace in front of the run.
  const bool unresolved = cs.spacing_px / 3.0 < o_.psf_fwhm_px;
  // A run holding a merged dash may be two stars' runs end to end (one star's last dashes on the other's first
  // ones, on one diurnal path): its count is no trail's.
  if (clean && !cs.before_occupied && !cs.run_merged && !unresolved) return true;
  result_.chains[k].reason = cs.before_occupied ? TrailReason::kImageBeforeRun
                             : cs.run_merged    ? TrailReason::kBlended
                             : unresolved       ? TrailReason::kUnresolvedRun
                                                : TrailReason::kUnconfirmed;
  return false;
}

}  // namespace platemeter::trail_internal
