// The trail decoder's frame (decoder.h): the images it reads, the order of its steps, chains and stars,
// the tags, and the result's stars and counts. LinkTrails (trail_linker.h) runs it.
#include "decoder.h"

#include <algorithm>
#include <numeric>
#include <string>
#include <unordered_map>

#include "platemeter/core/error.h"

namespace platemeter {
namespace trail_internal {

TrailDecoder::TrailDecoder(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options, const ScanPixels* scan)
    : images_(images), program_(program), o_(options),
      c_{images, options, {}, {}, {}, false, {}, {}, scan},
      trails_(static_cast<int>(program.leading_dashes.size())) {
  std::string why;
  if (!options.Check(&why)) throw Error("trail options", why);
  c_.per_trail.resize(trails_);
  for (const ShutterExposure& e : BuildShutterSchedule(program)) c_.per_trail[e.trail - 1].push_back(e);
  reference_ = static_cast<int>(std::max_element(program.leading_dashes.begin(), program.leading_dashes.end()) -
                                program.leading_dashes.begin());
  const size_t n = images.size();
  result_.images.resize(n);
  owner_count_.assign(n, 0);
  c_.p.resize(n);
  c_.usable.assign(n, false);
  c_.elongated.assign(n, false);
  std::vector<int> all_ids(n);
  std::iota(all_ids.begin(), all_ids.end(), 0);
  for (size_t i = 0; i < n; ++i) {
    const DetectedStar& d = images[i];
    c_.p[i] = d.point.position_px;
    if (d.point.status != PointStatus::kMeasured || (d.flags & kStarDefect)) {
      if (IsLine(d)) c_.lines.push_back(static_cast<int>(i));
      result_.images[i].reason = TrailReason::kNotStar;
      continue;
    }
    result_.images[i].reason = TrailReason::kUnlinked;
    c_.usable[i] = true;
    c_.elongated[i] = (d.flags & kStarElongated) != 0;
    c_.use_lengths = c_.use_lengths || d.length_px > 0;
    usable_ids_.push_back(static_cast<int>(i));
    if (c_.elongated[i]) dash_ids_.push_back(static_cast<int>(i));
  }
  all_.emplace(c_.p, all_ids, 32.0);
  dashes_.emplace(c_.p, dash_ids_, options.max_dash_spacing_px);
}

TrailLinkResult TrailDecoder::Decode() {
  DecodeRuns();
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (result_.chains[k].trail > 0) Settle(k, chain_[k].grown);
  CheckNumbers();
  const TrailOptions::Ablation& steps = o_.ablation;
  if (steps.grow_siblings) GrowSiblings();
  if (steps.pattern_trails) {
    SeparatorTrails();
    if (steps.grow_siblings) GrowSiblings();
  }
  if (steps.flow_trails) FlowTrails();
  DropMergedImages();
  FormStars();
  return std::move(result_);
}

int TrailDecoder::PushChain(const TrailChain& tc) {
  const int cid = static_cast<int>(result_.chains.size());
  result_.chains.push_back(tc);
  chain_.emplace_back();
  chain_.back().parent = cid;
  return cid;
}

// A new chain of trail s (0-based) found by `step`, a star of its own, with nothing taken yet.
int TrailDecoder::OpenChain(TrailStep step, int s, double flux_per_s, double rate_px_per_s) {
  TrailChain tc;
  tc.decoded_by = step;
  tc.trail = s + 1;
  tc.leading_dashes = program_.leading_dashes[s];
  tc.rate_px_per_s = rate_px_per_s;
  const int cid = PushChain(tc);
  chain_[cid].numbers = 1u << s;
  chain_[cid].flux_per_s = flux_per_s;
  return cid;
}

// A new chain (trail number s, its images (exposure, image)) as a star of its own, through Settle; false
// when refused.
bool TrailDecoder::AddChain(TrailStep step, int s, const Taken& taken, double flux_per_s, double rate_px_per_s,
                            int missed, int min_images) {
  const int cid = OpenChain(step, s, flux_per_s, rate_px_per_s);
  result_.chains[cid].missed_exposures = missed;
  for (const auto& [j, i] : taken) owner_count_[i] = 1;
  return Settle(cid, taken, min_images);
}

int TrailDecoder::Root(int k) {
  while (chain_[k].parent != k) k = chain_[k].parent = chain_[chain_[k].parent].parent;
  return k;
}

void TrailDecoder::Unite(int child_root, int root) {
  chain_[root].numbers |= chain_[child_root].numbers;
  chain_[child_root].parent = root;
}

void TrailDecoder::Ends(int k, double* t0_s, double* t1_s) const {
  *t0_s = 1e300, *t1_s = -1e300;
  for (const auto& [j, i] : chain_[k].kept)
    *t0_s = std::min(*t0_s, result_.images[i].mid_s), *t1_s = std::max(*t1_s, result_.images[i].mid_s);
}

bool TrailDecoder::OnOneArc(const Track& a, double a1_s, const Track& b, double b0_s) const {
  return trail_internal::OnOneArc(o_, a, a1_s, b, b0_s);
}

int TrailDecoder::NumberBySiblingsOf(int k) const {
  PatternTrail pt;
  const int shift = program_.leading_dashes[reference_] - result_.chains[k].leading_dashes;
  for (const auto& [j, i] : chain_[k].kept) pt.taken.push_back({j + shift, i});
  pt.flux_per_s = chain_[k].flux_per_s;
  SiblingGrowth grown;
  return NumberOf(pt, &grown);
}

int TrailDecoder::NumberOf(const PatternTrail& pt, SiblingGrowth* grown) const {
  // A decoded sibling's images are no other number's (they join).
  const auto other_number = [&](int i, int sibling) {
    const int ch = result_.images[i].chain;
    return ch >= 0 && result_.chains[ch].trail != sibling + 1;
  };
  return NumberBySiblings(c_, *all_, pt, reference_, program_.leading_dashes, other_number, grown);
}

void TrailDecoder::Tag(int cid, int j, int i) {
  const ShutterExposure& e = c_.per_trail[result_.chains[cid].trail - 1][j];
  TrailImage& ti = result_.images[i];
  ti.chain = cid;
  ti.assigned = true;
  ti.reason = TrailReason::kNone;
  ti.trail = e.trail;
  ti.kind = e.kind;
  ti.dot_index = e.dot_index;
  ti.dash_index = e.dash_index;
  ti.mid_s = e.mid_s;
}

void TrailDecoder::Untag(int i, TrailReason reason) {
  result_.images[i] = TrailImage{};
  result_.images[i].reason = reason;
}

void TrailDecoder::Refuse(int cid, TrailReason reason) {
  for (const auto& [j, i] : chain_[cid].kept) Untag(i, reason);
  chain_[cid].kept.clear();
  TrailChain& tc = result_.chains[cid];
  tc.trail = 0;
  tc.reason = reason;
  tc.bad_images = 0;
}

// A star may hold each trail number once; otherwise its trails stay stars of their own.
void TrailDecoder::FormStars() {
  std::unordered_map<int, std::vector<int>> members;
  for (int k = 0; k < static_cast<int>(result_.chains.size()); ++k)
    if (Decoded(k)) members[Root(k)].push_back(k);
  std::vector<std::vector<int>> groups;
  for (auto& [root, ks] : members) {
    std::vector<int> numbers;
    for (int k : ks) numbers.push_back(result_.chains[k].trail);
    std::sort(numbers.begin(), numbers.end());
    if (std::adjacent_find(numbers.begin(), numbers.end()) != numbers.end()) {
      for (int k : ks) groups.push_back({k});
    } else {
      std::sort(ks.begin(), ks.end(), [&](int x, int y) { return result_.chains[x].trail < result_.chains[y].trail; });
      groups.push_back(ks);
    }
  }
  std::sort(groups.begin(), groups.end());
  for (const std::vector<int>& g : groups) {
    // (with require_joined every trail tagged has a sibling of its star: the later steps' lone ones too)
    if (o_.require_joined && g.size() < 2) {
      Refuse(g[0], TrailReason::kLoneTrail);
      continue;
    }
    const int s = static_cast<int>(result_.stars.size());
    result_.stars.push_back({g});
    for (int k : g) {
      result_.chains[k].star = s;
      for (int i : result_.chains[k].images) result_.images[i].star = s;
    }
  }
  // The result's counts, from the tags themselves: the steps tag and take tags back, the counts follow.
  result_.assigned_dots = result_.assigned_dashes = result_.bad_images = 0;
  for (TrailChain& tc : result_.chains) tc.bad_images = 0;
  for (const TrailImage& ti : result_.images) {
    if (!ti.assigned) continue;
    (ti.kind == ExposureKind::kDot ? result_.assigned_dots : result_.assigned_dashes)++;
    if (!ti.bad) continue;
    ++result_.bad_images;
    if (ti.chain >= 0) ++result_.chains[static_cast<size_t>(ti.chain)].bad_images;
  }
}

}  // namespace trail_internal

TrailLinkResult LinkTrails(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options, const ScanPixels* scan) {
  return trail_internal::TrailDecoder(images, program, options, scan).Decode();
}

}  // namespace platemeter
