// Trail decoding: leading-dash runs, growth along the predicted track, the
// per-trail sidereal fit and the joining of trails into stars (trail_linker.h).
#include "platemeter/detect/trail_linker.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <numeric>
#include <unordered_map>

#include "platemeter/core/error.h"
#include "trail_internal.h"

namespace platemeter {

bool TrailOptions::Check(std::string* why) const {
  auto fail = [&](const char* r) {
    if (why) *why = r;
    return false;
  };
  if (!(psf_fwhm_px > 0)) return fail("psf_fwhm_px must be > 0");
  if (!(max_dash_spacing_px > 0)) return fail("max_dash_spacing_px must be > 0");
  if (!(edge_margin_px >= 0)) return fail("edge_margin_px must be >= 0");
  if (!(match_tolerance > 0 && match_tolerance < 0.5)) return fail("match_tolerance must be in (0, 0.5)");
  if (!(flux_tolerance >= 0)) return fail("flux_tolerance must be >= 0");
  if (!(position_floor_px >= 0)) return fail("position_floor_px must be >= 0");
  if (track_degree < 1 || track_degree > 6) return fail("track_degree must be 1..6");
  if (!(join_tolerance_px > 0)) return fail("join_tolerance_px must be > 0");
  if (!(flow_tolerance_px > 0)) return fail("flow_tolerance_px must be > 0");
  const Tuning& t = tuning;
  if (!(t.run_spacing_tolerance > 0 && t.run_spacing_tolerance < 0.5)) return fail("run_spacing_tolerance must be in (0, 0.5)");
  if (!(t.max_run_bend_deg > 0 && t.max_run_bend_deg < 45)) return fail("max_run_bend_deg must be in (0, 45)");
  if (!(t.min_tolerance_px > 0)) return fail("min_tolerance_px must be > 0");
  if (t.min_exposures_after_run < 1) return fail("min_exposures_after_run must be >= 1");
  if (t.max_missed_in_row < 1) return fail("max_missed_in_row must be >= 1");
  if (!(t.min_elongated_exposure_s >= 0)) return fail("min_elongated_exposure_s must be >= 0");
  if (!(t.dash_length_tolerance > 0)) return fail("dash_length_tolerance must be > 0");
  if (!(t.bad_sigma > 1) || !(t.min_bad_px >= 0)) return fail("bad_sigma must be > 1 and min_bad_px >= 0");
  if (!(t.join_tolerance_fraction >= 0)) return fail("join_tolerance_fraction must be >= 0");
  if (!(t.max_median_residual_px > 0) || !(t.max_median_residual_fwhm >= 0)) return fail("max_median_residual_px must be > 0");
  if (!(t.run_flux_tolerance > 0)) return fail("run_flux_tolerance must be > 0");
  if (!(t.crowd_radius_fwhm >= 0)) return fail("crowd_radius_fwhm must be >= 0");
  if (!(t.tight_tolerance_px > 0)) return fail("tight_tolerance_px must be > 0");
  if (!(t.max_leverage > 0 && t.max_leverage <= 1)) return fail("max_leverage must be in (0, 1]");
  if (t.min_sibling_images < 1 || !(t.sibling_window_s >= 0)) return fail("min_sibling_images must be >= 1");
  if (!(t.sibling_tolerance_px > 0) || !(t.sibling_tolerance_fraction >= 0)) return fail("sibling_tolerance_px must be > 0");
  if (!(t.clean_radius_spacings >= 0)) return fail("clean_radius_spacings must be >= 0");
  if (!(t.sibling_growth_window_s > 0)) return fail("sibling_growth_window_s must be > 0");
  if (!(t.motion_radius_px > 0)) return fail("motion_radius_px must be > 0");
  if (t.flow_degree < 1 || t.flow_degree > 10) return fail("flow_degree must lie in 1..10");
  if (!(t.flow_tolerance_fraction >= 0)) return fail("flow_tolerance_fraction must be >= 0");
  if (t.flow_min_images < 6 || t.flow_min_sibling_images < 6) return fail("flow_min_images must be >= 6");
  return true;
}

std::string TrailLinkResult::Summary() const {
  long decoded = 0;
  for (const TrailChain& c : chains) decoded += c.trail > 0;
  return std::to_string(assigned_dots) + " dots and " + std::to_string(assigned_dashes) + " dashes tagged in " +
         std::to_string(decoded) + " trails of " + std::to_string(stars.size()) + " stars (" +
         std::to_string(bad_images) + " bad); " + std::to_string(chains.size() - decoded) + " runs refused";
}

namespace {

using trail_internal::Compatible;
using trail_internal::Context;
using trail_internal::DegreeFor;
using trail_internal::Dist;
using trail_internal::Grid;
using trail_internal::Grow;
using trail_internal::Growth;
using trail_internal::GrowSpec;
using trail_internal::SiblingEvidence;
using trail_internal::Track;

// Images a decoded star's missing trail filled along the flow must hold (flow_fills_siblings).
constexpr int kSiblingFillImages = 3;

// With measured segments (trail-mode detection): a dash's run neighbours lie along its own direction
// (angle_deg) at 1.5 of its length, with its length. Each side takes its one candidate; two or more
// (crossing trails) link nothing on that side, and the dash is marked `open`: a run ending there could
// be longer than it looks.
void SegmentNeighbours(const Context& c, const Grid& dashes, const std::vector<int>& dash_ids,
                       std::unordered_map<int, std::vector<int>>* nb, std::unordered_map<int, bool>* open) {
  const TrailOptions& o = c.o;
  const double sin_bend = std::sin(o.tuning.max_run_bend_deg * std::numbers::pi / 180.0);
  for (int i : dash_ids) {
    const DetectedStar& di = c.images[i];
    if (di.length_px <= 0) continue;
    const double a = di.angle_deg * std::numbers::pi / 180.0, ux = std::cos(a), uy = std::sin(a);
    const double expect = 1.5 * di.length_px;
    const double along_tol = 2.0 * o.tuning.run_spacing_tolerance * expect + o.psf_fwhm_px;
    for (int side : {1, -1}) {
      int found = -1, count = 0;
      dashes.Near(c.p[i].x_px, c.p[i].y_px, expect + along_tol, [&](int j) {
        if (j == i || c.images[j].length_px <= 0) return;
        const double dx = c.p[j].x_px - c.p[i].x_px, dy = c.p[j].y_px - c.p[i].y_px;
        const double along = side * (dx * ux + dy * uy), across = std::abs(dx * uy - dy * ux);
        if (along <= 0 || std::abs(along - expect) > along_tol) return;
        if (across > std::max(0.5 * o.psf_fwhm_px, along * sin_bend)) return;
        const double dl = std::abs(c.images[j].length_px - di.length_px);
        if (dl > o.tuning.dash_length_tolerance * di.length_px + o.psf_fwhm_px + 3.0 * (di.sigma_length_px + c.images[j].sigma_length_px))
          return;
        found = j, ++count;
      });
      if (count == 1) (*nb)[i].push_back(found);
      if (count > 1) (*open)[i] = true;
    }
  }
}

// Runs of leading dashes: elongated images equally spaced along a line (spatial order).
std::vector<std::vector<int>> FindRuns(const Context& c, const Grid& dashes, const std::vector<int>& dash_ids) {
  const TrailOptions& o = c.o;
  const double cos_bend = std::cos(o.tuning.max_run_bend_deg * std::numbers::pi / 180.0);
  // Each dash's two neighbours in a run: the nearest dash, and the nearest one opposite to it.
  std::unordered_map<int, std::vector<int>> nb;
  std::unordered_map<int, bool> open;
  if (c.use_lengths) SegmentNeighbours(c, dashes, dash_ids, &nb, &open);
  for (int i : dash_ids) {
    if (c.use_lengths) break;
    std::vector<std::pair<double, int>> near;
    dashes.Near(c.p[i].x_px, c.p[i].y_px, o.max_dash_spacing_px, [&](int j) {
      if (j != i) near.push_back({Dist(c.p[i], c.p[j]), j});
    });
    std::sort(near.begin(), near.end());
    if (near.empty()) continue;
    const auto [d0, a] = near[0];
    // With measured lengths the spacing is 1.5 dash lengths (30 s against 20 s).
    auto spacing_ok = [&](double d, int j) {
      if (!c.use_lengths) return true;
      const double expect = 0.75 * (c.images[i].length_px + c.images[j].length_px);
      return std::abs(d - expect) <= 2.0 * o.tuning.run_spacing_tolerance * expect + c.o.psf_fwhm_px;
    };
    if (!spacing_ok(d0, a)) continue;
    nb[i].push_back(a);
    const double ax = (c.p[a].x_px - c.p[i].x_px) / d0, ay = (c.p[a].y_px - c.p[i].y_px) / d0;
    for (size_t k = 1; k < near.size(); ++k) {
      const auto [d, b] = near[k];
      if (std::abs(d - d0) > o.tuning.run_spacing_tolerance * d0) continue;
      const double cb = (ax * (c.p[b].x_px - c.p[i].x_px) + ay * (c.p[b].y_px - c.p[i].y_px)) / d;
      if (cb <= -cos_bend && spacing_ok(d, b)) {
        nb[i].push_back(b);
        break;
      }
    }
  }
  auto mutual = [&](int i, int j) {
    auto it = nb.find(j);
    return it != nb.end() && std::find(it->second.begin(), it->second.end(), i) != it->second.end();
  };
  std::unordered_map<int, std::vector<int>> adj;
  for (const auto& [i, js] : nb)
    for (int j : js)
      if (mutual(i, j)) adj[i].push_back(j);
  std::vector<std::vector<int>> runs;
  std::unordered_map<int, bool> seen;
  for (const auto& [i, js] : adj) {
    if (js.size() != 1 || seen[i]) continue;
    std::vector<int> run{i};
    seen[i] = true;
    int prev = -1, cur = i;
    for (;;) {
      int next = -1;
      for (int j : adj[cur])
        if (j != prev && !seen[j]) next = j;
      if (next < 0) break;
      seen[next] = true;
      run.push_back(next);
      prev = cur, cur = next;
    }
    // Equal spacing along the whole run, straight.
    bool ok = true;
    std::vector<double> gaps;
    for (size_t k = 1; k < run.size(); ++k) gaps.push_back(Dist(c.p[run[k]], c.p[run[k - 1]]));
    const double mean = std::accumulate(gaps.begin(), gaps.end(), 0.0) / gaps.size();
    for (double g : gaps) ok = ok && std::abs(g - mean) <= o.tuning.run_spacing_tolerance * mean;
    // An end dash with several candidates beyond it: the run may continue through a crossing.
    ok = ok && !open[run.front()] && !open[run.back()];
    if (ok) runs.push_back(run);
  }
  return runs;
}

// The final sidereal fit of one trail: weighted track, outliers flagged bad one at a time.
bool FitTrail(const Context& c, const std::vector<std::pair<int, int>>& taken, TrailChain* chain,
              std::vector<TrailImage>* out, Track* final_track) {
  const TrailOptions& o = c.o;
  const int n = static_cast<int>(taken.size());
  std::vector<bool> bad(n, false);
  std::vector<double> t(n), sx(n), sy(n);
  std::vector<PixelPoint> p(n);
  for (int k = 0; k < n; ++k) {
    const int i = taken[k].second;
    const DetectedStar& d = c.images[i];
    t[k] = (*out)[i].mid_s;
    p[k] = c.p[i];
    const trail_internal::FitSigma sigma = trail_internal::FitSigmaOf(o, d);
    sx[k] = sigma.x_px, sy[k] = sigma.y_px;
  }
  Track track;
  bool fitted = false;
  // Every pass refits without the images flagged so far: the final track never holds a bad one.
  for (int marked = 0;; ++marked) {
    std::vector<double> ft, fsx, fsy;
    std::vector<PixelPoint> fp;
    for (int k = 0; k < n; ++k)
      if (!bad[k]) ft.push_back(t[k]), fp.push_back(p[k]), fsx.push_back(sx[k]), fsy.push_back(sy[k]);
    if (ft.size() < 4) return false;
    const int degree = DegreeFor(static_cast<int>(ft.size()), ft.back() - ft.front(), o.track_degree);
    if (!track.Fit(ft, fp, fsx, fsy, degree)) break;
    fitted = true;
    // Studentised residuals (a fitted image's residual has the sigma sigma sqrt(1 - leverage): an
    // image near a trail's end, which the track follows, is judged fairly); their robust spread
    // (median chi of 2 dof = 1.177) scales the limit. deleted[k]: the residual had image k been left
    // out of the fit, r / (1 - h).
    std::vector<double> chi(n), deleted(n), good_chi;
    for (int k = 0; k < n; ++k) {
      const PixelPoint m = track.At(t[k]);
      double hx = 0, hy = 0;
      if (!bad[k]) track.LeverageAt(t[k], sx[k], sy[k], &hx, &hy);
      const double rx = p[k].x_px - m.x_px, ry = p[k].y_px - m.y_px;
      chi[k] = std::hypot(rx / (sx[k] * std::sqrt(1 - hx)), ry / (sy[k] * std::sqrt(1 - hy)));
      deleted[k] = std::hypot(rx / (1 - hx), ry / (1 - hy));
      if (!bad[k]) good_chi.push_back(chi[k]);
    }
    std::nth_element(good_chi.begin(), good_chi.begin() + good_chi.size() / 2, good_chi.end());
    const double spread = std::max(1.0, good_chi[good_chi.size() / 2] / 1.1774);
    int worst = -1;
    for (int k = 0; k < n; ++k) {
      if (bad[k]) continue;
      if (chi[k] > o.tuning.bad_sigma * spread && deleted[k] > o.tuning.min_bad_px && (worst < 0 || chi[k] > chi[worst])) worst = k;
    }
    // At most a third of the images bad, and enough left for the track.
    if (worst < 0 || marked + 1 > n / 3 || ft.size() <= 6) break;
    bad[worst] = true;
  }
  if (!fitted) return false;
  double ss = 0;
  int good = 0;
  for (int k = 0; k < n; ++k) {
    TrailImage& ti = (*out)[taken[k].second];
    const PixelPoint m = track.At(t[k]);
    ti.residual_x_px = p[k].x_px - m.x_px;
    ti.residual_y_px = p[k].y_px - m.y_px;
    ti.residual_px = std::hypot(ti.residual_x_px, ti.residual_y_px);
    ti.refined_px = m;
    track.SigmaAt(t[k], &ti.sigma_refined_x_px, &ti.sigma_refined_y_px);
    ti.bad = bad[k];
    if (bad[k]) {
      ti.reason = TrailReason::kBadFit;
      ++chain->bad_images;
    } else {
      ss += ti.residual_px * ti.residual_px, ++good;
    }
  }
  chain->rms_px = good > 0 ? std::sqrt(ss / good) : 0.0;
  *final_track = track;
  return true;
}

// Tags an image as exposure e of chain `chain` (its other fields untouched).
// The result's counts, from the tags themselves: the steps tag and take tags back, the counts follow.
void CountTags(TrailLinkResult* r) {
  r->assigned_dots = r->assigned_dashes = r->bad_images = 0;
  for (TrailChain& tc : r->chains) tc.bad_images = 0;
  for (const TrailImage& ti : r->images) {
    if (!ti.assigned) continue;
    (ti.kind == ExposureKind::kDot ? r->assigned_dots : r->assigned_dashes)++;
    if (!ti.bad) continue;
    ++r->bad_images;
    if (ti.chain >= 0) ++r->chains[static_cast<size_t>(ti.chain)].bad_images;
  }
}

void TagAs(TrailImage* ti, int chain, const ShutterExposure& e) {
  ti->chain = chain;
  ti->assigned = true;
  ti->reason = TrailReason::kNone;
  ti->trail = e.trail;
  ti->kind = e.kind;
  ti->dot_index = e.dot_index;
  ti->dash_index = e.dash_index;
  ti->mid_s = e.mid_s;
}

// Union-find over chains.
int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

TrailLinkResult LinkTrails(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options, const ScanPixels* scan) {
  std::string why;
  if (!options.Check(&why)) throw Error("trail options", why);
  const std::vector<ShutterExposure> schedule = BuildShutterSchedule(program);
  const int trails = static_cast<int>(program.leading_dashes.size());
  Context c{images, options, {}, {}, {}, false, std::vector<std::vector<ShutterExposure>>(trails), {}};
  for (const ShutterExposure& e : schedule) c.per_trail[e.trail - 1].push_back(e);
  c.scan = scan;

  TrailLinkResult result;
  const size_t n = images.size();
  result.images.resize(n);
  c.p.resize(n);
  c.usable.assign(n, false);
  c.elongated.assign(n, false);
  std::vector<int> usable_ids, dash_ids, all_ids(n);
  std::iota(all_ids.begin(), all_ids.end(), 0);
  for (size_t i = 0; i < n; ++i) {
    const DetectedStar& d = images[i];
    c.p[i] = d.point.position_px;
    if (d.point.status != PointStatus::kMeasured || (d.flags & kStarDefect)) {
      if (trail_internal::IsLine(d)) c.lines.push_back(static_cast<int>(i));
      result.images[i].reason = TrailReason::kNotStar;
      continue;
    }
    result.images[i].reason = TrailReason::kUnlinked;
    c.usable[i] = true;
    c.elongated[i] = (d.flags & kStarElongated) != 0;
    c.use_lengths = c.use_lengths || d.length_px > 0;
    usable_ids.push_back(static_cast<int>(i));
    if (c.elongated[i]) dash_ids.push_back(static_cast<int>(i));
  }
  const Grid all(c.p, all_ids, 32.0);
  const Grid dashes(c.p, dash_ids, options.max_dash_spacing_px);

  // 1-2. Runs, decoded by their length and grown in both directions.
  std::vector<std::vector<std::pair<int, int>>> taken_by;  // per decoded chain
  std::vector<int> owner_count(n, 0);
  std::unordered_map<int, double> flux_of;  // decoded chain -> flux per second
  std::unordered_map<int, bool> before_occupied;  // decoded chain -> an image one dash before its run
  std::unordered_map<int, std::pair<double, double>> dash_of;  // decoded chain -> its dashes' mean flux, length
  std::unordered_map<int, std::pair<PixelPoint, double>> before_of;  // decoded chain -> (position one dash before
                                                                     // its run, dash spacing)
  for (const std::vector<int>& run : FindRuns(c, dashes, dash_ids)) {
    TrailChain tc;
    tc.decoded_by = TrailStep::kRun;
    tc.leading_dashes = static_cast<int>(run.size());
    tc.images = run;
    auto refuse = [&](TrailReason reason) {
      tc.reason = reason;
      for (int i : run)
        if (result.images[i].chain < 0) result.images[i].reason = reason;
      result.chains.push_back(tc);
    };
    const auto it = std::find(program.leading_dashes.begin(), program.leading_dashes.end(), tc.leading_dashes);
    if (it == program.leading_dashes.end()) {
      refuse(TrailReason::kLeadingDashesIncomplete);
      continue;
    }
    const int t = static_cast<int>(it - program.leading_dashes.begin());
    // Equal exposures, equal fluxes: a stray dash of another star continuing the run (which would
    // change N) shows its own flux.
    {
      std::vector<double> f;
      for (int i : run) f.push_back(images[i].flux_dn);
      std::nth_element(f.begin(), f.begin() + f.size() / 2, f.end());
      const double median = f[f.size() / 2];
      // Only the end dashes matter (an inner dash blended with a crossing star's image does not
      // change N); no measured fluxes (median 0): not compared.
      bool same = true;
      if (median > 0)
        for (int i : {run.front(), run.back()})
          same = same && std::abs(images[i].flux_dn - median) <=
                             options.tuning.run_flux_tolerance * median + 4.0 * images[i].sigma_flux_dn;
      if (!same) {
        refuse(TrailReason::kRunFlux);
        continue;
      }
    }
    std::vector<Growth> grown(2);
    std::vector<std::vector<int>> ordered(2, run);
    std::reverse(ordered[1].begin(), ordered[1].end());
    double flux_per_s = 0.0;  // the run's median dash flux per second of exposure
    if (options.flux_tolerance > 0) {
      std::vector<double> f;
      for (int i : run) f.push_back(images[i].flux_dn);
      std::nth_element(f.begin(), f.begin() + f.size() / 2, f.end());
      flux_per_s = std::max(0.0, f[f.size() / 2] / c.per_trail[t].front().duration_s);
    }
    for (int dir = 0; dir < 2; ++dir) {
      GrowSpec spec;
      spec.exposures = &c.per_trail[t];
      for (size_t k = 0; k < run.size(); ++k) spec.seed.push_back({static_cast<int>(k), ordered[dir][k]});
      spec.first = static_cast<int>(run.size());
      spec.flux_per_s = flux_per_s;
      spec.max_missed_in_row = options.tuning.max_missed_in_row;
      grown[dir] = Grow(c, all, spec);
    }
    const bool ok0 = grown[0].after_run >= options.tuning.min_exposures_after_run;
    const bool ok1 = grown[1].after_run >= options.tuning.min_exposures_after_run;
    if (ok0 == ok1) {
      refuse(ok0 ? TrailReason::kAmbiguous : TrailReason::kShortPattern);
      continue;
    }
    const int dir = ok0 ? 0 : 1;
    // One dash before the run (30 s before its first): off the scan, or holding an image (a dash
    // not seen as one), would leave the count N in doubt.
    const std::vector<int>& r = ordered[dir];
    const PixelPoint a = c.p[r[0]], b = c.p[r[1]];
    const PixelPoint before{2 * a.x_px - b.x_px, 2 * a.y_px - b.y_px};
    if (!trail_internal::Inside(options, before, options.edge_margin_px)) {
      refuse(TrailReason::kAtEdge);
      continue;
    }
    // An image there that cannot hold a dash of this star (measured flux under half a dash's and
    // shorter than half a dash: a faint star's dot) leaves N certain; anything else may be the dash.
    double dash_flux = 0, dash_length = 0;
    for (int i : run) dash_flux += images[i].flux_dn / run.size(), dash_length += images[i].length_px / run.size();
    trail_internal::DashHolder holder{dash_flux, dash_length};
    trail_internal::ForReaching(c, all, before, std::max(options.tuning.min_tolerance_px, 0.5 * Dist(a, b)),
                                [&](int i) { holder.Add(images[i]); });
    const bool occupied = holder.Holds();
    // Occupied: the number needs its siblings' confirmation (step 4); no clean-field exception.
    if (occupied) before_occupied[result.chains.size()] = true;
    before_of[result.chains.size()] = {before, Dist(a, b)};
    dash_of[result.chains.size()] = {dash_flux, dash_length};
    flux_of[result.chains.size()] = flux_per_s;
    tc.trail = t + 1;
    tc.rate_px_per_s = grown[dir].rate_px_per_s;
    tc.missed_exposures = grown[dir].missed;
    tc.images.clear();
    // An inner dash of the run blended with another image (its flux off the run's) keeps the run's
    // count but is not tagged itself: its position is not this star's alone.
    std::vector<std::pair<int, int>> taken;
    for (const auto& [j, i] : grown[dir].taken) {
      if (j < tc.leading_dashes && flux_per_s > 0 &&
          std::abs(images[i].flux_dn - flux_per_s * c.per_trail[t][j].duration_s) >
              options.tuning.run_flux_tolerance * flux_per_s * c.per_trail[t][j].duration_s + 4.0 * images[i].sigma_flux_dn) {
        result.images[i].reason = TrailReason::kBlended;
        continue;
      }
      taken.push_back({j, i});
      tc.images.push_back(i), ++owner_count[i];
    }
    taken_by.push_back(taken);
    result.chains.push_back(tc);
  }
  // An image taken by two trails (crossing trails) belongs to neither.
  std::vector<int> chain_of_taken;  // result.chains index of each taken_by entry
  for (size_t k = 0; k < result.chains.size(); ++k)
    if (result.chains[k].trail > 0) chain_of_taken.push_back(static_cast<int>(k));
  std::vector<Track> tracks(result.chains.size());
  std::vector<std::vector<std::pair<int, int>>> kept_of(result.chains.size());  // (exposure, image) per chain
  // A trail refused after its images were tagged: the tags are taken back, the images keep `reason`.
  auto refuse = [&result](TrailChain& tc, const std::vector<std::pair<int, int>>& kept, TrailReason reason) {
    for (const auto& [j, i] : kept) {
      TrailImage& ti = result.images[i];
      ti = TrailImage{};
      ti.reason = reason;
    }
    tc.trail = 0;
    tc.reason = reason;
    tc.bad_images = 0;
  };
  // 3. The sidereal fit and the crowded-field checks of one trail (images: (exposure, image)); false:
  // the trail is refused and its tags taken back.
  // A trail must keep min_images (0: its leading dashes + half of min_exposures_after_run).
  auto settle = [&](int cid, const std::vector<std::pair<int, int>>& taken, int min_images = 0) -> bool {
    TrailChain& tc = result.chains[cid];
    if (min_images <= 0) min_images = tc.leading_dashes + options.tuning.min_exposures_after_run / 2;
    const std::vector<ShutterExposure>& ex = c.per_trail[tc.trail - 1];
    std::vector<std::pair<int, int>> kept;
    tc.images.clear();
    for (const auto& [j, i] : taken) {
      TrailImage& ti = result.images[i];
      if (owner_count[i] > 1) {
        ti.reason = TrailReason::kContested;
        continue;
      }
      kept.push_back({j, i});
      tc.images.push_back(i);
      TagAs(&ti, cid, ex[j]);
    }
    // 3. The sidereal fit (a trail left with too few images after the contested ones is refused).
    if (static_cast<int>(kept.size()) < min_images || !FitTrail(c, kept, &tc, &result.images, &tracks[cid])) {
      refuse(tc, kept, TrailReason::kContested);
      return false;
    }
    // Another star's images taken along the way (a crowded field) leave the track off most of them;
    // a trail's own images sit on it to their measuring precision.
    double median_residual = 0;
    {
      std::vector<double> res;
      for (const auto& [j, i] : kept)
        if (!result.images[i].bad) res.push_back(result.images[i].residual_px);
      std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
      const double limit = std::max(options.tuning.max_median_residual_px, options.tuning.max_median_residual_fwhm * options.psf_fwhm_px);
      if (!res.empty()) median_residual = res[res.size() / 2];
      if (res.empty() || res[res.size() / 2] > limit) {
        refuse(tc, kept, TrailReason::kPoorTrack);
        return false;
      }
    }
    // A bad image, or one off the track by more than tight_tolerance_px, with other images around it
    // is likely another star's (a crowded field): not tagged (TrailReason::kOffTrack). Alone, it is the trail's own
    // displaced image: tagged, flagged bad. An image the track merely follows (leverage above
    // max_leverage: beyond a long gap at the trail's end) cannot be checked: not tagged (TrailReason::kUnverified; the
    // plate's flow may check it, step 7).
    bool refused = false;
    for (int pass = 0; pass < 3 && !refused; ++pass) {  // until nothing more is dropped
      if (pass > 0) {  // the residuals of the refitted track
        std::vector<double> res;
        for (const auto& [j, i] : kept)
          if (!result.images[i].bad) res.push_back(result.images[i].residual_px);
        std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
        median_residual = res.empty() ? 0.0 : res[res.size() / 2];
      }
      bool dropped = false;
      // A piece of a crowded clump fitted jointly with a neighbour (blended and crowded) may carry part of
      // the neighbour's position (two dots 2 px apart, measured 1.5 px off the right one), and two such at
      // a trail's end pull the track onto themselves: each must lie on the track of the trail's other
      // images (within 3 median residuals and 0.1 px, that track known there to a third of it); else it
      // cannot be checked.
      const auto shared = [&](int i) { return (images[i].flags & kStarCrowded) && (images[i].flags & kStarBlended); };
      trail_internal::Track own;
      const bool any_shared =
          std::any_of(kept.begin(), kept.end(), [&](const std::pair<int, int>& ji) { return shared(ji.second); });
      const bool own_fitted =
          any_shared && trail_internal::FitTrackOf(
                            c, kept, [&](int i) { return result.images[i].mid_s; },
                            [&](int i) { return !shared(i) && !result.images[i].bad; }, 6, &own);
      {
        std::vector<std::pair<int, int>> good;
        tc.images.clear();
        for (const auto& [j, i] : kept) {
          TrailImage& ti = result.images[i];
          bool crowded = false;
          if (shared(i) && !ti.bad) {
            bool on_own = false;
            if (own_fitted) {
              double sx = 0, sy = 0;
              own.SigmaAt(ti.mid_s, &sx, &sy);
              const double limit_px = std::max(0.1, 3.0 * median_residual);
              on_own = 3.0 * std::hypot(sx, sy) <= limit_px && Dist(own.At(ti.mid_s), c.p[i]) <= limit_px;
            }
            if (!on_own) {
              ti = TrailImage{};
              ti.reason = own_fitted ? TrailReason::kOffTrack : TrailReason::kUnverified;
              dropped = true;
              continue;
            }
          }
          // (an image the detector split from a neighbour, `blended`: off the track already beyond 3 median
          // residuals of the trail, 3.5 sigma, and 0.1 px)
          const bool split = (images[i].flags & kStarBlended) != 0;
          if (ti.bad || ti.residual_px > (split ? std::min(options.tuning.tight_tolerance_px, std::max(0.1, 3.0 * median_residual))
                                                : options.tuning.tight_tolerance_px))
            all.Near(c.p[i].x_px, c.p[i].y_px, options.tuning.crowd_radius_fwhm * options.psf_fwhm_px, [&](int o) {
              if (o != i && result.images[o].chain != cid) crowded = true;
            });
          double hx = 0, hy = 0;
          if (!ti.bad) {
            const trail_internal::FitSigma sigma = trail_internal::FitSigmaOf(options, images[i]);
            tracks[cid].LeverageAt(ti.mid_s, sigma.x_px, sigma.y_px, &hx, &hy);
          }
          const bool unverified = std::max(hx, hy) > options.tuning.max_leverage;
          if (crowded || unverified) {
            ti = TrailImage{};
            ti.reason = unverified ? TrailReason::kUnverified : TrailReason::kOffTrack;
            dropped = true;
            continue;
          }
          good.push_back({j, i});
          tc.images.push_back(i);
        }
        kept = good;
      }
      if (!dropped) break;
      {  // the track without them
        tc.bad_images = 0;
        for (const auto& [j, i] : kept) result.images[i].bad = false, result.images[i].reason = TrailReason::kNone;
        if (static_cast<int>(kept.size()) < min_images || !FitTrail(c, kept, &tc, &result.images, &tracks[cid])) {
          refuse(tc, kept, TrailReason::kOffTrack);
          refused = true;
          break;
        }
      }
    }
    if (refused) return false;
    kept_of[cid] = kept;
    return true;
  };
  for (size_t g = 0; g < taken_by.size(); ++g) settle(chain_of_taken[g], taken_by[g]);

  // 4. Stars: trail A's track carried to B's images and back. Both must land on the other's
  // fitted track within the tolerance; a trail joins at most one trail of each other number.
  const int m = static_cast<int>(result.chains.size());
  auto ends = [&](int k, double* t0, double* t1) {
    *t0 = 1e300, *t1 = -1e300;
    for (const auto& [j, i] : kept_of[k]) *t0 = std::min(*t0, result.images[i].mid_s), *t1 = std::max(*t1, result.images[i].mid_s);
  };
  // Whether track a (images up to a1 s) and track b (images from b0 s, later) lie on one arc.
  auto on_one_arc = [&](const Track& ta, double a1, const Track& tb, double b0) {
    return trail_internal::OnOneArc(options, ta, a1, tb, b0);
  };
  auto decoded = [&](int k) { return result.chains[k].trail > 0 && !kept_of[k].empty(); };
  // Every decoded trail's track under every trail number (its images re-timed: exposure j of a
  // trail with N dashes is exposure j + N' - N of one with N').
  struct Retimed {
    bool ok = false;
    Track track;
    double t0 = 0, t1 = 0;
  };
  std::vector<std::vector<Retimed>> retimed(m, std::vector<Retimed>(trails));
  for (int k = 0; k < m; ++k) {
    if (!decoded(k)) continue;
    const int t = result.chains[k].trail - 1;
    for (int u = 0; u < trails; ++u) {
      Retimed& rt = retimed[k][u];
      if (u == t) {
        rt.ok = true, rt.track = tracks[k];
        ends(k, &rt.t0, &rt.t1);
        continue;
      }
      const int shift = program.leading_dashes[u] - program.leading_dashes[t];
      std::vector<double> ts;
      std::vector<PixelPoint> ps;
      for (const auto& [j, i] : kept_of[k]) {
        const int jj = j + shift;
        if (jj < 0 || jj >= static_cast<int>(c.per_trail[u].size())) continue;
        ts.push_back(c.per_trail[u][jj].mid_s);
        ps.push_back(c.p[i]);
      }
      if (ts.size() < 4 || !rt.track.Fit(ts, ps, {}, {}, tracks[k].degree())) continue;
      rt.ok = true;
      rt.t0 = *std::min_element(ts.begin(), ts.end()), rt.t1 = *std::max_element(ts.begin(), ts.end());
    }
  }
  // Two trails on one arc under numbers other than theirs (a leading dash lost without trace makes
  // trail N+1 look like trail N): both numbers are doubtful, both trails refused. Under their own
  // numbers: a join. Only adjacent numbers are compared (the extrapolation spans one break; trails
  // further apart join through their neighbours). Candidates: B's first image (its run's first
  // dash: exposure N_ub - N_tb under number ub) near A's track at that exposure's time.
  std::vector<bool> doubtful(m, false), joined(m, false);
  std::vector<std::pair<int, int>> joins;
  std::vector<std::vector<int>> partner_count(m, std::vector<int>(trails + 1, 0));
  std::vector<PixelPoint> head(m);
  std::vector<int> decoded_ids;
  for (int k = 0; k < m; ++k)
    if (decoded(k)) head[k] = c.p[kept_of[k].front().second], decoded_ids.push_back(k);
  const Grid heads(head, decoded_ids, 64.0);
  for (int a : decoded_ids) {
    const int ta = result.chains[a].trail - 1;
    for (int ua = 0; ua + 1 < trails; ++ua) {
      const int ub = ua + 1;
      const Retimed& ra = retimed[a][ua];
      if (!ra.ok) continue;
      const PixelPoint end = ra.track.At(ra.t1);
      for (int tb = 0; tb < trails; ++tb) {
        const int jj = program.leading_dashes[ub] - program.leading_dashes[tb];
        if (jj < 0 || jj >= static_cast<int>(c.per_trail[ub].size())) continue;
        const PixelPoint q = ra.track.At(c.per_trail[ub][jj].mid_s);
        heads.Near(q.x_px, q.y_px, 10.0 + 0.05 * Dist(q, end), [&](int b) {
          if (b == a || result.chains[b].trail - 1 != tb || !retimed[b][ub].ok) return;
          const Retimed& rb = retimed[b][ub];
          if (!on_one_arc(ra.track, ra.t1, rb.track, rb.t0)) return;
          if (ua == ta && ub == tb) {
            ++partner_count[a][tb + 1], ++partner_count[b][ta + 1];
            joins.push_back({a, b});
          } else {
            doubtful[a] = doubtful[b] = true;
          }
        });
      }
    }
  }
  for (const auto& [a, b] : joins)
    if (!doubtful[a] && !doubtful[b]) joined[a] = joined[b] = true;
  // Sibling evidence from the raw images (the sibling trails need not be decoded): under trail
  // number u, trail k's track carried to the exposures of trails u-1 and u+1 near its ends must
  // find images of the right length there. Under the wrong number (a lost or a stray leading dash)
  // it lands 30 s x the rate off. Counts the sibling exposures holding such an image.
  auto sibling_score = [&](int k, int u) {
    const Retimed& r = retimed[k][u];
    if (!r.ok) return 0;
    return trail_internal::SiblingsOf(c, all, r.track, r.t0, r.t1, u, flux_of.at(k),
                                      [&](int i) { return result.images[i].chain == k; }).hits;
  };
  // The trails with the most leading dashes: its exposures can hold every other trail's (re-timed).
  const int reference = static_cast<int>(
      std::max_element(program.leading_dashes.begin(), program.leading_dashes.end()) - program.leading_dashes.begin());
  // A decoded sibling's images are no other number's (they join).
  const auto other_number = [&](int i, int sibling) {
    const int ch = result.images[i].chain;
    return ch >= 0 && result.chains[ch].trail != sibling + 1;
  };
  auto number_by_siblings = [&](int k) {
    trail_internal::PatternTrail pt;
    const int shift = program.leading_dashes[reference] - result.chains[k].leading_dashes;
    for (const auto& [j, i] : kept_of[k]) pt.taken.push_back({j + shift, i});
    pt.flux_per_s = flux_of.at(k);
    trail_internal::SiblingGrowth grown;
    return trail_internal::NumberBySiblings(c, all, pt, reference, program.leading_dashes, other_number, &grown);
  };
  for (int k : decoded_ids) {
    if (doubtful[k]) continue;
    const int t = result.chains[k].trail - 1;
    const int own = sibling_score(k, t);
    int alt = 0;
    for (int u : {t - 1, t + 1})
      if (u >= 0 && u < trails) alt = std::max(alt, sibling_score(k, u));
    if (alt >= options.tuning.min_sibling_images && 2 * alt > own) {
      doubtful[k] = true;  // its siblings say another number
      continue;
    }
    if (joined[k]) continue;
    // Confirmed by a sibling grown from its track (on one arc, well fitted) under its number and no other;
    // single images on sibling exposures (`own`) do not confirm: in a crowded field other stars' images lie
    // within the tolerance of a few of them.
    {
      const int number = number_by_siblings(k);
      if (number == t) continue;
      if (number >= 0) {
        doubtful[k] = true;
        continue;
      }
    }
    // Unconfirmed: kept only where nothing could have hidden a leading dash (or posed as one).
    const auto& [before, spacing] = before_of.at(k);
    const auto& [dash_flux, dash_length] = dash_of.at(k);
    trail_internal::DashHolder holder{dash_flux, dash_length};
    trail_internal::ForReaching(c, all, before, options.tuning.clean_radius_spacings * spacing, [&](int i) {
      if (result.images[i].chain != k) holder.Add(images[i]);
    });
    const bool clean = !holder.Holds();
    // A slow star's 10 s gaps (a third of the spacing) within the PSF: its dashes merge, a lost one leaves
    // no trace in front of the run.
    const bool unresolved = spacing / 3.0 < options.psf_fwhm_px;
    if (!clean || before_occupied[k] || unresolved)
      doubtful[k] = true, joined[k] = false,
      result.chains[k].reason = before_occupied[k] ? TrailReason::kImageBeforeRun : unresolved ? TrailReason::kUnresolvedRun : TrailReason::kUnconfirmed;
  }
  if (options.require_joined)
    for (int k : decoded_ids)
      if (!doubtful[k] && !joined[k]) doubtful[k] = true, result.chains[k].reason = TrailReason::kLoneTrail;
  for (int k = 0; k < m; ++k) {
    if (!doubtful[k]) continue;
    TrailChain& tc = result.chains[k];
    if (tc.reason == TrailReason::kNone) tc.reason = TrailReason::kDoubtfulNumber;
    for (const auto& [j, i] : kept_of[k]) {
      TrailImage& ti = result.images[i];
      ti = TrailImage{};
      ti.reason = tc.reason;
    }
    tc.trail = 0;
    tc.bad_images = 0;
    kept_of[k].clear();
  }
  std::vector<int> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : joins) {
    const int ta = result.chains[a].trail, tb = result.chains[b].trail;
    if (decoded(a) && decoded(b) && partner_count[a][tb] == 1 && partner_count[b][ta] == 1)
      parent[Root(parent, a)] = Root(parent, b);
  }
  // 5. Siblings grown from the decoded trails: a trail whose own run was not found (its leading dashes
  // merged with crossing images, its first dots lost) is grown from its decoded neighbour's track,
  // carried across the break: its number is the neighbour's +-1, its exposures' times are known, and
  // every image must lie within the sibling tolerance of the prediction. The grown trail passes the
  // same fit and checks and must join its neighbour; it then seeds the next sibling.
  std::vector<int> numbers(m, 0);  // per star root: bit u set when the star holds trail u + 1
  for (int k = 0; k < m; ++k)
    if (decoded(k)) numbers[Root(parent, k)] |= 1 << (result.chains[k].trail - 1);
  // A new chain of trail s (0-based) found by `step`, a star of its own, with nothing taken yet; its index.
  auto open_chain = [&](TrailStep step, int s, double flux_per_s, double rate_px_per_s) {
    const int cid = static_cast<int>(result.chains.size());
    TrailChain tc;
    tc.decoded_by = step;
    tc.trail = s + 1;
    tc.leading_dashes = program.leading_dashes[s];
    tc.rate_px_per_s = rate_px_per_s;
    result.chains.push_back(tc);
    tracks.emplace_back();
    kept_of.emplace_back();
    parent.push_back(cid);
    numbers.push_back(1 << s);
    flux_of[cid] = flux_per_s;
    return cid;
  };
  // A new chain (trail number s, its images (exposure, image)) as a star of its own; false when refused.
  auto add_chain = [&](TrailStep step, int s, const std::vector<std::pair<int, int>>& taken, double flux_per_s,
                       double rate_px_per_s, int missed, int min_images = 0) {
    const int cid = open_chain(step, s, flux_per_s, rate_px_per_s);
    result.chains[cid].missed_exposures = missed;
    for (const auto& [j, i] : taken) owner_count[i] = 1;
    return settle(cid, taken, min_images);
  };
  auto GrowSiblings = [&] {
    std::vector<int> frontier;
    for (int k = 0; k < static_cast<int>(result.chains.size()); ++k)
      if (decoded(k)) frontier.push_back(k);
    while (!frontier.empty()) {
      std::vector<int> next;
      for (int k : frontier) {
        const int t = result.chains[k].trail - 1;
        for (int s : {t - 1, t + 1}) {
          if (!decoded(k) || s < 0 || s >= trails || (numbers[Root(parent, k)] >> s & 1)) continue;
          std::vector<std::pair<int, int>> taken;  // exposures of trail s
          const Growth g = trail_internal::GrowSibling(c, all, kept_of[k], t, s, flux_of.at(k),
                                                       [&](int i) { return result.images[i].chain >= 0; }, &taken);
          if (g.after_run < options.tuning.min_exposures_after_run) continue;
          const int cid = static_cast<int>(result.chains.size());
          if (!add_chain(TrailStep::kSibling, s, taken, flux_of.at(k), g.rate_px_per_s, g.missed)) continue;
          // It must join k: each track carried to the other's end lands on it.
          double k0 = 0, k1 = 0, n0 = 0, n1 = 0;
          ends(k, &k0, &k1);
          ends(cid, &n0, &n1);
          const bool joins_k = s < t ? on_one_arc(tracks[cid], n1, tracks[k], k0) : on_one_arc(tracks[k], k1, tracks[cid], n0);
          if (!joins_k) {
            refuse(result.chains[cid], kept_of[cid], TrailReason::kUnjoined);
            kept_of[cid].clear();
            continue;
          }
          const int root = Root(parent, k);
          parent[cid] = root;
          numbers[root] |= 1 << s;
          next.push_back(cid);
        }
      }
      frontier = next;
    }
  };
  // 6. Trails from their separator dashes (no run found, no decoded sibling): grown from each unassigned
  // dash read as each separator (trail_pattern.cpp), then numbered by their siblings' raw images: the
  // track under trail number u carried across the breaks must find images at the exposures of trails
  // u - 1 and u + 1 (at least min_sibling_images, 3x more than under any other number), or (a trail
  // whose siblings lie off the scan) every other number must find its siblings' long exposures empty.
  // A slow star (10 s of motion, the offset of a wrong number, within twice the tolerance) is not numbered.
  auto PatternTrails = [&] {
    std::vector<int> seeds;
    for (int i : dash_ids)
      if (result.images[i].chain < 0) seeds.push_back(i);
    std::sort(seeds.begin(), seeds.end(), [&](int x, int y) { return images[x].flux_dn > images[y].flux_dn; });
    const auto excluded = [&](int i) { return result.images[i].chain >= 0; };
    // The local direction of motion: the decoded trails' velocities near a point, when at least two agree
    // (within ~25 deg of their mean).
    std::vector<PixelPoint> mid_of(result.chains.size()), heading(result.chains.size());
    std::vector<int> moving;
    for (int k = 0; k < static_cast<int>(result.chains.size()); ++k) {
      if (!decoded(k)) continue;
      double t0 = 0, t1 = 0;
      ends(k, &t0, &t1);
      const PixelPoint v = tracks[k].VelocityAt(0.5 * (t0 + t1));
      const double speed = std::hypot(v.x_px, v.y_px);
      if (speed <= 0) continue;
      mid_of[k] = tracks[k].At(0.5 * (t0 + t1));
      heading[k] = {v.x_px / speed, v.y_px / speed};
      moving.push_back(k);
    }
    const Grid mids(mid_of, moving, options.tuning.motion_radius_px);
    auto motion_at = [&](const PixelPoint& p, PixelPoint* unit) {
      double sx = 0, sy = 0;
      int n = 0;
      mids.Near(p.x_px, p.y_px, options.tuning.motion_radius_px, [&](int k) { sx += heading[k].x_px, sy += heading[k].y_px, ++n; });
      const double len = std::hypot(sx, sy);
      if (n < 2 || len < 0.9 * n) return false;
      *unit = {sx / len, sy / len};
      return true;
    };
    for (int dash : seeds) {
      if (result.images[dash].chain >= 0) continue;
      trail_internal::PatternTrail pt;
      PixelPoint unit;
      const bool known = motion_at(c.p[dash], &unit);
      if (!trail_internal::GrowFromSeparator(c, all, dash, reference, known ? &unit : nullptr, excluded, &pt)) continue;
      trail_internal::SiblingGrowth grown;
      const int best = trail_internal::NumberBySiblings(c, all, pt, reference, program.leading_dashes, other_number, &grown);
      if (best < 0) continue;
      const int shift = program.leading_dashes[best] - program.leading_dashes[reference];
      std::vector<std::pair<int, int>> taken;
      for (const auto& [j, i] : pt.taken)
        if (j + shift >= 0) taken.push_back({j + shift, i});
      const int cid = static_cast<int>(result.chains.size());
      if (!add_chain(TrailStep::kSeparators, best, taken, pt.flux_per_s, grown.rate_px_per_s, 0)) continue;
      // Its sibling's images taken by a decoded trail of that number: the two join when they lie on one arc.
      const int sib = grown.sibling;
      const std::vector<std::pair<int, int>>& sibling_images = grown.images;
      std::unordered_map<int, int> votes;
      for (const auto& [j, i] : sibling_images)
        if (result.images[i].chain >= 0) ++votes[result.images[i].chain];
      for (const auto& [k, n] : votes) {
        if (2 * n < static_cast<int>(sibling_images.size()) || !decoded(k) || (numbers[Root(parent, k)] >> best & 1)) continue;
        double k0 = 0, k1 = 0, n0 = 0, n1 = 0;
        ends(k, &k0, &k1);
        ends(cid, &n0, &n1);
        if (sib < best ? on_one_arc(tracks[k], k1, tracks[cid], n0) : on_one_arc(tracks[cid], n1, tracks[k], k0)) {
          const int root = Root(parent, k);
          numbers[root] |= numbers[Root(parent, cid)];
          parent[Root(parent, cid)] = root;
        }
      }
    }
  };
  // 7. The plate's flow (trail_flow.cpp): one motion field fitted to every decoded trail's track. A decoded
  // star's missing trails are collected along it (their exposures' times are known); then every unassigned
  // dash is read as each exposure it may be, and a star is decoded when exactly one reading finds
  // its images in two trails or more.
  auto FlowTrails = [&] {
    std::vector<PixelPoint> samples_p, samples_v;
    int sampled_trails = 0;
    for (int k = 0; k < static_cast<int>(result.chains.size()); ++k) {
      if (!decoded(k) || static_cast<int>(kept_of[k].size()) < options.tuning.min_exposures_after_run) continue;
      std::vector<double> ts;
      for (const auto& [j, i] : kept_of[k]) ts.push_back(result.images[i].mid_s);
      trail_internal::AddFlowSamples(tracks[k], ts, &samples_p, &samples_v);
      ++sampled_trails;
    }
    // A polynomial of degree d has (d + 1)(d + 2) / 2 terms: at least as many trails, spread over the plate.
    SkyFlow flow;
    for (int degree = options.tuning.flow_degree; degree >= 2 && !flow.ok(); --degree)
      if (sampled_trails >= (degree + 1) * (degree + 2) / 2) flow.Fit(samples_p, samples_v, degree);
    if (!flow.ok()) return;
    const auto excluded = [&](int i) { return result.images[i].chain >= 0; };
    // A star's trails lie on one flow path: each trail's images carried along the flow from the end of the
    // star's largest trail nearest in time must mostly land within the flow's tolerance. A trail that does
    // not (a "sibling" grown from other stars' images, which the parabola's wider tolerance let through) is
    // not the star's: with two trails both go (which one is wrong is unknown), with more the strays.
    auto check_joins = [&] {
      std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
      for (int k = 0; k < static_cast<int>(result.chains.size()); ++k)
        if (decoded(k)) trails_of[Root(parent, k)].push_back(k);
      for (const auto& [root, ks] : trails_of) {
        if (ks.size() < 2) continue;
        int ref = ks.front();
        for (int k : ks) ref = kept_of[k].size() > kept_of[ref].size() ? k : ref;
        std::vector<int> strays;
        for (int k : ks) {
          if (k == ref) continue;
          double ref0_s = 0, ref1_s = 0, k0_s = 0, k1_s = 0;
          ends(ref, &ref0_s, &ref1_s);
          ends(k, &k0_s, &k1_s);
          const double t_origin_s = k0_s > ref1_s ? ref1_s : ref0_s;
          const PixelPoint origin = tracks[ref].At(t_origin_s);
          const FlowPath path(flow, origin, std::max(std::abs(k0_s - t_origin_s), std::abs(k1_s - t_origin_s)) + 30.0);
          int on = 0, n = 0;
          for (const auto& [j, i] : kept_of[k]) {
            const double dt = result.images[i].mid_s - t_origin_s;
            if (!path.Covers(dt)) continue;
            const PixelPoint q = path.At(dt);
            ++n;
            on += Dist(q, c.p[i]) <= trail_internal::FlowTolerance_px(options, q, origin);
          }
          if (2 * on < n) strays.push_back(k);
        }
        if (strays.empty()) continue;
        if (ks.size() == 2) strays = ks;
        for (int k : strays) {
          numbers[root] &= ~(1 << (result.chains[k].trail - 1));
          refuse(result.chains[k], kept_of[k], TrailReason::kOffFlow);
          kept_of[k].clear();
        }
      }
    };
    check_joins();
    // Adds the trails of `star` holding enough images to the star of `root` (-1: a new star).
    auto add_star = [&](const trail_internal::FlowStar& star, double rate_px_per_s, int root) {
      const bool new_star = root < 0;
      // (a decoded star's missing trail: its timing is the star's, its images need only be many enough for the fit)
      const int min_images = root >= 0 ? options.tuning.flow_min_sibling_images : options.tuning.flow_min_images;
      for (int s = 0; s < trails; ++s) {
        if (static_cast<int>(star.taken[s].size()) < min_images) continue;
        if (root >= 0 && (numbers[Root(parent, root)] >> s & 1)) continue;
        // A new star's trail shows its phase: a dash of its own (a reading shifted by one dot of a group, 40 s,
        // lines up the group's other dots but no dash: the separators fall between the dots).
        if (new_star && std::none_of(star.taken[s].begin(), star.taken[s].end(), [&](const std::pair<int, int>& ji) {
              return c.per_trail[s][ji.first].kind == ExposureKind::kDash && trail_internal::IsEvidence(c, ji.second);
            }))
          continue;
        const int cid = static_cast<int>(result.chains.size());
        // (the flow fixes its timing: no leading dashes needed)
        if (!add_chain(TrailStep::kFlow, s, star.taken[s], star.flux_per_s, rate_px_per_s, 0, min_images)) continue;
        if (root < 0) {
          root = cid;
          continue;
        }
        const int r = Root(parent, root);
        numbers[r] |= numbers[Root(parent, cid)];
        parent[Root(parent, cid)] = r;
      }
    };
    // Each decoded star's missing trail s (fn(root, s, k, t_end, origin)), carried from the end (origin at
    // t_end) of the star's decoded trail k nearest to it in time (the flow's error grows with the distance
    // carried): nearest in number, the most images; the end of its track's own images.
    auto for_missing_trails = [&](const std::function<void(int, int, int, double, const PixelPoint&)>& fn) {
      std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
      for (int k = 0; k < static_cast<int>(result.chains.size()); ++k)
        if (decoded(k)) trails_of[Root(parent, k)].push_back(k);
      for (const auto& [root, ks] : trails_of)
        for (int s = 0; s < trails; ++s) {
          if (numbers[Root(parent, root)] >> s & 1) continue;
          int k = ks.front();
          for (int q : ks) {
            const int dq = std::abs(result.chains[q].trail - 1 - s), dk = std::abs(result.chains[k].trail - 1 - s);
            if (dq < dk || (dq == dk && kept_of[q].size() > kept_of[k].size())) k = q;
          }
          double t0 = 1e300, t1 = -1e300;  // (the track's own images: not those the flow filled beyond them)
          for (const auto& [j, i] : kept_of[k])
            if (!result.images[i].flow_checked)
              t0 = std::min(t0, result.images[i].mid_s), t1 = std::max(t1, result.images[i].mid_s);
          if (t0 > t1) continue;  // (a trail of flow-filled images only has no track to carry)
          const double t_end = s > result.chains[k].trail - 1 ? t1 : t0;
          fn(root, s, k, t_end, tracks[k].At(t_end));
        }
    };
    // Decoded stars' missing trails.
    auto complete_stars = [&] {
      for_missing_trails([&](int root, int s, int k, double t_end, const PixelPoint& origin) {
        const trail_internal::FlowStar star = trail_internal::CollectAlongFlow(
            c, all, trail_internal::PlatePath(c, flow, origin), origin, t_end, flux_of.at(k), 1u << s, excluded);
        const PixelPoint v = flow.Velocity(origin);
        add_star(star, std::hypot(v.x_px, v.y_px), root);
      });
    };
    complete_stars();
    // Stars decoded from any of their dashes.
    std::vector<int> seeds;
    for (int i : dash_ids)
      if (result.images[i].chain < 0) seeds.push_back(i);
    // Where a dash is at most two FWHM long (slow stars near the pole) it is often measured as a point image
    // (Compatible says why): those seed too (whole V <= 8 plate: +80 dots right, 0 wrong).
    for (int i : usable_ids) {
      if (result.images[i].chain >= 0 || c.elongated[i] || images[i].length_px > 0) continue;
      const PixelPoint v = flow.Velocity(c.p[i]);
      const double dash_px = c.per_trail.front().front().duration_s * std::hypot(v.x_px, v.y_px);
      if (trail_internal::PointMayBeSwept(options, dash_px)) seeds.push_back(i);
    }
    std::sort(seeds.begin(), seeds.end(), [&](int x, int y) { return images[x].flux_dn > images[y].flux_dn; });
    for (int dash : seeds) {
      if (result.images[dash].chain >= 0) continue;
      trail_internal::FlowStar star;
      if (!trail_internal::DecodeByFlow(c, all, flow, dash, excluded, &star)) continue;
      const PixelPoint v = flow.Velocity(c.p[dash]);
      add_star(star, std::hypot(v.x_px, v.y_px), -1);
    }
    // Lone trails: stars the loop above left undecided, numbered by their runs (nothing else confirms the
    // number: not with require_joined).
    const auto trail_of = [&](int i) { return result.images[i].assigned ? result.images[i].trail : 0; };
    if (options.ablation.flow_lone_trails && !options.require_joined)
      for (int dash : seeds) {
        if (result.images[dash].chain >= 0) continue;
        trail_internal::LoneTrail lone;
        if (!trail_internal::DecodeLoneTrail(c, all, flow, dash, excluded, trail_of, &lone)) continue;
        const PixelPoint v = flow.Velocity(c.p[dash]);
        add_chain(TrailStep::kLone, lone.trail, lone.taken, lone.flux_per_s, std::hypot(v.x_px, v.y_px), 0,
                  options.tuning.flow_min_images);
      }
    complete_stars();  // the new stars' trails short of flow_min_images in their reading
    // An exposure's place along the flow (q, carried from origin): exactly one image (assigned or not) within
    // the flow's tolerance, unassigned, refused by no check but a track's (TrailReason::kUnlinked, TrailReason::kUnverified, or
    // TrailReason::kOffTrack: more than tight_tolerance_px off a track fitted among other stars' images -- then within
    // that of the place: the flow from a trail's end predicts what its track does, and the image its own
    // track dropped must not come back), compatible (length, flux) and no piece shared in a clump; -1
    // otherwise.
    auto flow_place_image = [&](const FlowPath& path, double dt, const PixelPoint& origin, const ShutterExposure& e,
                                double flux_per_s) {
      const PixelPoint q = path.At(dt);
      const double tol_px = trail_internal::FlowTolerance_px(options, q, origin);
      int near = 0, i = -1;
      all.Near(q.x_px, q.y_px, tol_px, [&](int o) {
        if (c.usable[o]) ++near, i = o;
      });
      if (near != 1) return -1;
      const TrailReason why = result.images[i].reason;  // (unassigned, and refused by no check but a track's)
      const bool shared = (images[i].flags & kStarCrowded) && (images[i].flags & kStarBlended);
      const bool off_track = why == TrailReason::kOffTrack && Dist(c.p[i], q) <= options.tuning.tight_tolerance_px;
      if ((why != TrailReason::kUnlinked && why != TrailReason::kUnverified && !off_track) || shared ||
          !trail_internal::Compatible(c, i, e, path.VelocityAt(dt), flux_per_s))
        return -1;
      return i;
    };
    // Image i tagged as exposure je of chain k, found along the flow at q: its measured position and sigmas
    // (the fit's weights: FitSigmaOf).
    auto tag_flow_checked = [&](int k, int je, int i, const PixelPoint& q) {
      const ShutterExposure& e = c.per_trail[result.chains[k].trail - 1][je];
      TrailImage& ti = result.images[i];
      ti = TrailImage{};
      TagAs(&ti, k, e);
      ti.flow_checked = true;
      ti.residual_x_px = c.p[i].x_px - q.x_px, ti.residual_y_px = c.p[i].y_px - q.y_px;
      ti.residual_px = Dist(c.p[i], q);
      ti.refined_px = c.p[i];
      const trail_internal::FitSigma sigma = trail_internal::FitSigmaOf(options, images[i]);
      ti.sigma_refined_x_px = sigma.x_px, ti.sigma_refined_y_px = sigma.y_px;
      kept_of[k].push_back({je, i});
      std::sort(kept_of[k].begin(), kept_of[k].end());
      std::vector<int>& chain_images = result.chains[k].images;
      chain_images.push_back(i);
      std::sort(chain_images.begin(), chain_images.end(),
                [&](int a, int b) { return result.images[a].mid_s < result.images[b].mid_s; });
    };
    auto recount_missed = [&](int k) {
      const auto [lo, hi] = std::minmax_element(kept_of[k].begin(), kept_of[k].end());
      result.chains[k].missed_exposures = hi->first - lo->first + 1 - static_cast<int>(kept_of[k].size());
    };
    // Each decoded trail's exposures without an image, filled along the flow: carried from the trail's image
    // nearest in time (the track there), an exposure's place must hold one image as flow_place_image says.
    // Such images lie beyond the growth's reach (after exposures missed in a row, where a crossing star took
    // the trail's images) or beyond the track's (a long gap at its end: TrailReason::kUnverified); the flow checks them.
    // In a gap inside the trail only an image nothing refused (TrailReason::kUnlinked) within tight_tolerance_px of
    // the track (the flow alone took a dash merged with a crossing star's there: 1 wrong tag).
    if (options.ablation.flow_fills_trails)
      for (int k = 0; k < static_cast<int>(result.chains.size()); ++k) {
        if (!decoded(k)) continue;
        const std::vector<ShutterExposure>& ex = c.per_trail[result.chains[k].trail - 1];
        const auto [first_it, last_it] = std::minmax_element(kept_of[k].begin(), kept_of[k].end());
        const int first = first_it->first, last = last_it->first;
        for (int je = 0; je < static_cast<int>(ex.size()); ++je) {
          const bool inside = je >= first && je <= last;
          const auto held = [&](const std::pair<int, int>& ji) { return ji.first == je; };
          if (inside && std::any_of(kept_of[k].begin(), kept_of[k].end(), held)) continue;
          const ShutterExposure& e = ex[je];
          int nearest = -1;
          for (const auto& [j, o] : kept_of[k])  // (the track's own images: it reaches them)
            if (!result.images[o].bad && !result.images[o].flow_checked &&
                (nearest < 0 || std::abs(ex[j].mid_s - e.mid_s) < std::abs(ex[nearest].mid_s - e.mid_s)))
              nearest = j;
          if (nearest < 0) break;
          const double dt = e.mid_s - ex[nearest].mid_s;
          const PixelPoint origin = tracks[k].At(ex[nearest].mid_s);
          const FlowPath path(flow, origin, std::abs(dt) + 30.0);
          if (!path.Covers(dt)) continue;
          const int i = flow_place_image(path, dt, origin, e, flux_of.at(k));
          // (a gap inside: the track knows the place too; an image it or a crowd check refused stays out)
          if (i < 0 || (inside && (result.images[i].reason != TrailReason::kUnlinked ||
                                   Dist(c.p[i], tracks[k].At(e.mid_s)) > options.tuning.tight_tolerance_px)))
            continue;
          tag_flow_checked(k, je, i, path.At(dt));
        }
        recount_missed(k);
      }
    // A decoded star's trails still missing (too few images for a track of their own, or refused by its fit
    // among other stars' images): each exposure's place carried along the flow from the end of the star's
    // trail nearest in time, filled as above. At least kSiblingFillImages of them, of two exposure lengths,
    // make the trail (a single image at the flow's tolerance may be a chance coincidence over the thousands
    // of places tried). An exposure whose neighbours' places lie within two tolerances of its own (a slow
    // star) is skipped; a place holding an image tagged with that trail number (the trail decoded as
    // another star's) leaves the trail alone.
    if (options.ablation.flow_fills_siblings)
      for_missing_trails([&](int root, int s, int k, double t_end, const PixelPoint& origin) {
        const std::vector<ShutterExposure>& ex = c.per_trail[s];
        const double reach_s = std::max(std::abs(ex.front().mid_s - t_end), std::abs(ex.back().mid_s - t_end));
        const FlowPath path(flow, origin, reach_s + 30.0);
        std::vector<std::pair<int, int>> found;
        std::vector<PixelPoint> places;
        for (int je = 0; je < static_cast<int>(ex.size()); ++je) {
          const double dt = ex[je].mid_s - t_end;
          if (!path.Covers(dt)) continue;
          const PixelPoint q = path.At(dt);
          const double tol_px = trail_internal::FlowTolerance_px(options, q, origin);
          // (the trail decoded as another star's: not filled twice)
          bool decoded_there = false;
          all.Near(q.x_px, q.y_px, tol_px, [&](int o) {
            decoded_there = decoded_there || (result.images[o].assigned && result.images[o].trail == s + 1);
          });
          if (decoded_there) return;
          bool apart = true;  // (from the neighbouring exposures' places)
          for (int jn : {je - 1, je + 1})
            if (jn >= 0 && jn < static_cast<int>(ex.size()) && path.Covers(ex[jn].mid_s - t_end))
              apart = apart && Dist(path.At(ex[jn].mid_s - t_end), q) > 2.0 * tol_px;
          const int i = apart ? flow_place_image(path, dt, origin, ex[je], flux_of.at(k)) : -1;
          const auto taken = [&](const std::pair<int, int>& ji) { return ji.second == i; };
          if (i < 0 || std::any_of(found.begin(), found.end(), taken)) continue;
          found.push_back({je, i});
          places.push_back(q);
        }
        std::vector<double> durations_s;  // (a chance image at each place would rarely fit two exposure lengths)
        for (const auto& [je, i] : found) durations_s.push_back(ex[je].duration_s);
        if (static_cast<int>(found.size()) < kSiblingFillImages || trail_internal::DistinctCount(durations_s) < 2) return;
        const PixelPoint v = flow.Velocity(origin);
        // (no track of its own: its images are the flow's) joined to the star
        const int cid = open_chain(TrailStep::kFlowFill, s, flux_of.at(k), std::hypot(v.x_px, v.y_px));
        const int r = Root(parent, root);
        parent[cid] = r;
        numbers[r] |= 1 << s;
        for (size_t n = 0; n < found.size(); ++n) tag_flow_checked(cid, found[n].first, found[n].second, places[n]);
        recount_missed(cid);
      });
  };
  if (options.ablation.grow_siblings) GrowSiblings();
  if (options.ablation.pattern_trails) {
    PatternTrails();
    if (options.ablation.grow_siblings) GrowSiblings();
  }
  if (options.ablation.flow_trails) FlowTrails();
  // A star may hold each trail number once; otherwise its trails stay stars of their own.
  std::unordered_map<int, std::vector<int>> members;
  for (int k = 0; k < static_cast<int>(result.chains.size()); ++k)
    if (decoded(k)) members[Root(parent, k)].push_back(k);
  std::vector<std::vector<int>> groups;
  for (auto& [root, ks] : members) {
    std::vector<int> numbers;
    for (int k : ks) numbers.push_back(result.chains[k].trail);
    std::sort(numbers.begin(), numbers.end());
    if (std::adjacent_find(numbers.begin(), numbers.end()) != numbers.end()) {
      for (int k : ks) groups.push_back({k});
    } else {
      std::sort(ks.begin(), ks.end(), [&](int x, int y) { return result.chains[x].trail < result.chains[y].trail; });
      groups.push_back(ks);
    }
  }
  std::sort(groups.begin(), groups.end());
  for (const std::vector<int>& g : groups) {
    // (with require_joined every trail tagged has a sibling of its star: the later steps' lone ones too)
    if (options.require_joined && g.size() < 2) {
      refuse(result.chains[g[0]], kept_of[g[0]], TrailReason::kLoneTrail);
      kept_of[g[0]].clear();
      continue;
    }
    const int s = static_cast<int>(result.stars.size());
    result.stars.push_back({g});
    for (int k : g) {
      result.chains[k].star = s;
      for (int i : result.chains[k].images) result.images[i].star = s;
    }
  }
  CountTags(&result);
  return result;
}

}  // namespace platemeter
