// Step 3 (decoder.h): a trail's images tagged, its sidereal fit (final_fit.cpp), and the crowded-field checks
// every trail of every step passes (docs/trails.md, "Crowded fields").
#include <algorithm>
#include <cmath>

#include "../median.h"
#include "decoder.h"
#include "evidence.h"

namespace platemeter::trail_internal {

namespace {

// The median residual of a trail's good (not bad) images; 0 when none.
double MedianGoodResidual_px(const std::vector<TrailImage>& tags, const std::vector<std::pair<int, int>>& kept,
                             bool* any) {
  std::vector<double> res;
  for (const auto& [j, i] : kept)
    if (!tags[i].bad) res.push_back(tags[i].residual_px);
  *any = !res.empty();
  if (res.empty()) return 0.0;
  std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
  return res[res.size() / 2];
}

}  // namespace

// Chain cid's images (exposure, image) tagged and fitted; false: refused, its tags taken back. An image two
// runs grew over (a crossing) is neither's. A trail must keep min_images (0: its leading dashes + half of
// min_exposures_after_run).
bool TrailDecoder::Settle(int cid, const Taken& taken, int min_images) {
  TrailChain& tc = result_.chains[cid];
  if (min_images <= 0) min_images = tc.leading_dashes + o_.tuning.min_exposures_after_run / 2;
  Taken& kept = chain_[cid].kept;
  kept.clear();
  tc.images.clear();
  for (const auto& [j, i] : taken) {
    if (owner_count_[i] > 1) {
      result_.images[i].reason = TrailReason::kContested;
      continue;
    }
    kept.push_back({j, i});
    tc.images.push_back(i);
    Tag(cid, j, i);
  }
  // (a trail left with too few images after the contested ones is refused)
  if (static_cast<int>(kept.size()) < min_images || !FitTrail(c_, kept, &tc, &result_.images, &chain_[cid].track)) {
    Refuse(cid, TrailReason::kContested);
    return false;
  }
  // Another star's images taken along the way (a crowded field) leave the track off most of them; a trail's
  // own images sit on it to their measuring precision.
  bool any = false;
  const double median_residual_px = MedianGoodResidual_px(result_.images, kept, &any);
  const double limit_px = std::max(o_.tuning.max_median_residual_px, o_.tuning.max_median_residual_fwhm * o_.psf_fwhm_px);
  if (!any || median_residual_px > limit_px) {
    Refuse(cid, TrailReason::kPoorTrack);
    return false;
  }
  Taken checked = kept;
  if (!DropUnverifiable(cid, &checked, median_residual_px, min_images)) return false;
  kept = checked;
  if (o_.ablation.two_stars && TwoStarsOnOnePath(cid)) {
    Refuse(cid, TrailReason::kBlended);
    return false;
  }
  return true;
}

// Whether trail cid's dots hold two stars' light: two stars on one diurnal path a fixed time apart merge at
// every exposure, and one swept PSF fitted to the pair is longer than the exposure's sweep by about their
// offset. Each dot's measured length (the detector's free-length fit) against the sweep its track predicts,
// over dots whose sweep is a FWHM or longer (shorter ones are measured as points): the median excess in px
// and in the dots' own sigmas (evidence.h, kTwoStar*).
bool TrailDecoder::TwoStarsOnOnePath(int cid) const {
  const TrailChain& tc = result_.chains[cid];
  std::vector<double> excess_px, excess_sigmas;
  for (const auto& [j, i] : chain_[cid].kept) {
    const ShutterExposure& e = c_.per_trail[tc.trail - 1][j];
    const DetectedStar& d = images_[i];
    if (e.kind != ExposureKind::kDot || result_.images[i].bad || !(d.length_px > 0) || !(d.sigma_length_px > 0))
      continue;
    const PixelPoint v = chain_[cid].track.VelocityAt(e.mid_s);
    const double sweep_px = e.duration_s * std::hypot(v.x_px, v.y_px);
    if (sweep_px < kTwoStarMinSweepFwhm * o_.psf_fwhm_px) continue;
    excess_px.push_back(d.length_px - sweep_px);
    excess_sigmas.push_back((d.length_px - sweep_px) / d.sigma_length_px);
  }
  if (static_cast<int>(excess_px.size()) < kTwoStarDots) return false;
  return detect_internal::Median(excess_px) > kTwoStarExcessFwhm * o_.psf_fwhm_px &&
         detect_internal::Median(excess_sigmas) > kTwoStarExcessSigmas;
}

// A bad image, or one off the track by more than tight_tolerance_px, with other images around it is likely
// another star's (a crowded field): not tagged (kOffTrack). Alone, it is the trail's own displaced image:
// tagged, flagged bad. An image the track merely follows (leverage above max_leverage: beyond a long gap at
// the trail's end) cannot be checked: not tagged (kUnverified; the plate's flow may check it, step 7). A
// flow trail's such images still count towards min_images: the flow found each at its predicted place (its
// track keeps kMinFlowTrackImages of its own). Repeated on the refitted track until nothing more is dropped
// (3 passes at most); false: refused.
bool TrailDecoder::DropUnverifiable(int cid, Taken* kept, double median_residual_px, int min_images) {
  TrailChain& tc = result_.chains[cid];
  // A piece of a crowded clump fitted jointly with a neighbour (blended and crowded) may carry part of the
  // neighbour's position (two dots 2 px apart, measured 1.5 px off the right one), and two such at a trail's
  // end pull the track onto themselves: each must lie on the track of the trail's other images (within 3
  // median residuals and 0.1 px, that track known there to a third of it); else it cannot be checked.
  const auto shared = [&](int i) { return (images_[i].flags & kStarCrowded) && (images_[i].flags & kStarBlended); };
  const bool flow_trail = tc.decoded_by == TrailStep::kFlow;
  int unverified = 0;  // dropped only because the track merely follows them
  for (int pass = 0; pass < 3; ++pass) {
    if (pass > 0) {  // the residuals of the refitted track
      bool any = false;
      median_residual_px = MedianGoodResidual_px(result_.images, *kept, &any);
    }
    bool dropped = false;
    Track own;
    const bool any_shared =
        std::any_of(kept->begin(), kept->end(), [&](const std::pair<int, int>& ji) { return shared(ji.second); });
    const bool own_fitted =
        any_shared && FitTrackOf(
                          c_, *kept, [&](int i) { return result_.images[i].mid_s; },
                          [&](int i) { return !shared(i) && !result_.images[i].bad; }, 6, &own);
    Taken good;
    tc.images.clear();
    for (const auto& [j, i] : *kept) {
      const TrailImage& ti = result_.images[i];
      if (shared(i) && !ti.bad) {
        bool on_own = false;
        if (own_fitted) {
          double sx = 0, sy = 0;
          own.SigmaAt(ti.mid_s, &sx, &sy);
          const double limit_px = std::max(0.1, 3.0 * median_residual_px);
          on_own = 3.0 * std::hypot(sx, sy) <= limit_px && Dist(own.At(ti.mid_s), c_.p[i]) <= limit_px;
        }
        if (!on_own) {
          Untag(i, own_fitted ? TrailReason::kOffTrack : TrailReason::kUnverified);
          dropped = true;
          continue;
        }
      }
      // (an image the detector split from a neighbour, `blended`: off the track already beyond 3 median
      // residuals of the trail, 3.5 sigma, and 0.1 px)
      const bool split = (images_[i].flags & kStarBlended) != 0;
      const double off_px = split ? std::min(o_.tuning.tight_tolerance_px, std::max(0.1, 3.0 * median_residual_px))
                                  : o_.tuning.tight_tolerance_px;
      bool crowded = false;
      if (ti.bad || ti.residual_px > off_px)
        all_->Near(c_.p[i].x_px, c_.p[i].y_px, o_.tuning.crowd_radius_fwhm * o_.psf_fwhm_px, [&](int other) {
          if (other != i && result_.images[other].chain != cid) crowded = true;
        });
      double hx = 0, hy = 0;
      if (!ti.bad) {
        const FitSigma sigma = FitSigmaOf(o_, images_[i]);
        chain_[cid].track.LeverageAt(ti.mid_s, sigma.x_px, sigma.y_px, &hx, &hy);
      }
      const bool follows = std::max(hx, hy) > o_.tuning.max_leverage;
      if (crowded || follows) {
        unverified += follows && !crowded;
        Untag(i, follows ? TrailReason::kUnverified : TrailReason::kOffTrack);
        dropped = true;
        continue;
      }
      good.push_back({j, i});
      tc.images.push_back(i);
    }
    *kept = good;
    if (!dropped) break;
    // the track without them
    tc.bad_images = 0;
    for (const auto& [j, i] : *kept) result_.images[i].bad = false, result_.images[i].reason = TrailReason::kNone;
    const int n = static_cast<int>(kept->size());
    const bool enough = flow_trail ? n + unverified >= min_images && n >= kMinFlowTrackImages : n >= min_images;
    if (!enough || !FitTrail(c_, *kept, &tc, &result_.images, &chain_[cid].track)) {
      chain_[cid].kept = *kept;
      Refuse(cid, TrailReason::kOffTrack);
      return false;
    }
  }
  return true;
}

}  // namespace platemeter::trail_internal
