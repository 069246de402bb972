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

#include "evidence.h"
#include "trail_internal.h"

namespace platemeter::trail_internal {

DashInPixels DashInPixelsAt(const Context& c, const Grid& all, const DashPlace& place) {
  const DashInPixelsOptions options;
  // (every detection whose light may reach the window: the longest a dash-long sweep)
  const double reach_px = place.length_px + (options.window_fwhm + 3.0) * place.fwhm_px;
  std::vector<DetectedStar> near;
  all.Near(place.centre_px.x_px, place.centre_px.y_px, reach_px, [&](int i) {
    if (c.usable[i]) near.push_back(c.images[i]);
  });
  return MeasureDashInPixels(*c.scan, place, near, options);
}

bool PixelsMayHoldDash(const Context& c, const Grid& all, const DashPlace& place, const DetectedStar* own) {
  if (!c.scan) return false;
  return DashInPixelsAt(c, all, place).shown || ClippedOnSweep(*c.scan, place, own);
}

namespace {

// Index of the trail's first dot (= its leading dash count).
int FirstDot(const std::vector<ShutterExposure>& ex) {
  int j = 0;
  while (j < static_cast<int>(ex.size()) && ex[j].kind != ExposureKind::kDot) ++j;
  return j;
}

// Whether, under trail number u (the seed at seed_s of that trail), another trail of the star lies on the
// format where nothing could hold it: at least two of its dashes' places inside the format along the flow,
// at least two of them empty and at most one not (a crowd may put an image at one), by flux (CountDashPlaces;
// places beside a much brighter image do not count). The flow predicts a place to flow_tolerance_px over
// hundreds of pixels, so an empty place says the trail is not there.
bool SiblingAbsent(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s, int u,
                   double flux_per_s, const TagOf& tag_of) {
  for (int s = 0; s < static_cast<int>(c.per_trail.size()); ++s) {
    if (s == u) continue;
    const DashPlaces places = CountDashPlaces(c, all, path, p, seed_s, s, flux_per_s, tag_of);
    if (places.inside >= 2 && places.empty >= std::max(2, places.inside - 1)) return true;
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

// The place of a dash of the star dt from the seed, as the flow predicts it.
DashPlace PlaceOnPath(const Context& c, const FlowPath& path, double dt, double dash_length_px, double dash_flux_dn) {
  const PixelPoint q = path.At(dt), v = path.VelocityAt(dt);
  DashPlace place;
  place.centre_px = q;
  place.angle_rad = std::atan2(v.y_px, v.x_px);
  place.length_px = dash_length_px;
  place.fwhm_px = c.o.psf_fwhm_px;
  place.flux_dn = dash_flux_dn;
  place.tolerance_px = FlowTolerance_px(c.o, q, path.At(0.0));  // (the path starts at the seed)
  return place;
}

// What the scan's pixels show at the place of a dash of the star dt from the seed (where LinkTrails was
// given them; nothing measured without them): its thirds fitted with the light of the detections about it
// (MeasureDashInPixels).
DashInPixels DashInScan(const Context& c, const Grid& all, const FlowPath& path, double dt, double dash_length_px,
                        double dash_flux_dn) {
  if (!c.scan) return {};
  return DashInPixelsAt(c, all, PlaceOnPath(c, path, dt, dash_length_px, dash_flux_dn));
}

// A dash read as a lone trail (DecodeLoneTrail): its readings grouped, the run counted back along the flow,
// the trail's number, and the trail taken under it.
class LoneReader {
 public:
  LoneReader(const Context& c, const Grid& all, const FlowPath& path, int dash, const PixelPoint& velocity_px_per_s,
             const std::function<bool(int)>& excluded)
      : c_(c), o_(c.o), all_(all), path_(path), dash_(dash), p_(c.p[dash]), v_(velocity_px_per_s),
        speed_px_per_s_(std::hypot(v_.x_px, v_.y_px)), a_dash_(c.per_trail.front().front()),
        flux_per_s_(c.images[dash].flux_dn / a_dash_.duration_s), excluded_(excluded),
        every_trail_((1u << c.per_trail.size()) - 1u) {}
  bool GroupReadings();
  bool CountRun();
  int Number(const TagOf& tag_of) const;
  bool Take(int trail, LoneTrail* out) const;

 private:
  // Readings of the dash grouped by its time from the trail's first dot: readings in one group predict the
  // same dots and separators (the programs after the runs are alike, the flow autonomous) and differ only in
  // their leading dashes.
  struct Group {
    int trail = -1, exposure = -1;                // a reading of the group (trail, exposure)
    std::vector<std::pair<int, int>> program;     // (exposure, image) past the run, in that reading's trail
    bool self = false;                            // the dash taken as the reading's exposure
    std::map<int, int> sibling_dots;              // per reading's trail: the most dots of another trail
  };
  // The detection explaining dashes from .. from + k - 1 (merged, k > 1): its k and image; k = 0 when none
  // does, -1 when more than one k or image would; off: the place of dash `from` lies beyond the format.
  struct Explained {
    int k = 0, image = -1;
    bool off = false;
  };
  void AddReading(int t, int j);
  Explained Explain(int from) const;
  bool PlaceEmpty(int m, bool* stop) const;
  bool HoldsAnotherDash(int m, const Explained& before) const;
  int NumberEntering(const TagOf& tag_of) const;

  const Context& c_;
  const TrailOptions& o_;
  const Grid& all_;
  const FlowPath& path_;
  const int dash_;
  const PixelPoint p_, v_;
  const double speed_px_per_s_;
  const ShutterExposure& a_dash_;  // a leading dash: every dash lasts 20 s
  const double flux_per_s_;
  const std::function<bool(int)>& excluded_;
  const unsigned every_trail_;
  std::map<long, Group> groups_;  // key: the dash's time from the first dot, 0.1 s
  const Group* best_ = nullptr;
  // The run, counted back from its last dash (m = 0) along the flow: its dashes seen (m of them counted),
  // the image of dash m alone (single), the run's detections, and whether it goes on beyond the format.
  int m_ = 0;
  std::vector<int> single_, run_;
  bool off_format_ = false;
  int first_dot_ = 0, max_dashes_ = 0;
  double last_dash_s_ = 0;  // the run's last dash from the seed
};

void LoneReader::AddReading(int t, int j) {
  const std::vector<ShutterExposure>& ex = c_.per_trail[t];
  const int first_dot = FirstDot(ex);
  const ShutterExposure& e = ex[j];
  const FlowStar own = CollectAlongFlow(c_, all_, path_, p_, e.mid_s, flux_per_s_, 1u << t, excluded_);
  if (own.hits < kOwnTrailImages) return;
  // Dots of the star's other trails under this reading: only the right trail number lines them up.
  const FlowStar whole = CollectAlongFlow(c_, all_, path_, p_, e.mid_s, flux_per_s_, every_trail_ & ~(1u << t), excluded_);
  int sibling_dots = 0;
  for (size_t u = 0; u < whole.taken.size(); ++u) {
    int dots = 0;
    for (const auto& [k, i] : whole.taken[u]) dots += c_.per_trail[u][k].kind == ExposureKind::kDot;
    sibling_dots = std::max(sibling_dots, dots);
  }
  const long key = std::lround(10.0 * (e.mid_s - ex[first_dot].mid_s));
  Group& g = groups_[key];
  g.sibling_dots[t] = std::max(g.sibling_dots[t], sibling_dots);
  if (g.trail >= 0) return;  // the group's program is known from its first reading
  g.trail = t, g.exposure = j;
  for (const auto& [k, i] : own.taken[t]) {
    if (k < first_dot) continue;
    g.program.push_back({k, i});
    g.self |= i == dash_ && k == j;
  }
}

// The dash read as every dash exposure it may be; exactly one group with the images of a candidate, and no
// other group lining up dots of a second trail (then the star is no lone trail: DecodeByFlow left it
// undecided).
bool LoneReader::GroupReadings() {
  for (size_t t = 0; t < c_.per_trail.size(); ++t)
    for (int j = 0; j < static_cast<int>(c_.per_trail[t].size()); ++j) {
      const ShutterExposure& e = c_.per_trail[t][j];
      if (e.kind == ExposureKind::kDash && Compatible(c_, dash_, e, v_, 0.0)) AddReading(static_cast<int>(t), j);
    }
  for (const auto& [key, g] : groups_) {
    if (EvidenceCount(c_, g.program) < kCandidateImages) continue;
    if (best_) return false;
    best_ = &g;
  }
  if (!best_) return false;
  for (const auto& [key, g] : groups_)
    for (const auto& [t, dots] : g.sibling_dots)
      if (&g != best_ && dots >= kOtherTrailDots) return false;
  const std::vector<ShutterExposure>& ex = c_.per_trail[best_->trail];
  first_dot_ = FirstDot(ex);
  last_dash_s_ = ex[first_dot_ - 1].mid_s - ex[best_->exposure].mid_s;
  for (const auto& e : c_.per_trail) max_dashes_ = std::max(max_dashes_, FirstDot(e));
  single_.assign(max_dashes_ + 1, -1);
  return true;
}

// Each step explains dashes m .. m + k - 1 by one detection: a single dash (k = 1) or k dashes merged through
// their 10 s gaps (their centre, (30 k - 10) s of motion long, k dashes' flux); exactly one k.
LoneReader::Explained LoneReader::Explain(int from) const {
  Explained r;
  for (int k = 1; from + k <= max_dashes_ + 1; ++k) {
    const double dt_first = last_dash_s_ - 30.0 * (from + k - 1);
    if (!path_.Covers(dt_first) || !Inside(o_, path_.At(dt_first), o_.edge_margin_px)) {
      r.off = k == 1;
      break;
    }
    const double dt = last_dash_s_ - 30.0 * (from + 0.5 * (k - 1));
    const PixelPoint q = path_.At(dt), vq = path_.VelocityAt(dt);
    const double tol = FlowTolerance_px(o_, q, p_);
    ShutterExposure merged = a_dash_;
    merged.duration_s = a_dash_.duration_s + 30.0 * (k - 1);  // the swept length
    const double merged_flux_per_s = flux_per_s_ * k * a_dash_.duration_s / merged.duration_s;
    int count = 0, image = -1;
    all_.Near(q.x_px, q.y_px, tol, [&](int i) {
      if (!c_.usable[i] || (excluded_ && excluded_(i)) || !Compatible(c_, i, merged, vq, merged_flux_per_s)) return;
      ++count, image = i;
    });
    if (count > 1 || (count == 1 && r.k != 0)) return Explained{-1, -1, false};
    if (count == 1) r.k = k, r.image = image;
  }
  return r;
}

// Dash m absent: nothing may hold it. The flow puts it within its tolerance; a detection holding it (merged
// with another image: at least its flux; the bigger piece of a split: half of it; or a rejected line reaching
// there) lies within half its length and two FWHM of that. Empty, and the pixels (where given) show no dash
// there either (merged into another star's image the flux rule let through, or no detection at all): the
// run's end. Where the pixels show one, or a saturated image the detector does not see into: *stop (no
// decoding).
bool LoneReader::PlaceEmpty(int m, bool* stop) const {
  const double dash_flux = a_dash_.duration_s * flux_per_s_, dash_length = a_dash_.duration_s * speed_px_per_s_;
  const PixelPoint q = path_.At(last_dash_s_ - 30.0 * m);
  if (Blind(o_, q, dash_length)) {  // a dash there would have been lost in a cross: the count stays unknown
    *stop = true;
    return true;
  }
  const double reach_px = 0.5 * dash_length + 2.0 * o_.psf_fwhm_px + o_.flow_tolerance_px;
  bool empty = true;
  double faint_flux_dn = 0;  // pieces of a dash the deblender cut add up
  ForReaching(c_, all_, q, reach_px, [&](int i) {
    const DetectedStar& h = c_.images[i];
    const bool explained = excluded_ && excluded_(i) && CannotHideDash(c_, i, dash_flux);  // another star's
    const bool faint = h.flux_dn > 0 && h.flux_dn < 0.5 * dash_flux && !(h.flags & (kStarCrowded | kStarBlended));
    if (explained || std::find(run_.begin(), run_.end(), i) != run_.end()) return;
    if (!faint) empty = false;
    else faint_flux_dn += h.flux_dn;
  });
  if (!(empty && faint_flux_dn < 0.5 * dash_flux)) return false;
  // (a saturated core on the place: not the run's dash after it, counted last)
  const DetectedStar* after = run_.empty() ? nullptr : &c_.images[run_.back()];
  *stop = PixelsMayHoldDash(c_, all_, PlaceOnPath(c_, path_, last_dash_s_ - 30.0 * m, dash_length, dash_flux), after);
  return true;
}

// Dash m's place held, the place before it a dash. Where the holder is a dash on the place (its length,
// direction and position; not its flux) whose light beyond the run's dash is about the dash before's (half to
// twice it), two stars' dashes are merged there -- stars on one diurnal path a whole number of dash spacings
// apart -- and the dash before may be the other star's: the run may end at m as well as go on, and the count
// is ambiguous (ARunHoldingAMergedDashMayBeTwoStarsRunsEndToEnd). A holder off the place or of another shape
// is the run's own dash mismeasured beside another image, as before.
bool LoneReader::HoldsAnotherDash(int m, const Explained& before) const {
  const double dt = last_dash_s_ - 30.0 * m;
  const PixelPoint q = path_.At(dt), vq = path_.VelocityAt(dt);
  const double dash_dn = a_dash_.duration_s * flux_per_s_;
  const double before_dash_dn = c_.images[before.image].flux_dn / before.k;
  bool merged = false;
  all_.Near(q.x_px, q.y_px, FlowTolerance_px(o_, q, p_), [&](int i) {
    const DetectedStar& h = c_.images[i];
    if (!c_.usable[i] || (excluded_ && excluded_(i)) || h.flux_dn <= 0 || (h.flags & kStarCrowded)) return;
    if (!Compatible(c_, i, a_dash_, vq, 0.0)) return;
    const double excess_dn = h.flux_dn - dash_dn;
    merged |= excess_dn >= 0.5 * before_dash_dn && excess_dn <= 2.0 * before_dash_dn;
  });
  return merged;
}

// The run, counted back from its last dash along the flow: dash m (0 = the last) lies 30 m s before it, up to
// a place inside the format where nothing may hold a dash, or beyond the format's edge. false: not decoded.
bool LoneReader::CountRun() {
  const double dash_flux = a_dash_.duration_s * flux_per_s_, dash_length = a_dash_.duration_s * speed_px_per_s_;
  for (;;) {
    if (m_ > max_dashes_) return false;
    const Explained e = Explain(m_);
    if (e.k < 0) return false;
    if (e.off) {
      // Dash m's own place beyond the format: the run may go on there. (Only a merge reaching beyond it: no
      // such explanation, dash m is judged alone.)
      if (!o_.ablation.flow_entering_trails) return false;
      off_format_ = true;
      return true;
    }
    if (e.k > 0) {
      if (e.k == 1) single_[m_] = e.image;
      run_.push_back(e.image);
      m_ += e.k;
      continue;
    }
    bool stop = false;
    if (PlaceEmpty(m_, &stop)) return !stop;
    // Something at dash m's place: the run's own dash mismeasured (merged with a neighbour, cut, shaped wrong)
    // where the run goes on, one dash (single, or the last of merged ones) at the place before it.
    if (!o_.ablation.flow_lone_held_dashes) return false;
    // Where the pixels are there to ask (LinkTrails given the scan): no light of a dash at the place beside the
    // holder's (a foreign image by the empty place before the run) is the run's end; a dash's light there
    // (merged with the holder) is the run's own dash as above.
    const DashInPixels seen = DashInScan(c_, all_, path_, last_dash_s_ - 30.0 * m_, dash_length, dash_flux);
    if (seen.absent) return true;
    const Explained next = Explain(m_ + 1);
    if ((next.k <= 0 || next.off) && !seen.shown) return false;
    if (next.k > 0 && !next.off && HoldsAnotherDash(m_, next)) return false;
    ++m_;  // dash m held by an image not its own measurement: not tagged
  }
}

// A run going on beyond the format (m of its dashes seen: a trail entering the format) has no count: the
// number is the one of at least m dashes under which none of the star's other trails lies on the format where
// nothing is (the trails before it lie further back on its arc, those after it further on) -- exactly one.
int LoneReader::NumberEntering(const TagOf& tag_of) const {
  const std::vector<ShutterExposure>& ex = c_.per_trail[best_->trail];
  // The star's dash flux from its faintest dash (seed or separator): a blend only adds flux, and too much
  // would empty its other trails' places.
  double dash_flux_dn = c_.images[dash_].flux_dn;
  for (const auto& [k, i] : best_->program)
    if (ex[k].kind == ExposureKind::kDash && IsEvidence(c_, i) && c_.images[i].flux_dn > 0)
      dash_flux_dn = std::min(dash_flux_dn, c_.images[i].flux_dn);
  int trail = -1;
  for (int u = 0; u < static_cast<int>(c_.per_trail.size()); ++u) {
    const int j = best_->exposure + FirstDot(c_.per_trail[u]) - first_dot_;  // the seed's exposure in trail u
    if (FirstDot(c_.per_trail[u]) < m_ || j < 0 || j >= static_cast<int>(c_.per_trail[u].size())) continue;
    const double seed_s = c_.per_trail[u][j].mid_s, star_flux_per_s = dash_flux_dn / a_dash_.duration_s;
    if (SiblingAbsent(c_, all_, path_, p_, seed_s, u, star_flux_per_s, tag_of)) {
      // Absence numbers the trail only where the reading shows no other trail of the star: one shown and one
      // absent says a trail is hidden (its dashes merged or lost), not that the reading is wrong.
      const FlowStar shown = CollectAlongFlow(c_, all_, path_, p_, seed_s, star_flux_per_s, every_trail_ & ~(1u << u), nullptr);
      for (const auto& images : shown.taken)
        if (static_cast<int>(images.size()) >= kShownImages) return -1;
      continue;
    }
    if (trail >= 0) return -1;
    trail = u;
  }
  return trail;
}

// The run's length must be a trail's (entering the format: NumberEntering), and the star's other trails must
// not say another number; -1 otherwise.
int LoneReader::Number(const TagOf& tag_of) const {
  int trail = -1;
  if (!off_format_) {
    for (size_t t = 0; t < c_.per_trail.size(); ++t)
      if (FirstDot(c_.per_trail[t]) == m_) trail = static_cast<int>(t);
  } else {
    trail = NumberEntering(tag_of);
  }
  if (trail < 0) return -1;
  const auto own = best_->sibling_dots.find(trail);
  const int own_dots = own == best_->sibling_dots.end() ? 0 : own->second;
  for (const auto& [t, dots] : best_->sibling_dots)
    if (t != trail && dots >= kOtherTrailDots && dots >= own_dots) return -1;
  return trail;
}

// The trail under its number: the run's dashes then the program past it; the seed taken (as a dash of the run
// or in the program), flow_min_images images, dashes besides the seed, and the exposure durations required.
bool LoneReader::Take(int trail, LoneTrail* out) const {
  if (!best_->self && std::find(single_.begin(), single_.end(), dash_) == single_.end()) return false;
  const std::vector<ShutterExposure>& ex = c_.per_trail[best_->trail];
  const int n = FirstDot(c_.per_trail[trail]);  // the run's dashes, m of them seen (seen dash k: exposure n-1-k)
  out->trail = trail;
  out->flux_per_s = flux_per_s_;
  out->taken.clear();
  for (int k = m_ - 1; k >= 0; --k)
    if (single_[k] >= 0) out->taken.push_back({n - 1 - k, single_[k]});  // merged dashes are not tagged
  const int shift = n - first_dot_;
  for (const auto& [k, i] : best_->program) out->taken.push_back({k + shift, i});
  std::vector<std::vector<std::pair<int, int>>> per_trail(c_.per_trail.size());
  per_trail[trail] = out->taken;
  const ProgramCover cover = CoverOf(c_, per_trail, dash_);
  // (A trail entering the format shows its separators and at most the end of its run: one dash besides the
  // seed suffices where its siblings' absence gave the number.)
  const int other_dashes = off_format_ ? 1 : kOtherDashes;
  return static_cast<int>(out->taken.size()) >= o_.tuning.flow_min_images && cover.other_dashes >= other_dashes &&
         cover.durations >= DurationsRequired(c_, path_, trail, ex[best_->exposure].mid_s - ex[first_dot_].mid_s);
}

}  // namespace

bool DecodeLoneTrail(const Context& c, const Grid& all, const SkyFlow& flow, int dash,
                     const std::function<bool(int)>& excluded, const TagOf& tag_of,
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
  if (!Compatible(c, dash, c.per_trail.front().front(), v, 0.0)) return false;
  if (10.0 * speed < kLoneNotDecodedTolerances * o.flow_tolerance_px) return false;
  const FlowPath path = PlatePath(c, flow, p);
  LoneReader reader(c, all, path, dash, v, excluded);
  if (!reader.GroupReadings() || !reader.CountRun()) return false;
  const int trail = reader.Number(tag_of);
  return trail >= 0 && reader.Take(trail, out);
}

}  // namespace platemeter::trail_internal
