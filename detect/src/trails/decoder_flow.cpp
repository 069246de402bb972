// Step 7 (decoder.h): the plate's flow (trail_flow.cpp, docs/trails.md "The plate's flow"): one motion field
// fitted to every decoded trail's track. Joined trails off it are refused; a decoded star's missing trails
// are collected along it (their exposures' times are known); every unassigned dash is read as each exposure
// it may be and a star decoded when exactly one reading finds its images in two trails or more; then lone
// trails, numbered by their runs found along the flow; then the exposures still empty filled along it
// (decoder_flow_fill.cpp).
#include <algorithm>
#include <cmath>
#include <map>

#include "decoder.h"
#include "evidence.h"

namespace platemeter::trail_internal {

void TrailDecoder::FlowTrails() {
  if (!FitFlow()) return;
  CheckTrailsOnFlow();
  CheckJoinsOnFlow();
  CheckSeparatorStars();
  CompleteStars();
  const auto excluded = [&](int i) { return Excluded(i); };
  const std::vector<int> seeds = FlowSeeds();
  // Stars decoded from any of their dashes.
  for (int dash : seeds) {
    if (result_.images[dash].chain >= 0) continue;
    FlowStar star;
    if (!DecodeByFlow(c_, *all_, flow_, dash, excluded, &star)) continue;
    if (ReadingRefuted(dash, star.seed_s, star.taken, star.flux_per_s)) continue;
    const PixelPoint v = flow_.Velocity(c_.p[dash]);
    AddFlowStar(star, std::hypot(v.x_px, v.y_px), -1);
  }
  // Lone trails: stars the loop above left undecided, numbered by their runs (nothing else confirms the
  // number: not with require_joined).
  const TagOf tag_of = TagOfImages();
  if (o_.ablation.flow_lone_trails && !o_.require_joined)
    for (int dash : seeds) {
      if (result_.images[dash].chain >= 0) continue;
      LoneTrail lone;
      if (!DecodeLoneTrail(c_, *all_, flow_, dash, excluded, tag_of, &lone)) continue;
      std::vector<Taken> per_trail(trails_);
      per_trail[lone.trail] = lone.taken;
      double seed_s = std::nan("");  // (the seed is one of the run's dashes it took)
      for (const auto& [j, i] : lone.taken)
        if (i == dash) seed_s = c_.per_trail[lone.trail][j].mid_s;
      if (std::isfinite(seed_s) && LoneNumberRefuted(dash, lone, seed_s, per_trail)) continue;
      const PixelPoint v = flow_.Velocity(c_.p[dash]);
      AddChain(TrailStep::kLone, lone.trail, lone.taken, lone.flux_per_s, std::hypot(v.x_px, v.y_px), 0,
               o_.tuning.flow_min_images);
    }
  CompleteStars();  // the new stars' trails short of flow_min_images in their reading
  if (o_.ablation.flow_fills_trails) FillTrailsAlongFlow();
  if (o_.ablation.flow_fills_siblings) FillMissingSiblings();
}

// The flow fitted to the decoded trails' tracks (those of at least min_exposures_after_run images). A
// polynomial of degree d has (d + 1)(d + 2) / 2 terms: at least as many trails, spread over the plate.
bool TrailDecoder::FitFlow() {
  std::vector<PixelPoint> samples_p, samples_v;
  int sampled_trails = 0;
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k) {
    if (!Decoded(k) || static_cast<int>(chain_[k].kept.size()) < o_.tuning.min_exposures_after_run) continue;
    std::vector<double> ts;
    for (const auto& [j, i] : chain_[k].kept) ts.push_back(result_.images[i].mid_s);
    AddFlowSamples(chain_[k].track, ts, &samples_p, &samples_v);
    ++sampled_trails;
  }
  for (int degree = o_.tuning.flow_degree; degree >= 2 && !flow_.ok(); --degree)
    if (sampled_trails >= (degree + 1) * (degree + 2) / 2) flow_.Fit(samples_p, samples_v, degree);
  return flow_.ok();
}

// A trail's own images lie on one flow path. Its track, a polynomial, may bend across a long gap from one
// star's images onto another's on a path beside it (Kyoto's KS19121 T1 and KS19130 T4, 5 px apart with their
// dots at one place: a run of the one and the other's dots 400 px on made one trail). Good images a FWHM off
// (another star's path, resolved from this one) both ways make the trail two stars' (OnTwoFlowPaths): refused.
void TrailDecoder::CheckTrailsOnFlow() {
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k) {
    if (!Decoded(k) || result_.chains[k].decoded_by == TrailStep::kFlowFill) continue;
    std::vector<std::pair<double, PixelPoint>> images;
    for (const auto& [j, i] : chain_[k].kept)
      if (!result_.images[i].bad) images.push_back({result_.images[i].mid_s, c_.p[i]});
    if (!OnTwoFlowPaths(flow_, images, o_.psf_fwhm_px)) continue;
    chain_[Root(k)].numbers &= ~(1u << (result_.chains[k].trail - 1));
    Refuse(k, TrailReason::kOffFlow);
  }
}

// A star's trails lie on one flow path: each trail's images carried along the flow from the end of the
// star's largest trail nearest in time must mostly land within the flow's tolerance. A trail that does not
// (a "sibling" grown from other stars' images, which the parabola's wider tolerance let through) is not the
// star's: with two trails both go (which one is wrong is unknown), with more the strays.
void TrailDecoder::CheckJoinsOnFlow() {
  std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) trails_of[Root(k)].push_back(k);
  for (const auto& [root, ks] : trails_of) {
    if (ks.size() < 2) continue;
    int ref = ks.front();
    for (int k : ks) ref = chain_[k].kept.size() > chain_[ref].kept.size() ? k : ref;
    std::vector<int> strays;
    for (int k : ks) {
      if (k == ref) continue;
      double ref0_s = 0, ref1_s = 0, k0_s = 0, k1_s = 0;
      Ends(ref, &ref0_s, &ref1_s);
      Ends(k, &k0_s, &k1_s);
      const double t_origin_s = k0_s > ref1_s ? ref1_s : ref0_s;
      const PixelPoint origin = chain_[ref].track.At(t_origin_s);
      const FlowPath path(flow_, origin, std::max(std::abs(k0_s - t_origin_s), std::abs(k1_s - t_origin_s)) + 30.0);
      int on = 0, n = 0;
      for (const auto& [j, i] : chain_[k].kept) {
        const double dt = result_.images[i].mid_s - t_origin_s;
        if (!path.Covers(dt)) continue;
        const PixelPoint q = path.At(dt);
        ++n;
        on += Dist(q, c_.p[i]) <= FlowTolerance_px(o_, q, origin);
      }
      if (2 * on < n) strays.push_back(k);
    }
    if (strays.empty()) continue;
    if (ks.size() == 2) strays = ks;
    for (int k : strays) {
      chain_[root].numbers &= ~(1u << (result_.chains[k].trail - 1));
      Refuse(k, TrailReason::kOffFlow);
    }
  }
}

// Stars of separator trails only (step 6 numbered them by a sibling's raw images, which a wrong number can
// find too) are read as the flow's readings are: from their brightest dash, refused with all their trails
// when their empty places refute the reading (ReadingRefuted). A star holding a trail decoded by its
// run has its number from that run.
void TrailDecoder::CheckSeparatorStars() {
  std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) trails_of[Root(k)].push_back(k);
  for (const auto& [root, ks] : trails_of) {
    if (std::any_of(ks.begin(), ks.end(), [&](int k) { return result_.chains[k].decoded_by != TrailStep::kSeparators; }))
      continue;
    std::vector<Taken> taken(trails_);
    int seed = -1, seed_trail = 0;
    for (int k : ks) {
      const int s = result_.chains[k].trail - 1;
      taken[s] = chain_[k].kept;
      for (const auto& [j, i] : chain_[k].kept)
        if (c_.per_trail[s][j].kind == ExposureKind::kDash && IsEvidence(c_, i) &&
            (seed < 0 || images_[i].flux_dn > images_[seed].flux_dn))
          seed = i, seed_trail = k;
    }
    if (seed < 0 || !ReadingRefuted(seed, result_.images[seed].mid_s, taken, chain_[seed_trail].flux_per_s)) continue;
    for (int k : ks) {
      chain_[root].numbers &= ~(1u << (result_.chains[k].trail - 1));
      Refuse(k, TrailReason::kEmptyPlaces);
    }
  }
}

// Adds the trails of `star` holding enough images to the star of `root` (-1: a new star).
void TrailDecoder::AddFlowStar(const FlowStar& star, double rate_px_per_s, int root) {
  const bool new_star = root < 0;
  // (a decoded star's missing trail: its timing is the star's, its images need only be many enough for the fit)
  const int min_images = root >= 0 ? o_.tuning.flow_min_sibling_images : o_.tuning.flow_min_images;
  for (int s = 0; s < trails_; ++s) {
    if (static_cast<int>(star.taken[s].size()) < min_images) continue;
    if (root >= 0 && (chain_[Root(root)].numbers >> s & 1)) continue;
    // A new star's trail shows its phase: a dash of its own (a reading shifted by one dot of a group, 40 s,
    // lines up the group's other dots but no dash: the separators fall between the dots).
    if (new_star && std::none_of(star.taken[s].begin(), star.taken[s].end(), [&](const std::pair<int, int>& ji) {
          return c_.per_trail[s][ji.first].kind == ExposureKind::kDash && IsEvidence(c_, ji.second);
        }))
      continue;
    const int cid = static_cast<int>(result_.chains.size());
    // (the flow fixes its timing: no leading dashes needed)
    if (!AddChain(TrailStep::kFlow, s, star.taken[s], star.flux_per_s, rate_px_per_s, 0, min_images)) continue;
    if (root < 0) {
      root = cid;
      continue;
    }
    const int r = Root(root);
    Unite(Root(cid), r);
  }
}

// Each decoded star's missing trail s (fn(root, s, k, t_end, origin)), carried from the end (origin at t_end)
// of the star's decoded trail k nearest to it in time (the flow's error grows with the distance carried):
// nearest in number, the most images; the end of its track's own images.
void TrailDecoder::ForMissingTrails(
    const std::function<void(int root, int s, int k, double t_end_s, const PixelPoint& origin)>& fn) {
  std::map<int, std::vector<int>> trails_of;  // star root -> its decoded trails
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) trails_of[Root(k)].push_back(k);
  for (const auto& [root, ks] : trails_of)
    for (int s = 0; s < trails_; ++s) {
      if (chain_[Root(root)].numbers >> s & 1) continue;
      int k = ks.front();
      for (int q : ks) {
        const int dq = std::abs(result_.chains[q].trail - 1 - s), dk = std::abs(result_.chains[k].trail - 1 - s);
        if (dq < dk || (dq == dk && chain_[q].kept.size() > chain_[k].kept.size())) k = q;
      }
      double t0 = 1e300, t1 = -1e300;  // (the track's own images: not those the flow filled beyond them)
      for (const auto& [j, i] : chain_[k].kept)
        if (!result_.images[i].flow_checked)
          t0 = std::min(t0, result_.images[i].mid_s), t1 = std::max(t1, result_.images[i].mid_s);
      if (t0 > t1) continue;  // (a trail of flow-filled images only has no track to carry)
      const double t_end_s = s > result_.chains[k].trail - 1 ? t1 : t0;
      fn(root, s, k, t_end_s, chain_[k].track.At(t_end_s));
    }
}

TagOf TrailDecoder::TagOfImages() const {
  return [this](int i) {
    const TrailImage& ti = result_.images[i];
    return ti.assigned ? ImageTag{ti.trail, ti.mid_s} : ImageTag{};
  };
}

// A reading's places (the seed at seed_s; its images `taken` per trail; docs/trails.md "Empty places"): counted
// at the reading's faintest dash's flux, its dots where the detector cannot have missed them.
DashPlaces TrailDecoder::PlacesOfReading(int dash, double seed_s, const std::vector<Taken>& taken,
                                         double flux_per_s, int max_empty) const {
  return ReadingPlaces(c_, *all_, PlatePath(c_, flow_, c_.p[dash]), c_.p[dash], seed_s,
                       FaintestDashRate(c_, taken, flux_per_s), kDetectedDotSnr * images_[dash].sigma_flux_dn, TagOfImages(),
                       max_empty);
}

// Whether a reading is refused for the places it predicts empty: they must not make it kRefuteOdds times
// likelier wrong than right, nor leave two more places empty than another timing of its seed
// (OtherReadingLikelier).
bool TrailDecoder::ReadingRefuted(int dash, double seed_s, const std::vector<Taken>& taken, double flux_per_s) {
  if (!o_.ablation.flow_empty_places) return false;
  const DashPlaces own = PlacesOfReading(dash, seed_s, taken, flux_per_s);
  bool refuted = EmptyPlacesLogOdds(own) > std::log(kRefuteOdds);
  // Compared with the seed read as each other dash of the program (Lisbon's KS13794, docs/trails_record.md:
  // read one group off, 5 of 46 places empty, leaning right; read right, 0 of 53).
  std::vector<double> rival_seeds_s;
  for (const std::vector<ShutterExposure>& trail : c_.per_trail)
    for (const ShutterExposure& e : trail)
      if (e.kind == ExposureKind::kDash && std::abs(e.mid_s - seed_s) >= kSameExposure_s) rival_seeds_s.push_back(e.mid_s);
  refuted = refuted || RivalLikelier(dash, own, rival_seeds_s, taken, flux_per_s);
  result_.refused_readings += refuted;
  return refuted;
}

// Whether the seed read at one of rival_seeds_s is likelier than its reading `own` (OtherReadingLikelier). Only a
// reading with two empty places or more can be outdone; a rival's count stops where it no longer can.
bool TrailDecoder::RivalLikelier(int dash, const DashPlaces& own, const std::vector<double>& rival_seeds_s,
                                 const std::vector<Taken>& taken, double flux_per_s) const {
  const int own_empty = own.empty + own.dot_empty;
  if (own_empty < 2) return false;
  for (double rival_s : rival_seeds_s)
    if (OtherReadingLikelier(own, PlacesOfReading(dash, rival_s, taken, flux_per_s, own_empty - 2))) return true;
  return false;
}

// Whether a lone trail's reading (its number from its run counted back, the seed at seed_s) is refused for its
// places: refuted as any reading, or another number's reading of the same images likelier by its places
// (OtherReadingLikelier). The run's count then rests on one place that may hold another star's light (Paris's
// KS18071, docs/trails_record.md), and the trail is left untagged.
bool TrailDecoder::LoneNumberRefuted(int dash, const LoneTrail& lone, double seed_s, const std::vector<Taken>& taken) {
  if (!o_.ablation.flow_empty_places) return false;
  const DashPlaces own = PlacesOfReading(dash, seed_s, taken, lone.flux_per_s);
  bool refuted = EmptyPlacesLogOdds(own) > std::log(kRefuteOdds);
  int j_seed = -1;  // the seed's exposure in the trail, and where the runs' lengths put it under trail u
  for (const auto& [j, i] : lone.taken)
    if (i == dash) j_seed = j;
  std::vector<double> rival_seeds_s;
  for (int u = 0; u < trails_ && j_seed >= 0; ++u) {
    const int ju = j_seed + program_.leading_dashes[u] - program_.leading_dashes[lone.trail];
    if (u != lone.trail && ju >= 0 && ju < static_cast<int>(c_.per_trail[u].size()))
      rival_seeds_s.push_back(c_.per_trail[u][ju].mid_s);
  }
  refuted = refuted || RivalLikelier(dash, own, rival_seeds_s, taken, lone.flux_per_s);
  result_.refused_readings += refuted;
  return refuted;
}

// Decoded stars' missing trails collected along the flow.
void TrailDecoder::CompleteStars() {
  ForMissingTrails([&](int root, int s, int k, double t_end_s, const PixelPoint& origin) {
    const FlowStar star = CollectAlongFlow(c_, *all_, PlatePath(c_, flow_, origin), origin, t_end_s,
                                           chain_[k].flux_per_s, 1u << s, [&](int i) { return Excluded(i); });
    const PixelPoint v = flow_.Velocity(origin);
    AddFlowStar(star, std::hypot(v.x_px, v.y_px), root);
  });
}

// The images that may seed a star along the flow, brightest first: every unassigned dash, and where a dash is
// at most two FWHM long (slow stars near the pole) every unassigned point image, since such a dash is often
// measured as a point (Compatible says why; whole V <= 8 plate: +80 dots right, 0 wrong).
std::vector<int> TrailDecoder::FlowSeeds() const {
  std::vector<int> seeds;
  for (int i : dash_ids_)
    if (result_.images[i].chain < 0) seeds.push_back(i);
  for (int i : usable_ids_) {
    if (result_.images[i].chain >= 0 || c_.elongated[i] || images_[i].length_px > 0) continue;
    const PixelPoint v = flow_.Velocity(c_.p[i]);
    const double dash_px = c_.per_trail.front().front().duration_s * std::hypot(v.x_px, v.y_px);
    if (PointMayBeSwept(o_, dash_px)) seeds.push_back(i);
  }
  std::sort(seeds.begin(), seeds.end(), [&](int x, int y) { return images_[x].flux_dn > images_[y].flux_dn; });
  return seeds;
}

}  // namespace platemeter::trail_internal
