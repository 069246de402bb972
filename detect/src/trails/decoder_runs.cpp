// Steps 1-2 (decoder.h): every run of leading dashes (runs.cpp) numbered by its length and grown exposure
// by exposure in both time directions; exactly one direction must grow (docs/trails.md, "Runs").
#include <algorithm>

#include "decoder.h"

namespace platemeter::trail_internal {

void TrailDecoder::DecodeRuns() {
  for (const std::vector<int>& run : FindRuns(c_, *dashes_, dash_ids_)) DecodeRun(run);
}

namespace {

double MedianFlux_dn(const std::vector<DetectedStar>& images, const std::vector<int>& run) {
  std::vector<double> f;
  for (int i : run) f.push_back(images[i].flux_dn);
  std::nth_element(f.begin(), f.begin() + f.size() / 2, f.end());
  return f[f.size() / 2];
}

}  // namespace

void TrailDecoder::DecodeRun(const std::vector<int>& run) {
  TrailChain tc;
  tc.decoded_by = TrailStep::kRun;
  tc.leading_dashes = static_cast<int>(run.size());
  tc.images = run;
  const auto refuse = [&](TrailReason reason) {
    tc.reason = reason;
    for (int i : run)
      if (result_.images[i].chain < 0) result_.images[i].reason = reason;
    PushChain(tc);
  };
  const auto it = std::find(program_.leading_dashes.begin(), program_.leading_dashes.end(), tc.leading_dashes);
  if (it == program_.leading_dashes.end()) return refuse(TrailReason::kLeadingDashesIncomplete);
  const int t = static_cast<int>(it - program_.leading_dashes.begin());
  // Equal exposures, equal fluxes: a stray dash of another star continuing the run (which would change N)
  // shows its own flux. Only the end dashes matter (an inner dash blended with a crossing star's image does
  // not change N); no measured fluxes (median 0): not compared.
  const double median_dn = MedianFlux_dn(images_, run);
  if (median_dn > 0)
    for (int i : {run.front(), run.back()})
      if (!(std::abs(images_[i].flux_dn - median_dn) <= o_.tuning.run_flux_tolerance * median_dn + 4.0 * images_[i].sigma_flux_dn))
        return refuse(TrailReason::kRunFlux);
  std::vector<Growth> grown(2);
  std::vector<std::vector<int>> ordered(2, run);
  std::reverse(ordered[1].begin(), ordered[1].end());
  // the run's median dash flux per second of exposure
  const double flux_per_s = o_.flux_tolerance > 0 ? std::max(0.0, median_dn / c_.per_trail[t].front().duration_s) : 0.0;
  for (int dir = 0; dir < 2; ++dir) {
    GrowSpec spec;
    spec.exposures = &c_.per_trail[t];
    for (size_t k = 0; k < run.size(); ++k) spec.seed.push_back({static_cast<int>(k), ordered[dir][k]});
    spec.first = static_cast<int>(run.size());
    spec.flux_per_s = flux_per_s;
    spec.max_missed_in_row = o_.tuning.max_missed_in_row;
    grown[dir] = Grow(c_, *all_, spec);
  }
  const bool ok0 = grown[0].after_run >= o_.tuning.min_exposures_after_run;
  const bool ok1 = grown[1].after_run >= o_.tuning.min_exposures_after_run;
  if (ok0 == ok1) return refuse(ok0 ? TrailReason::kAmbiguous : TrailReason::kShortPattern);
  const int dir = ok0 ? 0 : 1;
  // One dash before the run (30 s before its first): off the scan, or holding an image (a dash not seen as
  // one), would leave the count N in doubt.
  const std::vector<int>& r = ordered[dir];
  const PixelPoint a = c_.p[r[0]], b = c_.p[r[1]];
  const PixelPoint before{2 * a.x_px - b.x_px, 2 * a.y_px - b.y_px};
  if (!Inside(o_, before, o_.edge_margin_px)) return refuse(TrailReason::kAtEdge);
  // An image there that cannot hold a dash of this star (measured flux under half a dash's and shorter than
  // half a dash: a faint star's dot) leaves N certain; anything else may be the dash: the number then needs
  // its siblings' confirmation (step 4), with no clean-field exception.
  double dash_flux = 0, dash_length = 0;
  for (int i : run) dash_flux += images_[i].flux_dn / run.size(), dash_length += images_[i].length_px / run.size();
  DashHolder holder{dash_flux, dash_length};
  ForReaching(c_, *all_, before, std::max(o_.tuning.min_tolerance_px, 0.5 * Dist(a, b)),
              [&](int i) { holder.Add(images_[i]); });
  holder.held = holder.held || Blind(o_, before, dash_length);  // a dash there would have been lost in a cross
  tc.trail = t + 1;
  tc.rate_px_per_s = grown[dir].rate_px_per_s;
  tc.missed_exposures = grown[dir].missed;
  tc.images.clear();
  // An inner dash of the run blended with another image (its flux off the run's) keeps the run's count but
  // is not tagged itself: its position is not this star's alone.
  Taken taken;
  bool run_merged = false;
  for (const auto& [j, i] : grown[dir].taken) {
    const double duration_s = c_.per_trail[t][j].duration_s;
    if (j < tc.leading_dashes && flux_per_s > 0 &&
        std::abs(images_[i].flux_dn - flux_per_s * duration_s) >
            o_.tuning.run_flux_tolerance * flux_per_s * duration_s + 4.0 * images_[i].sigma_flux_dn) {
      result_.images[i].reason = TrailReason::kBlended;
      run_merged = true;
      continue;
    }
    taken.push_back({j, i});
    tc.images.push_back(i), ++owner_count_[i];
  }
  const int cid = PushChain(tc);
  ChainState& cs = chain_[cid];
  cs.before_occupied = holder.Holds();
  cs.run_merged = run_merged;
  cs.before_px = before;
  cs.spacing_px = Dist(a, b);
  cs.run_angle_rad = std::atan2(a.y_px - b.y_px, a.x_px - b.x_px);
  cs.first_dash_image = r[0];
  cs.dash_flux_dn = dash_flux, cs.dash_length_px = dash_length;
  cs.flux_per_s = flux_per_s;
  cs.grown = taken;
}

}  // namespace platemeter::trail_internal
