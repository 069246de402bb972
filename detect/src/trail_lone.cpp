// A lone trail numbered by its leading run found along the plate's flow (trail_internal.h; docs/trails.md
// "The plate's flow", step 4). A star with one trail on the format (the others off it, or hidden) cannot be
// decoded by its sibling trails. Its dot program fixes the time of every image relative to a dash, but not
// the trail's number: the four trails' programs after their leading runs are alike. The run tells: under
// the flow, the positions of the run's dashes are known to a fraction of a pixel, so the dashes present
// there are counted (single, or merged through their 10 s gaps into one detection whose centre, length and
// flux say how many) and the place one dash before them must be empty.
#include <algorithm>
#include <cmath>
#include <map>

#include "platemeter/detect/dash_in_pixels.h"

#include "trail_internal.h"

namespace platemeter::trail_internal {

namespace {

// Index of the trail's first dot (= its leading dash count).
int FirstDot(const std::vector<ShutterExposure>& ex) {
  int j = 0;
  while (j < static_cast<int>(ex.size()) && ex[j].kind != ExposureKind::kDot) ++j;
  return j;
}

// A reading lining up this many dots of another trail makes the star DecodeByFlow's (which left it undecided).
constexpr int kOtherTrailDots = 3;
// A group of readings with this many images past the run is a candidate; exactly one may exist.
constexpr int kCandidateImages = 5;
// As in DecodeByFlow: dashes besides the seed, and exposure durations among the images (a reading shifted by
// a dot group maps the dots onto other durations; the flux tolerance lets some of them through, not all).
constexpr int kOtherDashes = 2, kDurations = 4;
// A trail cut by the format's edge: dashes and at least two dot durations.
constexpr int kMinDurationsCut = 3;
// A slow star (10 s of motion within this many flow tolerances) is not decoded: readings shifted by 10 s land
// on its own images. (Its run may merge: the merged explanation below counts it.)
constexpr double kLoneNotDecodedTolerances = 2.0;
// A reading showing this many images of another trail of the star shows that trail.
constexpr int kShownImages = 3;
// An empty place of a trail counts where an image of that trail (any star's) is tagged within this.
constexpr double kExposedRadius_px = 150.0;

// Whether, under trail number u (the seed at seed_s of that trail), another trail of the star lies on the
// format where nothing could hold it: at least two of its dashes' places inside the format along the flow,
// at least two of them empty and at most one not (a crowd may put an image at one), by flux
// (DashHolder::by_flux: the star's dashes measure alike). The flow predicts a place to flow_tolerance_px
// over hundreds of pixels, so an empty place says the trail is not there.
bool SiblingAbsent(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s, int u,
                   double flux_per_s, const std::function<int(int)>& trail_of) {
  const TrailOptions& o = c.o;
  for (int s = 0; s < static_cast<int>(c.per_trail.size()); ++s) {
    if (s == u) continue;
    int inside = 0, empty = 0;
    for (const ShutterExposure& e : c.per_trail[s]) {
      if (e.kind != ExposureKind::kDash) continue;
      const double dt = e.mid_s - seed_s;
      if (!path.Covers(dt)) continue;
      const PixelPoint q = path.At(dt);
      if (!Inside(o, q, o.edge_margin_px)) continue;
      ++inside;
      // Only where trail s was exposed: another star's image of it tagged nearby (a cloud or a shutter fault
      // during one trail empties its places on every star).
      bool exposed = false;
      all.Near(q.x_px, q.y_px, kExposedRadius_px, [&](int i) { exposed = exposed || trail_of(i) == s + 1; });
      const double tol_px = FlowTolerance_px(o, q, p);
      // (An image tagged as another trail number of another star, whose flux leaves no room for this dash,
      // holds none of it; one tagged with trail s may be the star's own.)
      const double dash_flux_dn = flux_per_s * e.duration_s;
      const auto explained = [&](int i) {
        return trail_of(i) > 0 && trail_of(i) != s + 1 && CannotHideDash(c, i, dash_flux_dn);
      };
      empty += exposed && DashPlaceEmpty(c, all, q, path.VelocityAt(dt), dash_flux_dn, e.duration_s, tol_px, true,
                                         explained);
    }
    if (inside >= 2 && empty >= std::max(2, inside - 1)) return true;
  }
  return false;
}

// The exposure durations a lone trail's images must show: kDurations, or, for a trail cut by the format's
// edge (dots of its program beyond it: a trail leaving the format after its first dot groups, or entering it
// for its last ones), every duration of its exposures on the format, at least kMinDurationsCut.
// seed_from_first_dot_s: the seed's time from the trail's first dot.
int DurationsRequired(const Context& c, const FlowPath& path, int trail, double seed_from_first_dot_s) {
  const std::vector<ShutterExposure>& ex = c.per_trail[trail];
  const double seed_s = ex[FirstDot(ex)].mid_s + seed_from_first_dot_s;
  std::vector<double> on_format_s;
  bool cut = false;  // dots of the program off the format
  for (size_t k = 0; k < ex.size(); ++k) {
    const double dt = ex[k].mid_s - seed_s;
    if (path.Covers(dt) && Inside(c.o, path.At(dt), c.o.edge_margin_px))
      on_format_s.push_back(ex[k].duration_s);
    else
      cut = cut || ex[k].kind == ExposureKind::kDot;
  }
  if (!cut || !c.o.ablation.flow_cut_trails) return kDurations;
  return std::max(kMinDurationsCut, std::min(kDurations, DistinctCount(on_format_s)));
}

// What the scan's pixels show at the place of a dash of the star dt from the seed (where LinkTrails was
// given them; nothing measured without them): its thirds fitted with the light of the detections about it
// (MeasureDashInPixels).
DashInPixels DashInScan(const Context& c, const Grid& all, const FlowPath& path, double dt, double dash_length_px,
                        double dash_flux_dn) {
  if (!c.scan) return {};
  const PixelPoint q = path.At(dt), v = path.VelocityAt(dt);
  DashPlace place;
  place.centre_px = q;
  place.angle_rad = std::atan2(v.y_px, v.x_px);
  place.length_px = dash_length_px;
  place.fwhm_px = c.o.psf_fwhm_px;
  place.flux_dn = dash_flux_dn;
  const DashInPixelsOptions options;
  // (every detection whose light may reach the window: the longest a dash-long sweep)
  const double reach_px = dash_length_px + (options.window_fwhm + 3.0) * place.fwhm_px;
  std::vector<DetectedStar> near;
  all.Near(q.x_px, q.y_px, reach_px, [&](int i) {
    if (c.usable[i]) near.push_back(c.images[i]);
  });
  return MeasureDashInPixels(*c.scan, place, near, options);
}

}  // namespace

bool DecodeLoneTrail(const Context& c, const Grid& all, const SkyFlow& flow, int dash,
                     const std::function<bool(int)>& excluded, const std::function<int(int)>& trail_of,
                     LoneTrail* out) {
  const TrailOptions& o = c.o;
  const DetectedStar& d = c.images[dash];
  const PixelPoint p = c.p[dash];
  // (a blended seed too: a dash fitted jointly with the dot on its wing; one merged with another image reads
  // the star's flux wrong, and the durations below refuse it)
  // (point images too: where a dash is at most two FWHM long, Compatible takes them; measured lengths needed)
  if (!c.use_lengths || d.flux_dn <= 0 || !IsEvidence(c, dash)) return false;
  const PixelPoint v = flow.Velocity(p);
  const double speed = std::hypot(v.x_px, v.y_px);
  const ShutterExposure& a_dash = c.per_trail.front().front();  // a leading dash: every dash lasts 20 s
  if (!Compatible(c, dash, a_dash, v, 0.0)) return false;
  if (10.0 * speed < kLoneNotDecodedTolerances * o.flow_tolerance_px) return false;
  const double flux_per_s = d.flux_dn / a_dash.duration_s;
  const FlowPath path = PlatePath(c, flow, p);
  const unsigned every_trail = (1u << c.per_trail.size()) - 1u;

  // Readings of the dash grouped by its time from the trail's first dot: readings in one group predict the
  // same dots and separators (the programs after the runs are alike, the flow autonomous) and differ only in
  // their leading dashes.
  struct Group {
    int trail = -1, exposure = -1;                // a reading of the group (trail, exposure)
    std::vector<std::pair<int, int>> program;     // (exposure, image) past the run, in that reading's trail
    bool self = false;                            // the dash taken as the reading's exposure
    std::map<int, int> sibling_dots;              // per reading's trail: the most dots of another trail
  };
  std::map<long, Group> groups;  // key: the dash's time from the first dot, 0.1 s
  for (size_t t = 0; t < c.per_trail.size(); ++t) {
    const std::vector<ShutterExposure>& ex = c.per_trail[t];
    const int first_dot = FirstDot(ex);
    for (int j = 0; j < static_cast<int>(ex.size()); ++j) {
      const ShutterExposure& e = ex[j];
      if (e.kind != ExposureKind::kDash || !Compatible(c, dash, e, v, 0.0)) continue;
      const FlowStar own = CollectAlongFlow(c, all, path, p, e.mid_s, flux_per_s, 1u << t, excluded);
      if (own.hits < 3) continue;
      // Dots of the star's other trails under this reading: only the right trail number lines them up.
      const FlowStar whole = CollectAlongFlow(c, all, path, p, e.mid_s, flux_per_s, every_trail & ~(1u << t), excluded);
      int sibling_dots = 0;
      for (size_t u = 0; u < whole.taken.size(); ++u) {
        int dots = 0;
        for (const auto& [k, i] : whole.taken[u]) dots += c.per_trail[u][k].kind == ExposureKind::kDot;
        sibling_dots = std::max(sibling_dots, dots);
      }
      const long key = std::lround(10.0 * (e.mid_s - ex[first_dot].mid_s));
      Group& g = groups[key];
      g.sibling_dots[static_cast<int>(t)] = std::max(g.sibling_dots[static_cast<int>(t)], sibling_dots);
      if (g.trail >= 0) continue;  // the group's program is known from its first reading
      g.trail = static_cast<int>(t), g.exposure = j;
      for (const auto& [k, i] : own.taken[t]) {
        if (k < first_dot) continue;
        g.program.push_back({k, i});
        g.self |= i == dash && k == j;
      }
    }
  }
  // Exactly one group with the images of a candidate.
  const Group* best = nullptr;
  for (const auto& [key, g] : groups) {
    if (EvidenceCount(c, g.program) < kCandidateImages) continue;
    if (best) return false;
    best = &g;
  }
  if (!best) return false;
  // Another group lining up dots of a second trail: the star is no lone trail (DecodeByFlow left it undecided).
  for (const auto& [key, g] : groups)
    for (const auto& [t, dots] : g.sibling_dots)
      if (&g != best && dots >= kOtherTrailDots) return false;
  // The run, counted back from its last dash along the flow: dash m (0 = the last) lies 30 m s before it.
  const std::vector<ShutterExposure>& ex = c.per_trail[best->trail];
  const int first_dot = FirstDot(ex);
  const double last_dash_s = ex[first_dot - 1].mid_s - ex[best->exposure].mid_s;  // from the seed
  int max_dashes = 0;
  for (const auto& e : c.per_trail) max_dashes = std::max(max_dashes, FirstDot(e));
  // Each step explains dashes m .. m + k - 1 by one detection: a single dash (k = 1) or k dashes merged
  // through their 10 s gaps (their centre, (30 k - 10) s of motion long, k dashes' flux); exactly one k.
  std::vector<int> single(max_dashes + 1, -1);  // the image of dash m, alone
  std::vector<int> run;                         // the run's detections
  const double dash_flux = a_dash.duration_s * flux_per_s, dash_length = a_dash.duration_s * speed;
  int m = 0;
  bool off_format = false;  // the run goes on beyond the format (or may)
  // The detection explaining dashes from .. from + k - 1 (merged, k > 1): its k and image; k = 0 when none
  // does, -1 when more than one k or image would; off: the place of dash `from` lies beyond the format.
  struct Explained {
    int k = 0, image = -1;
    bool off = false;
  };
  const auto explain = [&](int from) {
    Explained r;
    for (int k = 1; from + k <= max_dashes + 1; ++k) {
      const double dt_first = last_dash_s - 30.0 * (from + k - 1);
      if (!path.Covers(dt_first) || !Inside(o, path.At(dt_first), o.edge_margin_px)) {
        r.off = k == 1;
        break;
      }
      const double dt = last_dash_s - 30.0 * (from + 0.5 * (k - 1));
      const PixelPoint q = path.At(dt), vq = path.VelocityAt(dt);
      const double tol = FlowTolerance_px(o, q, p);
      ShutterExposure merged = a_dash;
      merged.duration_s = a_dash.duration_s + 30.0 * (k - 1);  // the swept length
      const double merged_flux_per_s = flux_per_s * k * a_dash.duration_s / merged.duration_s;
      int count = 0, image = -1;
      all.Near(q.x_px, q.y_px, tol, [&](int i) {
        if (!c.usable[i] || (excluded && excluded(i)) || !Compatible(c, i, merged, vq, merged_flux_per_s)) return;
        ++count, image = i;
      });
      if (count > 1 || (count == 1 && r.k != 0)) return Explained{-1, -1, false};
      if (count == 1) r.k = k, r.image = image;
    }
    return r;
  };
  for (;;) {
    if (m > max_dashes) return false;
    const Explained e = explain(m);
    if (e.k < 0) return false;
    if (e.off) {
      // Dash m's own place beyond the format: the run may go on there. (Only a merge reaching beyond it:
      // no such explanation, dash m is judged alone.)
      if (!o.ablation.flow_entering_trails) return false;
      off_format = true;
      break;
    }
    if (e.k > 0) {
      if (e.k == 1) single[m] = e.image;
      run.push_back(e.image);
      m += e.k;
      continue;
    }
    // Dash m absent: nothing may hold it. The flow puts it within its tolerance; a detection holding it
    // (merged with another image: at least its flux; the bigger piece of a split: half of it; or a rejected
    // line reaching there) lies within half its length and two FWHM of that.
    const PixelPoint q = path.At(last_dash_s - 30.0 * m);
    const double reach_px = 0.5 * dash_length + 2.0 * o.psf_fwhm_px + o.flow_tolerance_px;
    bool empty = true;
    double faint_flux_dn = 0;  // pieces of a dash the deblender cut add up
    ForReaching(c, all, q, reach_px, [&](int i) {
      const DetectedStar& h = c.images[i];
      const bool explained = excluded && excluded(i) && CannotHideDash(c, i, dash_flux);  // another star's
      const bool faint = h.flux_dn > 0 && h.flux_dn < 0.5 * dash_flux && !(h.flags & (kStarCrowded | kStarBlended));
      if (explained || std::find(run.begin(), run.end(), i) != run.end()) return;
      if (!faint) empty = false;
      else faint_flux_dn += h.flux_dn;
    });
    if (empty && faint_flux_dn < 0.5 * dash_flux) {
      // (not where the pixels show a dash there: merged into another star's image the flux rule let
      // through, or no detection at all)
      const DashInPixels seen = DashInScan(c, all, path, last_dash_s - 30.0 * m, dash_length, dash_flux);
      if (seen.shown) return false;
      break;
    }
    // Something at dash m's place: the run's own dash mismeasured (merged with a neighbour, cut, shaped
    // wrong) where the run goes on, one dash (single, or the last of merged ones) at the place before it.
    if (!o.ablation.flow_lone_held_dashes) return false;
    // Where the pixels are there to ask (LinkTrails given the scan): no light of a dash at the place beside the
    // holder's (a foreign image by the empty place before the run) is the run's end; a dash's light there
    // (merged with the holder) is the run's own dash as above.
    const DashInPixels seen = DashInScan(c, all, path, last_dash_s - 30.0 * m, dash_length, dash_flux);
    if (seen.absent) break;
    const Explained next = explain(m + 1);
    if ((next.k <= 0 || next.off) && !seen.shown) return false;
    ++m;  // dash m held by an image not its own measurement: not tagged
    continue;
  }
  // The run's length must be a trail's. A run going on beyond the format (m of its dashes seen: a trail
  // entering the format) has no count: the number is the one of at least m dashes under which none of the
  // star's other trails lies on the format where nothing is (the trails before it lie further back on its
  // arc, those after it further on) -- exactly one.
  int trail = -1;
  if (!off_format) {
    for (size_t t = 0; t < c.per_trail.size(); ++t)
      if (FirstDot(c.per_trail[t]) == m) trail = static_cast<int>(t);
  } else {
    // The star's dash flux from its faintest dash (seed or separator): a blend only adds flux, and too much
    // would empty its other trails' places.
    double dash_flux_dn = d.flux_dn;
    for (const auto& [k, i] : best->program)
      if (ex[k].kind == ExposureKind::kDash && IsEvidence(c, i) && c.images[i].flux_dn > 0)
        dash_flux_dn = std::min(dash_flux_dn, c.images[i].flux_dn);
    for (int u = 0; u < static_cast<int>(c.per_trail.size()); ++u) {
      const int j = best->exposure + FirstDot(c.per_trail[u]) - first_dot;  // the seed's exposure in trail u
      if (FirstDot(c.per_trail[u]) < m || j < 0 || j >= static_cast<int>(c.per_trail[u].size())) continue;
      const double seed_s = c.per_trail[u][j].mid_s, star_flux_per_s = dash_flux_dn / a_dash.duration_s;
      if (SiblingAbsent(c, all, path, p, seed_s, u, star_flux_per_s, trail_of)) {
        // Absence numbers the trail only where the reading shows no other trail of the star: one shown and
        // one absent says a trail is hidden (its dashes merged or lost), not that the reading is wrong.
        const FlowStar shown = CollectAlongFlow(c, all, path, p, seed_s, star_flux_per_s, every_trail & ~(1u << u), nullptr);
        for (const auto& images : shown.taken)
          if (static_cast<int>(images.size()) >= kShownImages) return false;
        continue;
      }
      if (trail >= 0) return false;
      trail = u;
    }
  }
  if (trail < 0) return false;
  const int n = FirstDot(c.per_trail[trail]);  // the run's dashes, m of them seen (seen dash k: exposure n-1-k)
  // The star's other trails must not say another number.
  const auto own = best->sibling_dots.find(trail);
  const int own_dots = own == best->sibling_dots.end() ? 0 : own->second;
  for (const auto& [t, dots] : best->sibling_dots)
    if (t != trail && dots >= kOtherTrailDots && dots >= own_dots) return false;
  // The seed must be taken: as a dash of the run or in the program.
  if (!best->self && std::find(single.begin(), single.end(), dash) == single.end()) return false;

  // The trail under its number: the run's dashes then the program past it.
  out->trail = trail;
  out->flux_per_s = flux_per_s;
  out->taken.clear();
  for (int k = m - 1; k >= 0; --k)
    if (single[k] >= 0) out->taken.push_back({n - 1 - k, single[k]});  // merged dashes are not tagged
  const int shift = n - first_dot;
  for (const auto& [k, i] : best->program) out->taken.push_back({k + shift, i});
  std::vector<std::vector<std::pair<int, int>>> per_trail(c.per_trail.size());
  per_trail[trail] = out->taken;
  const ProgramCover cover = CoverOf(c, per_trail, dash);
  // (A trail entering the format shows its separators and at most the end of its run: one dash besides the
  // seed suffices where its siblings' absence gave the number.)
  const int other_dashes = off_format ? 1 : kOtherDashes;
  return static_cast<int>(out->taken.size()) >= o.tuning.flow_min_images && cover.other_dashes >= other_dashes &&
         cover.durations >= DurationsRequired(c, path, trail, ex[best->exposure].mid_s - ex[first_dot].mid_s);
}

}  // namespace platemeter::trail_internal
