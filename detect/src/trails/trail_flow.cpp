// Trails decoded by the plate's flow (trail_internal.h; docs/trails.md "The plate's flow"): every
// star moves with one flow, so one image of a star at a known time predicts all its other images to
// a fraction of a pixel across the whole plate. A dash read as each exposure it may be (its length)
// predicts the star's ~130 images; only the right reading finds them in several trails (the trails'
// different leading-dash counts shift their dot programs 30 s against each other: a wrong reading
// lines up one trail, or a few dots of each).
#include <algorithm>
#include <cmath>

#include "../median.h"
#include "evidence.h"
#include "trail_internal.h"

namespace platemeter::trail_internal {

namespace {

// The median offset of a reading's images of trail t (0-based) from their places along `path`.
PixelPoint MedianOffset(const Context& c, const FlowPath& path, const std::vector<std::pair<int, int>>& taken, size_t t,
                        double t_origin_s) {
  std::vector<double> dx, dy;
  for (const auto& [j, i] : taken) {
    const PixelPoint q = path.At(c.per_trail[t][j].mid_s - t_origin_s);
    dx.push_back(c.p[i].x_px - q.x_px), dy.push_back(c.p[i].y_px - q.y_px);
  }
  return {detect_internal::Median(dx), detect_internal::Median(dy)};
}

// Flux / duration of each of a reading's evidence images besides the seed.
std::vector<double> EvidenceRates(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken,
                                  int seed) {
  std::vector<double> rate_dn_per_s;
  for (size_t t = 0; t < taken.size(); ++t)
    for (const auto& [j, i] : taken[t])
      if (i != seed && IsEvidence(c, i)) rate_dn_per_s.push_back(c.images[i].flux_dn / c.per_trail[t][j].duration_s);
  return rate_dn_per_s;
}

// The median of those rates over the seed's flux per second: near 1 when the seed's flux is the star's (a
// seed merged with another image reads about 0.5).
double FluxRatio(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken, int seed,
                 double flux_per_s) {
  const std::vector<double> rate_dn_per_s = EvidenceRates(c, taken, seed);
  return rate_dn_per_s.empty() ? 0.0 : detect_internal::Median(rate_dn_per_s) / flux_per_s;
}

// The star's flux per second from a reading's own images, for a blended seed (its flux shared with the
// neighbour it was fitted with): the median rate of the images with a flux; 0 with fewer than 5.
double ImagesFluxPerSecond(const Context& c, const FlowStar& s, int seed) {
  std::vector<double> rate_dn_per_s = EvidenceRates(c, s.taken, seed);
  std::erase_if(rate_dn_per_s, [](double r) { return !(r > 0); });
  return rate_dn_per_s.size() < static_cast<size_t>(kMinFluxImages) ? 0.0 : detect_internal::Median(rate_dn_per_s);
}

// Whether the seed holds more than the reading's images' flux per second x its exposure length
// (kMergedFluxExcess and 4 of its flux sigmas): another image's light merged into it.
bool SeedMerged(const Context& c, const FlowStar& s, int seed, double duration_s) {
  const DetectedStar& d = c.images[seed];
  return HoldsMergedLight(d.flux_dn, d.sigma_flux_dn, ImagesFluxPerSecond(c, s, seed) * duration_s);
}

// DecodeByFlow's evidence of a reading (its images `s`, the seed `dash` at t_origin_s). Decoded: a trail of
// flow_min_images and a second one holding more dots than a wrong reading lines up (without a dash: more,
// at the first trail's offset; below).
// A candidate (another one makes the decision ambiguous): a trail of 5 and a second one with 3 dots.
// Evidence of a reading: the trail with the most images, and the dots of the next best trail. A wrong
// reading lines up one trail of the star (the trails' dot programs are shifted 30 s against each other)
// and at most 2 dots of any other (docs/trails.md, "The plate's flow": the schedule's own shifts), except
// the two readings 120 s off, which line up 8 dots of every trail (and so are always candidates).
struct Evidence {
  int first = 0, second_images = 0, second_dots = 0;  // evidence (IsEvidence; a second trail with a dash)
  int same_offset_dashless = 0;  // ... of a second trail, dash or not, at the first trail's offset, 2 groups
  int any_first = 0, any_second_dots = 0;  // every image taken (the ambiguity test's candidates)
};
// A second trail must show a dash of its own (a separator: the brightest images of its program): a
// group of evenly spaced dots of another star on nearly the same diurnal arc, at the place of a
// neighbouring trail under a reading shifted by a break, lines up with no dash (whole plate: a lone
// trail read under the next number so, 15 wrong tags) -- unless its images sit at the first trail's
// offset (kSameOffset_px) and show two dot groups (another star's group lines up within one). The seed
// is not that dash: every reading puts it at a dash place, so it shows no phase (Denver: a twin path's
// dash read under the next trail, 4 dots of the twin its "second trail", 13 wrong tags).
Evidence ReadingEvidence(const Context& c, const FlowPath& path, const FlowStar& s, double t_origin_s, int dash) {
  const size_t n = s.taken.size();
  std::vector<int> images(n, 0), dots(n, 0), dashes(n, 0), any_dots(n, 0);
  for (size_t t = 0; t < n; ++t)
    for (const auto& [j, i] : s.taken[t]) {
      const bool dot = c.per_trail[t][j].kind == ExposureKind::kDot;
      any_dots[t] += dot;
      if (!IsEvidence(c, i)) continue;
      ++images[t];
      if (dot)
        ++dots[t];
      else
        dashes[t] += i != dash;
    }
  Evidence ev;
  const int top = static_cast<int>(std::max_element(images.begin(), images.end()) - images.begin());
  ev.first = images[top];
  for (size_t t = 0; t < n; ++t) {
    if (static_cast<int>(t) == top || dashes[t] < 1) continue;
    if (dots[t] > ev.second_dots || (dots[t] == ev.second_dots && images[t] > ev.second_images))
      ev.second_dots = dots[t], ev.second_images = images[t];
  }
  const PixelPoint top_offset = MedianOffset(c, path, s.taken[top], top, t_origin_s);
  for (size_t t = 0; t < n; ++t) {
    if (static_cast<int>(t) == top || dots[t] < kDashlessDots) continue;
    if (Dist(MedianOffset(c, path, s.taken[t], t, t_origin_s), top_offset) > kSameOffset_px) continue;
    std::vector<double> groups;
    for (const auto& [j, i] : s.taken[t])
      if (c.per_trail[t][j].kind == ExposureKind::kDot && IsEvidence(c, i)) groups.push_back(c.per_trail[t][j].group);
    if (DistinctCount(groups) >= 2) ev.same_offset_dashless = std::max(ev.same_offset_dashless, dots[t]);
  }
  int any_top = 0;
  for (size_t t = 0; t < n; ++t)
    if (s.taken[t].size() > s.taken[any_top].size()) any_top = static_cast<int>(t);
  ev.any_first = static_cast<int>(s.taken[any_top].size());
  for (size_t t = 0; t < n; ++t)
    if (static_cast<int>(t) != any_top) ev.any_second_dots = std::max(ev.any_second_dots, any_dots[t]);
  return ev;
}

}  // namespace

void AddFlowSamples(const Track& track, const std::vector<double>& t_s, std::vector<PixelPoint>* p,
                    std::vector<PixelPoint>* velocity_px_per_s) {
  if (t_s.empty()) return;
  const auto [lo, hi] = std::minmax_element(t_s.begin(), t_s.end());
  const double margin = 0.1 * (*hi - *lo);
  for (double t : t_s) {
    if (t < *lo + margin || t > *hi - margin) continue;
    p->push_back(track.At(t));
    velocity_px_per_s->push_back(track.VelocityAt(t));
  }
}

ProgramCover CoverOf(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken_per_trail, int seed) {
  ProgramCover cover;
  std::vector<double> durations_s;
  for (size_t t = 0; t < taken_per_trail.size(); ++t)
    for (const auto& [j, i] : taken_per_trail[t]) {
      if (!IsEvidence(c, i)) continue;
      cover.other_dashes += i != seed && c.per_trail[t][j].kind == ExposureKind::kDash;
      durations_s.push_back(c.per_trail[t][j].duration_s);
    }
  cover.durations = DistinctCount(durations_s);
  return cover;
}

FlowPath PlatePath(const Context& c, const SkyFlow& flow, const PixelPoint& p) {
  double t_first_s = 1e300, t_last_s = -1e300;
  for (const auto& ex : c.per_trail)
    for (const ShutterExposure& e : ex) t_first_s = std::min(t_first_s, e.mid_s), t_last_s = std::max(t_last_s, e.mid_s);
  return FlowPath(flow, p, t_last_s - t_first_s, 30.0, [&](const PixelPoint& q) { return Inside(c.o, q, -50.0); });
}

bool OnTwoFlowPaths(const SkyFlow& flow, const std::vector<std::pair<double, PixelPoint>>& images, double off_px) {
  if (images.size() < 2) return false;
  const auto off_from = [&](const std::pair<double, PixelPoint>& origin) {
    double span_s = 0;
    for (const auto& [t_s, p] : images) span_s = std::max(span_s, std::abs(t_s - origin.first));
    const FlowPath path(flow, origin.second, span_s + 30.0);
    int off = 0;
    for (const auto& [t_s, p] : images)
      off += path.Covers(t_s - origin.first) && Dist(path.At(t_s - origin.first), p) > off_px;
    return off;
  };
  return off_from(images.front()) >= kFlowStrayImages && off_from(images.back()) >= kFlowStrayImages;
}

FlowStar CollectAlongFlow(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& origin,
                          double t_origin_s, double flux_per_s, unsigned trail_mask,
                          const std::function<bool(int)>& excluded) {
  const TrailOptions& o = c.o;
  FlowStar out;
  out.flux_per_s = flux_per_s;
  out.taken.resize(c.per_trail.size());
  for (size_t t = 0; t < c.per_trail.size(); ++t) {
    if (!(trail_mask >> t & 1u)) continue;
    const std::vector<ShutterExposure>& ex = c.per_trail[t];
    for (int j = 0; j < static_cast<int>(ex.size()); ++j) {
      const double dt = ex[j].mid_s - t_origin_s;
      if (!path.Covers(dt)) continue;
      const PixelPoint q = path.At(dt);
      if (!Inside(o, q, 0.0)) continue;
      const double tol = FlowTolerance_px(o, q, origin);
      const PixelPoint v = path.VelocityAt(dt);
      int count = 0, image = -1;
      all.Near(q.x_px, q.y_px, tol, [&](int i) {
        if (!c.usable[i] || (excluded && excluded(i)) || !Compatible(c, i, ex[j], v, flux_per_s)) return;
        ++count, image = i;
      });
      if (count != 1) continue;
      out.taken[t].push_back({j, image});
      ++out.hits;
    }
  }
  return out;
}

bool DecodeByFlow(const Context& c, const Grid& all, const SkyFlow& flow, int dash,
                  const std::function<bool(int)>& excluded, FlowStar* out) {
  const TrailOptions& o = c.o;
  const DetectedStar& d = c.images[dash];
  // (point images too: where a dash is at most two FWHM long, Compatible takes them; measured lengths needed)
  const bool blended = (d.flags & kStarBlended) != 0;
  if (!c.use_lengths || d.flux_dn <= 0 || (blended && !o.ablation.flow_blended_seeds) || !IsEvidence(c, dash)) return false;
  const PixelPoint p = c.p[dash];
  const PixelPoint v = flow.Velocity(p);
  const double speed = std::hypot(v.x_px, v.y_px);
  // Every star passing p moves so: the dash must be 20 s of that motion, along it.
  const ShutterExposure* any_dash = nullptr;
  for (const auto& ex : c.per_trail)
    for (const ShutterExposure& e : ex)
      if (e.kind == ExposureKind::kDash && !any_dash) any_dash = &e;
  if (!any_dash || !Compatible(c, dash, *any_dash, v, 0.0)) return false;
  // A slow star (10 s of motion, the shift between some readings, within 4 flow tolerances): a wrong reading
  // lands near its own images, so it must show more (a trail of 12, 8 dots of a second trail, 5 durations: with
  // the usual evidence the whole V <= 8 plate had 19 wrong tags, a lone trail read under another number with 4
  // chance dots of a "second trail"). The slowest stars were once not decoded at all (under 2.5 tolerances);
  // with these counts they tag right and nothing wrong (Denver +95 dots right, the benchmark plate +8).
  const bool slow = 10.0 * speed < kSlowTolerances * o.flow_tolerance_px;
  if (slow && blended) return false;  // (a slow star's wrong readings land near its own images: no flux from them)
  const bool crowded = o.ablation.flow_crowded_readings && !slow;  // the crowd's weaker evidence (below)
  const FlowPath path = PlatePath(c, flow, p);
  const unsigned every_trail = (1u << c.per_trail.size()) - 1u;
  const int need_first = slow ? std::max(kSlowFirst, o.tuning.flow_min_images) : o.tuning.flow_min_images;
  const int need_second_dots = slow ? kSlowSecondTrailDots : kSecondTrailDots;
  const int need_durations = slow ? kSlowDurations : kDurations;
  int readings = 0;
  FlowStar best;
  for (const auto& ex : c.per_trail)
    for (const ShutterExposure& e : ex) {
      // Every exposure the seed may be (by its length): a slow star's 10 s dot measures as its 20 s dash does,
      // and a reading of it as a dash lines up the star's images one dot late. Only one reading may decode.
      if (!Compatible(c, dash, e, v, 0.0)) continue;
      const double flux_per_s = d.flux_dn / e.duration_s;
      // First the reading's own trail (the exposures near the dash): a wrong reading finds little there,
      // and most readings of most dashes stop here.
      const unsigned own = 1u << (e.trail - 1);
      // A blended seed: the reading's images, whatever their flux, give the star's flux per second.
      double reading_flux_per_s = flux_per_s;
      if (blended) {
        if (CollectAlongFlow(c, all, path, p, e.mid_s, 0.0, own, excluded).hits < kOwnTrailImages) continue;
        reading_flux_per_s =
            ImagesFluxPerSecond(c, CollectAlongFlow(c, all, path, p, e.mid_s, 0.0, every_trail, excluded), dash);
        if (!(reading_flux_per_s > 0)) continue;
      }
      // The seed read as one of two stars' dashes merged into one image: two stars on one diurnal path whose
      // times differ by the spacing of two of the program's dashes lie on one place at those dashes, in every
      // trail. Read with the merge's whole flux, a reading one dot group off lines up the brighter durations
      // of the next group; read with the share of one star, the seed finds that star's own images. That
      // reading, a candidate, leaves the decision ambiguous (Denver: two such stars, 8 wrong tags).
      bool merged_candidate = false;
      const double share_flux_per_s = kMergedSeedShare * reading_flux_per_s;
      if (!blended && CollectAlongFlow(c, all, path, p, e.mid_s, share_flux_per_s, own, excluded).hits >= kOwnTrailImages) {
        const Evidence share =
            ReadingEvidence(c, path, CollectAlongFlow(c, all, path, p, e.mid_s, share_flux_per_s, every_trail, excluded),
                            e.mid_s, dash);
        merged_candidate = share.any_first >= kCandidateFirst && share.any_second_dots >= kCandidateDots;
      }
      if (CollectAlongFlow(c, all, path, p, e.mid_s, reading_flux_per_s, own, excluded).hits < kOwnTrailImages) {
        readings += merged_candidate;
        continue;
      }
      FlowStar s = CollectAlongFlow(c, all, path, p, e.mid_s, reading_flux_per_s, every_trail, excluded);
      // The dash itself must be taken as that exposure (alone within the tolerance); a blended seed's flux
      // may fail the reading's: then no other image may be taken there, and the seed joins the reading.
      std::vector<std::pair<int, int>>& own_taken = s.taken[e.trail - 1];
      const auto at_seed = std::find_if(own_taken.begin(), own_taken.end(), [&](const std::pair<int, int>& ji) {
        return c.per_trail[e.trail - 1][ji.first].mid_s == e.mid_s;
      });
      bool self = at_seed != own_taken.end() && at_seed->second == dash;
      if (blended && at_seed == own_taken.end()) {
        const int j_seed = static_cast<int>(&e - c.per_trail[e.trail - 1].data());
        own_taken.insert(std::lower_bound(own_taken.begin(), own_taken.end(), std::make_pair(j_seed, -1)),
                         {j_seed, dash});
        ++s.hits, self = true;
      }
      const Evidence ev = ReadingEvidence(c, path, s, e.mid_s, dash);
      const bool candidate = ev.any_first >= kCandidateFirst && ev.any_second_dots >= kCandidateDots;
      const bool second = ev.second_dots >= need_second_dots ||
                          (crowded && ev.same_offset_dashless >= kDashlessDots);
      const bool decoded = self && ev.first >= need_first && second;
      readings += candidate || decoded || merged_candidate;  // (one timing counts once)
      if (!decoded) continue;
      // Dashes besides the seed: a seed merged with another image (twice its flux) reads the star's 1.2 s
      // dots as 0.6 s ones, its 10 s dots as 6.2 s ones; its own dashes, half the flux expected then, are
      // not taken. Images of at least four of the program's six exposure durations: a reading shifted within
      // the trails maps the star's dots onto other groups, and the flux tolerance (a faint dot's sigma) lets
      // some of those through (on the whole V <= 8 plate: 1.2 s dots read as 0.6 s ones, 10 s as 6.2 s), not all.
      // Where the crowd hides the star's other dashes or durations, other proof of the seed's flux (not slow):
      // many dashes (5) with 3 durations; one dash with 5 durations, or with 4 and the images' flux per
      // second the seed's (FluxRatio within 0.8-1.25; a merged seed reads about 0.5).
      const ProgramCover cover = CoverOf(c, s.taken, dash);
      const bool usual = cover.other_dashes >= kOtherDashes && cover.durations >= need_durations;
      const bool many_dashes = cover.other_dashes >= kManyDashes && cover.durations >= kManyDashesDurations;
      const double ratio = cover.other_dashes >= 1 ? FluxRatio(c, s.taken, dash, flux_per_s) : 0.0;
      const bool one_dash = cover.other_dashes >= 1 &&
                            (cover.durations >= kOneDashDurations ||
                             (cover.durations >= kDurations && ratio > kMinFluxRatio && ratio < 1.0 / kMinFluxRatio));
      if (!usual && (blended || !(crowded && (many_dashes || one_dash)))) continue;  // (not a blended seed's flux)
      // A seed holding more light than the reading's images give its exposure is merged with another image.
      // Read with its own flux it lines up brighter or later dots (Denver: KS12778's D21s, each merged with
      // another image, 1.25 times a dash; one read as a dash timed the star's dots one late, the other trails'
      // merged D21s its dashes: 14 wrong tags once flow trails kept their unverified images).
      if (!blended && SeedMerged(c, s, dash, e.duration_s)) continue;
      s.seed_s = e.mid_s;
      best = std::move(s);
    }
  if (readings != 1 || best.hits == 0) return false;
  *out = std::move(best);
  return true;
}

}  // namespace platemeter::trail_internal
