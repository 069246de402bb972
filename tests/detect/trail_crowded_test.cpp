// Duty-cycle trails in a crowded field (docs/trails.md, "Crowded fields"):
// the simulator's true trail images of a whole Orbigon plate with catalog
// stars to V = 7 (thousands of trails crossing), reduced to what a detector
// sees: images closer than one FWHM (a dot on a dash's segment included) are
// one detection (flux-weighted centre, summed flux: blends, lost and merged
// leading dashes, strays on the track), faint ones dropped. A merged detection
// is right only when tagged as its dominant image (at least half its flux).
// No rendering: runs in a few seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/detect/trail_linker.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/orbigon_trails.h"

namespace platemeter {
namespace {

using testing::OrbigonFormatOutline_px;
using testing::OrbigonTrailSpec;
using testing::SecondsAfter0530;

// A whole Orbigon plate with the catalog stars to magnitude_limit (V = 7: thousands of crossing trails).
std::string FieldSpec(double magnitude_limit) { return OrbigonTrailSpec("crowded-trails", magnitude_limit, 5.0, 6000.0); }

struct TrueImage {
  const MeasuredPoint* truth;
  PixelPoint p, a, b;  // centre and segment ends (px)
  double flux = 0, length_px = 0, angle_deg = 0;
};

double PointSegment(const PixelPoint& p, const PixelPoint& a, const PixelPoint& b) {
  const double dx = b.x_px - a.x_px, dy = b.y_px - a.y_px, l2 = dx * dx + dy * dy;
  const double u = l2 > 0 ? std::clamp(((p.x_px - a.x_px) * dx + (p.y_px - a.y_px) * dy) / l2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x_px - a.x_px - u * dx, p.y_px - a.y_px - u * dy);
}

int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The detections a detector would make of a simulated plate's true trail images (those `keep` accepts).
struct Field {
  sim::SimulatedPlate plate;
  std::vector<TrueImage> all;
  std::vector<DetectedStar> found;
  std::vector<std::vector<int>> members;  // true images of each detection
  std::map<std::string, int> images_per_trail, dominant_per_trail;
  TrailOptions options;
};

std::unique_ptr<Field> BuildField(const std::string& spec, const std::function<bool(const MeasuredPoint&)>& keep) {
  auto field = std::make_unique<Field>();
  field->plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "crowded.toml"), DefinitionRegistry());
  const sim::SimulatedPlate& plate = field->plate;
  const double fwhm_px = 30.0 / 12.5;
  std::vector<TrueImage>& all = field->all;
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& t = plate.truth[i];
    if ((t.kind != PointKind::kTrailDot && t.kind != PointKind::kTrailDash) || plate.truth_mark[i] < 0 || !keep(t)) continue;
    const sim::SceneMark& m = plate.scene.marks[static_cast<size_t>(plate.truth_mark[i])];
    const double sx = m.px_from_um[0] * m.segment_u_um + m.px_from_um[1] * m.segment_v_um;
    const double sy = m.px_from_um[2] * m.segment_u_um + m.px_from_um[3] * m.segment_v_um;
    TrueImage im{&t, {*t.x_px, *t.y_px}, {*t.x_px - sx / 2, *t.y_px - sy / 2}, {*t.x_px + sx / 2, *t.y_px + sy / 2}};
    im.flux = std::abs(m.amplitude_dn);
    im.length_px = std::hypot(sx, sy);
    im.angle_deg = std::atan(sy / (sx != 0 ? sx : 1e-12)) * 180.0 / std::numbers::pi;
    all.push_back(im);
  }
  // Faint images (the 0.6-1.2 s dots of the fainter stars) are not detected: the faintest quarter.
  std::vector<double> fluxes;
  for (const TrueImage& im : all) fluxes.push_back(im.flux);
  std::nth_element(fluxes.begin(), fluxes.begin() + fluxes.size() / 4, fluxes.end());
  const double min_flux = fluxes[fluxes.size() / 4];
  // Images within one FWHM of each other (segments: of the other's segment) are one detection.
  const int n = static_cast<int>(all.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::unordered_map<long long, std::vector<int>> cells;
  const double cell = 16.0;
  auto key = [&](long x, long y) { return (static_cast<long long>(x) << 32) ^ (y & 0xffffffffLL); };
  for (int i = 0; i < n; ++i)
    cells[key(std::lround(all[i].p.x_px / cell), std::lround(all[i].p.y_px / cell))].push_back(i);
  for (int i = 0; i < n; ++i) {
    const long cx = std::lround(all[i].p.x_px / cell), cy = std::lround(all[i].p.y_px / cell);
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells.find(key(cx + dx, cy + dy));
        if (it == cells.end()) continue;
        for (int j : it->second) {
          if (j <= i) continue;
          const double d = std::min(PointSegment(all[i].p, all[j].a, all[j].b), PointSegment(all[j].p, all[i].a, all[i].b));
          if (d < fwhm_px) parent[Root(parent, i)] = Root(parent, j);
        }
      }
  }
  std::map<int, std::vector<int>> groups;
  for (int i = 0; i < n; ++i) groups[Root(parent, i)].push_back(i);
  for (const auto& [root, g] : groups) {
    double f = 0, x = 0, y = 0;
    int dominant = g[0];
    for (int i : g) {
      f += all[i].flux, x += all[i].flux * all[i].p.x_px, y += all[i].flux * all[i].p.y_px;
      if (all[i].flux > all[dominant].flux) dominant = i;
    }
    if (f < min_flux) continue;
    DetectedStar d;
    d.point.kind = PointKind::kStar;
    d.point.status = PointStatus::kMeasured;
    const int k = static_cast<int>(field->found.size());
    d.point.position_px = {x / f + 0.03 * std::sin(1.7 * k), y / f + 0.03 * std::cos(2.3 * k)};
    d.point.sigma_x_px = d.point.sigma_y_px = 0.03;
    d.flux_dn = f;
    d.sigma_flux_dn = 0.02 * f;
    d.length_px = all[dominant].length_px;
    d.sigma_length_px = 0.1;
    d.angle_deg = all[dominant].angle_deg;
    if (d.length_px > fwhm_px) d.flags = kStarElongated;
    field->found.push_back(d);
    field->members.push_back(g);
  }
  // Whole trails (every image of the trail a detection's dominant image): the coverage's denominator.
  for (const TrueImage& im : all) field->images_per_trail[im.truth->star_id + im.truth->trail]++;
  for (const std::vector<int>& g : field->members) {
    int dominant = g[0];
    for (int i : g) dominant = all[i].flux > all[dominant].flux ? i : dominant;
    field->dominant_per_trail[all[dominant].truth->star_id + all[dominant].truth->trail]++;
  }
  TrailOptions& to = field->options;
  to.psf_fwhm_px = fwhm_px;
  to.max_dash_spacing_px = 40.0;  // 30 s at the fastest rate (~0.94 px/s at 12.5 um)
  to.exposed_outline_px = OrbigonFormatOutline_px(plate);  // the simulator draws no image outside the format
  return field;
}

struct Score {
  long right = 0;       // unmerged dots of whole trails tagged right
  long clean_dots = 0;  // unmerged dots of whole trails
  long wrong = 0;       // detections tagged other than their dominant image
  long mixing = 0;      // linker stars holding images of several truth stars
};

// The true image holding most of detection k's flux.
const MeasuredPoint& DominantTruth(const Field& field, size_t k) {
  const std::vector<int>& g = field.members[k];
  int dominant = g[0];
  for (int i : g) dominant = field.all[i].flux > field.all[dominant].flux ? i : dominant;
  return *field.all[dominant].truth;
}

// The leading dashes of a true image's trail (Table 1 defaults: T1..T4 lead with 2..5).
int LeadingDashes(const MeasuredPoint& t) { return std::stoi(t.trail.substr(1)) + 1; }

// A merged detection is right only when tagged as its dominant image (a close double star's images
// coincide all along its trails: the tags hold for both).
Score ScoreField(const Field& field, const TrailLinkResult& r, bool report) {
  Score score;
  std::map<int, std::set<std::string>> star_truths;
  for (size_t k = 0; k < field.found.size(); ++k) {
    const TrailImage& ti = r.images[k];
    const std::vector<int>& g = field.members[k];
    const MeasuredPoint& first = *field.all[g[0]].truth;
    const auto dominant_it = field.dominant_per_trail.find(first.star_id + first.trail);
    const bool whole = dominant_it != field.dominant_per_trail.end() &&
                       dominant_it->second == field.images_per_trail.at(first.star_id + first.trail);
    const bool clean_dot = g.size() == 1 && first.kind == PointKind::kTrailDot && whole;
    score.clean_dots += clean_dot;
    if (!ti.assigned) continue;
    const MeasuredPoint& t = DominantTruth(field, k);
    const bool dot = ti.kind == ExposureKind::kDot;
    const bool ok = (t.kind == PointKind::kTrailDot) == dot && t.trail == "T" + std::to_string(ti.trail) &&
                    *t.dot == (dot ? ti.dot_index : ti.dash_index) &&
                    std::abs(SecondsAfter0530(t.mid_time_utc) - ti.mid_s) < 0.0015;
    if (ok) star_truths[ti.star].insert(t.star_id);
    score.wrong += !ok;
    score.right += ok && clean_dot && dot;
    if (!ok && report && score.wrong <= 5)
      ADD_FAILURE() << "tagged T" << ti.trail << " " << ti.dot_index << "/" << ti.dash_index << " is " << first.id
                    << " (+" << g.size() - 1 << " merged)";
  }
  for (const auto& [s, ids] : star_truths) score.mixing += ids.size() > 1;
  return score;
}

// A step's gain: the field linked with `options` and with `off` applied to them; prints both, expects
// no wrong tag either way and returns (with, without).
std::pair<Score, Score> WithAndWithout(const char* name, const Field& field, const TrailOptions& options,
                                       const std::function<void(TrailOptions*)>& off) {
  const Score with = ScoreField(field, LinkTrails(field.found, DutyCycleScheduleOptions{}, options), true);
  TrailOptions without_options = options;
  off(&without_options);
  const Score without = ScoreField(field, LinkTrails(field.found, DutyCycleScheduleOptions{}, without_options), false);
  std::printf("[%s] %ld unmerged dots of whole trails, %ld tagged right, %ld wrong (without: %ld, %ld)\n", name,
              with.clean_dots, with.right, with.wrong, without.right, without.wrong);
  EXPECT_EQ(with.wrong, 0);
  EXPECT_EQ(without.wrong, 0);
  return {with, without};
}

TEST(TrailCrowded, NoImageOfACrowdedFieldIsTaggedWrongly) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const auto field = BuildField(FieldSpec(7.0), [](const MeasuredPoint&) { return true; });
  ASSERT_GT(field->all.size(), 50000u) << "not a crowded field";
  const TrailLinkResult r = LinkTrails(field->found, DutyCycleScheduleOptions{}, field->options);
  const Score score = ScoreField(*field, r, true);
  std::printf("[crowded] %zu true images, %zu detections, %ld unmerged dots of whole trails, %ld tagged right, %ld "
              "wrong, %ld linker stars mixing truth stars; %s\n",
              field->all.size(), field->found.size(), score.clean_dots, score.right, score.wrong, score.mixing,
              r.Summary().c_str());
  EXPECT_EQ(score.wrong, 0);
  EXPECT_GT(score.clean_dots, 2000);
  // Trails filled along the flow, beyond their first and last images and in gaps inside them (there only
  // within tight_tolerance_px of the track too): within the flow's tolerance, with the sigmas of the
  // measurement (position floor included).
  long flow_checked = 0, inside_gaps = 0;
  std::map<int, std::pair<double, double>> track_span_s;  // chain -> first, last mid-time of its track's images
  for (size_t k = 0; k < field->found.size(); ++k) {
    const TrailImage& ti = r.images[k];
    if (!ti.assigned || ti.flow_checked) continue;
    auto [it, added] = track_span_s.insert({ti.chain, {ti.mid_s, ti.mid_s}});
    it->second = {std::min(it->second.first, ti.mid_s), std::max(it->second.second, ti.mid_s)};
  }
  for (size_t k = 0; k < field->found.size(); ++k) {
    const TrailImage& ti = r.images[k];
    if (!ti.assigned || !ti.flow_checked) continue;
    ++flow_checked;
    EXPECT_LE(ti.residual_px, field->options.flow_tolerance_px + field->options.tuning.flow_tolerance_fraction * 6000.0);
    EXPECT_GE(ti.sigma_refined_x_px, field->options.position_floor_px);
    if (r.chains[ti.chain].decoded_by == TrailStep::kFlowFill) continue;  // a star's missing trail: no track of its own
    const auto& [t0, t1] = track_span_s.at(ti.chain);
    inside_gaps += ti.mid_s > t0 && ti.mid_s < t1;
  }
  std::printf("[crowded] %ld images filled along the flow, %ld of them in gaps inside their trails\n", flow_checked,
              inside_gaps);
  EXPECT_GT(flow_checked, 100);
  EXPECT_GT(inside_gaps, 0);
  EXPECT_GE(score.right, score.clean_dots * 85 / 100);  // figures in docs/trails.md
  // The same field linked with some steps changed.
  auto rescored = [&](const char* what, const std::function<void(TrailOptions*)>& change) {
    TrailOptions o = field->options;
    change(&o);
    const Score s = ScoreField(*field, LinkTrails(field->found, DutyCycleScheduleOptions{}, o), false);
    std::printf("[crowded, %s] %ld tagged right, %ld wrong\n", what, s.right, s.wrong);
    return s;
  };
  // Without the crowded-field checks the same field is tagged wrongly: the test can fail.
  const Score loose = rescored("checks off", [](TrailOptions* o) {
    o->flux_tolerance = 0;
    o->tuning.run_flux_tolerance = 1e9;
    o->tuning.tight_tolerance_px = 1e9;
    o->tuning.crowd_radius_fwhm = 0;
    o->tuning.max_leverage = 1.0;
    o->tuning.max_median_residual_px = 1e9;
    o->tuning.clean_radius_spacings = 0;
  });
  EXPECT_GT(loose.wrong, 0);
  // Without the sibling growth, the separator seeds and the plate's flow (docs/trails_record.md, "Hidden runs",
  // "The plate's flow") fewer are found; without the flow alone, fewer too; without the lone trails numbered
  // by their runs along the flow ("The plate's flow" 5), fewer.
  const Score runs_only = rescored("leading runs only", [](TrailOptions* o) {
    o->ablation.grow_siblings = o->ablation.pattern_trails = o->ablation.flow_trails = false;
  });
  EXPECT_EQ(runs_only.wrong, 0);
  EXPECT_LT(runs_only.right, score.right * 9 / 10);
  const Score no_flow = rescored("without the flow", [](TrailOptions* o) { o->ablation.flow_trails = false; });
  EXPECT_EQ(no_flow.wrong, 0);
  EXPECT_LT(no_flow.right, score.right);
  const Score no_lone = rescored("without lone trails", [](TrailOptions* o) { o->ablation.flow_lone_trails = false; });
  EXPECT_EQ(no_lone.wrong, 0);
  EXPECT_LT(no_lone.right, score.right);
  // Without the decoded trails filled along the flow, fewer (docs/trails.md).
  const Score no_ends = rescored("without the trails filled along the flow",
                                 [](TrailOptions* o) { o->ablation.flow_fills_trails = false; });
  EXPECT_EQ(no_ends.wrong, 0);
  EXPECT_LT(no_ends.right, score.right);
  // Nor without a decoded star's missing trails filled along the flow.
  const Score no_siblings = rescored("without the stars' missing trails filled along the flow",
                                     [](TrailOptions* o) { o->ablation.flow_fills_siblings = false; });
  EXPECT_EQ(no_siblings.wrong, 0);
  EXPECT_LT(no_siblings.right, score.right);
  // Without the crowded readings (a reading's dashless second trail at its first trail's offset, the seed's
  // flux shown by few dashes: docs/trails.md, "The plate's flow" 4), fewer.
  const Score no_crowded = rescored("without the crowded readings",
                                    [](TrailOptions* o) { o->ablation.flow_crowded_readings = false; });
  EXPECT_EQ(no_crowded.wrong, 0);
  EXPECT_LT(no_crowded.right, score.right);
  // The empty dash places' veto (docs/trails.md, "Empty places") refuses almost no right reading of a
  // crowded field: without it, at most 1 % of the clean dots more right (and none wrong with it, above).
  const Score no_veto = rescored("without the empty dash places' veto",
                                 [](TrailOptions* o) { o->ablation.flow_empty_places = false; });
  EXPECT_LE(no_veto.right, score.right + score.clean_dots / 100);
  // Trails joined to a sibling only (require_joined: no lone or entering trails), fewer, none wrong.
  const Score joined = rescored("joined trails only", [](TrailOptions* o) { o->require_joined = true; });
  EXPECT_EQ(joined.wrong, 0);
  EXPECT_LT(joined.right, score.right);
  // Every star's first separator dash fitted jointly with a neighbour (flag blended, 1.6 x its flux) and its
  // leading runs hidden (crowded pieces, no evidence): the stars decoded through the flow from the blended
  // seeds (docs/trails.md, "The plate's flow" 4) are more, none wrong.
  for (size_t k = 0; k < field->found.size(); ++k) {
    const MeasuredPoint& t = DominantTruth(*field, k);
    if (t.kind != PointKind::kTrailDash) continue;
    const int leading = LeadingDashes(t);
    DetectedStar& d = field->found[k];
    if (*t.dot <= leading) d.flags |= kStarCrowded;
    if (*t.dot == leading + 1) d.flags |= kStarBlended, d.flux_dn *= 1.6;
  }
  const auto [blended, not_blended] = WithAndWithout("blended seeds", *field, field->options,
                                                     [](TrailOptions* o) { o->ablation.flow_blended_seeds = false; });
  EXPECT_GT(blended.right, not_blended.right);
}

// Stars with a single trail on the plate (as where the others leave the format): no sibling can number it,
// only its own run. The runs a crowd hides from the run linker are found along the plate's flow
// (docs/trails.md, "The plate's flow" 5): more trails decoded, none wrongly.
TEST(TrailCrowded, LoneTrailsAreNumberedByTheirRunsAlongTheFlow) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const auto field = BuildField(FieldSpec(7.0), [](const MeasuredPoint& t) {
    unsigned h = 0;  // the star's one trail, from its id
    for (char ch : t.star_id) h = 31 * h + static_cast<unsigned char>(ch);
    return t.trail == "T" + std::to_string(1 + h % 4);
  });
  // (With every option: in a field of lone trails only, a separator-grown trail numbered by a grown sibling
  // found a chance "sibling" among other stars' images, 38 wrong tags on one star, until the flow checked
  // every star's joins: docs/trails.md, "The plate's flow" 2.)
  // This field drops the star's other trails where the format would show them (no plate can): the entering
  // trails' rule reads their absence as evidence against the true number (1028 wrong tags), so it is off here
  // (TrailsEnteringTheFormatAreNumberedByTheirSiblingsAbsence keeps every trail on a smaller format). So is
  // the empty dash places' veto, which reads the same absence as every lone reading being wrong (with it on,
  // the lone trails added 106 right dots here, not the 255 asked below).
  TrailOptions options = field->options;
  options.ablation.flow_entering_trails = false;
  options.ablation.flow_empty_places = false;
  const auto [score, before] =
      WithAndWithout("lone trails", *field, options, [](TrailOptions* o) { o->ablation.flow_lone_trails = false; });
  EXPECT_GT(score.clean_dots, 1000);
  EXPECT_GT(score.right, before.right + score.clean_dots / 20);  // figures in docs/trails.md
  // The dash before the last of every run of 3 dashes or more measured wrong (as merged with a neighbour:
  // 1.5 x its flux, 1.6 x its length, no flag): the runs go on over its place where the dash before it is
  // there (docs/trails.md, "The plate's flow" 5); more right, none wrong.
  for (size_t k = 0; k < field->found.size(); ++k) {
    const MeasuredPoint& t = DominantTruth(*field, k);
    const int leading = LeadingDashes(t);
    if (t.kind != PointKind::kTrailDash || leading < 3 || *t.dot != leading - 1) continue;
    DetectedStar& d = field->found[k];
    d.flux_dn *= 1.5, d.length_px *= 1.6;
  }
  const auto [held, not_held] =
      WithAndWithout("held dashes", *field, options, [](TrailOptions* o) { o->ablation.flow_lone_held_dashes = false; });
  EXPECT_GT(held.right, not_held.right + held.clean_dots / 50);
}

// A trail entering the format (its leading run beyond the edge) has no number of its own, and a star with
// one trail on the format no sibling to number it. Its other trails lie further back on its arc (those
// before it) and further on (those after): under a wrong number some of them fall on the format, where
// the flow predicts their dashes to half a pixel, and nothing is there (docs/trails.md, "Trails entering
// the format"). Here the plate's format is cut to its central 3200 px square: many trails enter it.
TEST(TrailCrowded, TrailsEnteringTheFormatAreNumberedByTheirSiblingsAbsence) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const double lo_px = 1400, hi_px = 4600;
  const auto inside = [&](const MeasuredPoint& t) {
    return *t.x_px > lo_px && *t.x_px < hi_px && *t.y_px > lo_px && *t.y_px < hi_px;
  };
  const auto field = BuildField(FieldSpec(7.0), inside);
  TrailOptions options = field->options;
  options.exposed_outline_px = {{lo_px, lo_px}, {hi_px, lo_px}, {hi_px, hi_px}, {lo_px, hi_px}};
  const auto [score, before] =
      WithAndWithout("entering trails", *field, options, [](TrailOptions* o) { o->ablation.flow_entering_trails = false; });
  EXPECT_GT(score.clean_dots, 1000);
  EXPECT_GT(score.right, before.right + score.clean_dots / 25);  // figures in docs/trails.md
  // An entering trail may show its last dot groups only, and trails leave this format too, some after their
  // run and one or two dot groups: such a lone trail needs only the exposure durations it shows on the format
  // (docs/trails.md, "Trails cut by the format's edge").
  const auto [cut, cut_before] =
      WithAndWithout("cut trails", *field, options, [](TrailOptions* o) { o->ablation.flow_cut_trails = false; });
  EXPECT_GT(cut.right, cut_before.right);
  // A cloud (or a shutter fault) during the last trail: no star's T4 anywhere. Read as absent, it would
  // refute every entering T3 and leave T4 standing; a trail's place counts only where that trail was exposed.
  const auto clouded = BuildField(FieldSpec(7.0), [&](const MeasuredPoint& t) { return inside(t) && t.trail != "T4"; });
  const auto [cloud, cloud_before] =
      WithAndWithout("entering trails, no T4", *clouded, options,
                     [](TrailOptions* o) { o->ablation.flow_entering_trails = false; });
  EXPECT_GE(cloud.right, cloud_before.right);
}

// Trail T3 of every third star (by a hash of its id).
bool EveryThirdStarsT3(const MeasuredPoint& t) {
  unsigned h = 0;
  for (char ch : t.star_id) h = 31 * h + static_cast<unsigned char>(ch);
  return h % 3 == 0 && t.trail == "T3";
}

// The field decoded with the filling of a decoded star's missing trails along the flow and without it: the
// chosen trails' dots (each alone in its detection) tagged right as T3 both ways, and the whole field's score.
struct FillFigures {
  long dots = 0, right = 0, right_before = 0;
  Score with, without;
};
FillFigures FilledTrails(const Field& field, const std::function<bool(const MeasuredPoint&)>& chosen) {
  const auto chosen_right = [&](const TrailLinkResult& r, long* dots) {
    long right = 0;
    *dots = 0;
    for (size_t k = 0; k < field.found.size(); ++k) {
      const MeasuredPoint& t = *field.all[field.members[k][0]].truth;
      if (field.members[k].size() != 1 || !chosen(t)) continue;
      ++*dots;
      const TrailImage& ti = r.images[k];
      right += ti.assigned && ti.kind == ExposureKind::kDot && ti.trail == 3 && ti.dot_index == *t.dot &&
               std::abs(SecondsAfter0530(t.mid_time_utc) - ti.mid_s) < 0.0015;
      if (ti.assigned && ti.chain >= 0 && r.chains[ti.chain].decoded_by == TrailStep::kFlowFill) {
        EXPECT_TRUE(ti.flow_checked);
        EXPECT_LE(ti.residual_px, field.options.flow_tolerance_px + field.options.tuning.flow_tolerance_fraction * 6000.0);
      }
    }
    return right;
  };
  TrailOptions without = field.options;
  without.ablation.flow_fills_siblings = false;
  const TrailLinkResult with_r = LinkTrails(field.found, DutyCycleScheduleOptions{}, field.options);
  const TrailLinkResult without_r = LinkTrails(field.found, DutyCycleScheduleOptions{}, without);
  FillFigures f;
  f.right = chosen_right(with_r, &f.dots);
  f.right_before = chosen_right(without_r, &f.dots);
  f.with = ScoreField(field, with_r, true);
  f.without = ScoreField(field, without_r, false);
  return f;
}

// A star's trail showing a few images only (the rest lost under dust, off the format or too faint) has too
// few for a track of its own. Carried along the flow from the star's decoded trail nearest in time, each
// exposure's place holds its image to the flow's tolerance (docs/trails.md, "The plate's flow" 3). Here
// every third star's T3 keeps five of its dots (one a group).
TEST(TrailCrowded, AStarsSparseTrailIsFilledAlongTheFlowFromItsOtherTrails) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const auto sparse = EveryThirdStarsT3;
  const auto field = BuildField(FieldSpec(7.0), [&](const MeasuredPoint& t) {
    return !sparse(t) || (t.kind == PointKind::kTrailDot && *t.dot % 5 == 0);
  });
  const FillFigures f = FilledTrails(*field, sparse);
  std::printf("[sparse trails] %ld sparse dots detected alone, %ld tagged right (without the filling: %ld); all: %ld "
              "tagged right, %ld wrong (without: %ld, %ld)\n",
              f.dots, f.right, f.right_before, f.with.right, f.with.wrong, f.without.right, f.without.wrong);
  EXPECT_EQ(f.with.wrong, 0);
  EXPECT_EQ(f.without.wrong, 0);
  EXPECT_GT(f.dots, 500);
  // Figures in docs/trails.md.
  EXPECT_GE(f.right, f.dots * 7 / 10);
  EXPECT_LE(f.right_before, f.dots * 3 / 10);
}

// A star's trail cut by the format's edge may show one dot group only: five dots of one duration. Carried
// along the flow, five images at five places (each within the flow's tolerance, of the dot's flux and length)
// are no chance coincidence, though they show one exposure length. Here every third star's T3 keeps its last
// group (dots 21-25, 10 s each).
TEST(TrailCrowded, AStarsTrailShowingOneDotGroupIsFilledAlongTheFlow) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const auto cut = EveryThirdStarsT3;
  const auto field = BuildField(FieldSpec(7.0), [&](const MeasuredPoint& t) {
    return !cut(t) || (t.kind == PointKind::kTrailDot && *t.dot > 20);
  });
  const FillFigures f = FilledTrails(*field, cut);
  std::printf("[one dot group] %ld dots of trails showing one group, detected alone: %ld tagged right (without the "
              "filling: %ld); all: %ld tagged right, %ld wrong (without: %ld, %ld)\n",
              f.dots, f.right, f.right_before, f.with.right, f.with.wrong, f.without.right, f.without.wrong);
  EXPECT_EQ(f.with.wrong, 0);
  EXPECT_GT(f.dots, 200);
  EXPECT_GE(f.right, f.dots * 7 / 10);
  EXPECT_LE(f.right_before, f.dots * 3 / 10);
}

// Trails whose leading runs are wholly lost (merged into crossing images, or under dust) are still
// decoded: a sibling decoded from its own run grows them across the break (their number is its
// number +- 1), and a trail with no decoded sibling is grown from a separator dash and numbered by the
// sibling it can grow under exactly one number. Here every run of trails T2 and T3 is removed (only
// the siblings can number them), then every leading dash of every trail (only the separators remain).
TEST(TrailCrowded, TrailsWithoutTheirLeadingRunAreDecodedFromTheirSiblings) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  auto leading = [](const MeasuredPoint& t) {
    return t.kind == PointKind::kTrailDash && *t.dot <= LeadingDashes(t);
  };
  for (const bool all_trails : {false, true}) {
    const auto field = BuildField(FieldSpec(5.0), [&](const MeasuredPoint& t) {
      return !(leading(t) && (all_trails || t.trail == "T2" || t.trail == "T3"));
    });
    const TrailLinkResult r = LinkTrails(field->found, DutyCycleScheduleOptions{}, field->options);
    const Score score = ScoreField(*field, r, true);
    TrailOptions runs_only = field->options;
    runs_only.ablation.grow_siblings = runs_only.ablation.pattern_trails = runs_only.ablation.flow_trails = false;
    const Score before = ScoreField(*field, LinkTrails(field->found, DutyCycleScheduleOptions{}, runs_only), false);
    std::printf("[no runs: %s] %ld unmerged dots of whole trails, %ld tagged right (leading runs only: %ld), %ld wrong; %s\n",
                all_trails ? "every trail" : "T2, T3", score.clean_dots, score.right, before.right, score.wrong,
                r.Summary().c_str());
    EXPECT_EQ(score.wrong, 0);
    EXPECT_GT(score.clean_dots, 1000);
    // Figures in docs/trails.md.
    EXPECT_GE(score.right, score.clean_dots * (all_trails ? 5 : 8) / 10);
    EXPECT_LE(before.right, score.clean_dots * (all_trails ? 0 : 6) / 10);
  }
}

}  // namespace
}  // namespace platemeter
