// Duty-cycle trails on a simulated Orbigon star-field plate: DetectStars in
// trail mode, then LinkTrails; every assigned image is compared with the
// simulator's truth rows (star, trail, dot index, mid-time, star grouping), the
// positions with the truth and the renderer's Cramer-Rao bounds; the schedule
// of seed 001 Table 1 is the simulator's own (defaults: 2/3/4/5 dashes, 8 min
// breaks). Figures in docs/trails.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/error.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/detect/trail_forced.h"
#include "platemeter/detect/trail_linker.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/render_crb.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/orbigon_trails.h"

namespace platemeter {
namespace {

using testing::OrbigonFormatOutline_px;
using testing::OrbigonTrailSpec;
using testing::SecondsAfter0530;

// The plate of the tests below: catalog stars to V = 2.5 (experiments: TRAIL_MAG) at 12.5 um.
std::string SpecTrails(double magnitude = 2.5, double pixel_size_um = 12.5) {
  return OrbigonTrailSpec("trails", magnitude, magnitude, 2500.0, pixel_size_um, 20.0);
}

TEST(TrailLinker, OptionsAreChecked) {
  TrailOptions o;
  o.match_tolerance = -1;
  EXPECT_THROW(LinkTrails({}, DutyCycleScheduleOptions{}, o), Error);
  TrailOptions flow;
  flow.tuning.flow_min_sibling_images = 5;  // the flow's trails need enough images for the sidereal fit
  EXPECT_THROW(LinkTrails({}, DutyCycleScheduleOptions{}, flow), Error);
  flow = TrailOptions{};
  flow.flow_tolerance_px = 0;
  EXPECT_THROW(LinkTrails({}, DutyCycleScheduleOptions{}, flow), Error);
  // The tuning is checked too, also where it was not before (#27: every setting checked).
  for (const auto& spoil : std::vector<std::function<void(TrailOptions*)>>{
           [](TrailOptions* t) { t->tuning.max_leverage = 0.0; },
           [](TrailOptions* t) { t->tuning.tight_tolerance_px = -0.1; },
           [](TrailOptions* t) { t->tuning.motion_radius_px = 0.0; },
           [](TrailOptions* t) { t->flux_tolerance = -0.5; }}) {
    TrailOptions bad;
    spoil(&bad);
    EXPECT_THROW(LinkTrails({}, DutyCycleScheduleOptions{}, bad), Error);
  }
  EXPECT_TRUE(LinkTrails({}, DutyCycleScheduleOptions{}).images.empty());
}

// The longest 20 s dash of the plate in px: the sidereal rate omega f, stretched by the gnomonic
// projection up to (1 + (r/f)^2) at the format's half diagonal r (what a caller knows beforehand).
double LongestDashPx(double pixel_um) {
  const double f_mm = 80.2, r_mm = 57.0 * std::sqrt(2.0), omega = 7.2921159e-5;
  return 20.0 * omega * f_mm * (1.0 + (r_mm / f_mm) * (r_mm / f_mm)) * 1e3 / pixel_um;
}

// A band of rows of a simulated Orbigon plate through the middle of the trails, detected in trail
// mode and linked; the figures against the simulator's truth.
struct BandRun {
  sim::SimulatedPlate plate;
  long w = 0, h = 0, y0 = 0;
  std::vector<DetectedStar> found;
  TrailOptions options;  // the linker's options used
  TrailLinkResult r;
  std::vector<const MeasuredPoint*> truth;  // trail dots and dashes
  std::map<std::string, bool> inside;       // star + trail -> complete (all 25 dots and N + 4 dashes on the
                                            // plate) and all its images inside the band (10 px margin)
  std::vector<const MeasuredPoint*> match;  // per detection: the truth image within 1.5 px, or nullptr
  std::vector<float> values;                // the band's pixels (rows y0..y0 + h), DN
};

// The band's pixels as a scan (rows outside the band are off it: the band's rows only).
// (`values`: the band's pixels or a copy of them painted over)
ScanPixels BandPixels(const BandRun& b, const std::vector<float>& values) {
  ScanPixels scan;
  scan.read = [&b, &values](const PixelRect& rect, float* values_dn) {
    for (long y = 0; y < rect.height_px; ++y)
      std::copy_n(&values[static_cast<size_t>((rect.y0_px + y - b.y0) * b.w + rect.x0_px)], rect.width_px,
                  values_dn + y * rect.width_px);
  };
  scan.width_px = b.w;
  scan.height_px = b.y0 + b.h;
  scan.dark = true;
  scan.high_dn = 65535.0;
  return scan;
}
ScanPixels BandPixels(const BandRun& b) { return BandPixels(b, b.values); }

BandRun RunBand(const std::string& spec, double pixel_um, long band_rows, double threshold_sigma,
               const std::function<void(sim::Scene*)>& edit_scene = {}) {
  BandRun b;
  b.plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "trails.toml"), DefinitionRegistry());
  if (edit_scene) edit_scene(&b.plate.scene);
  // A band (the whole plate at 12.5 um would be 92 Mpx): pixels small enough that the leading
  // dashes (20 s open, 10 s closed) are resolved.
  std::vector<double> rows;
  for (const MeasuredPoint& t : b.plate.truth)
    if (t.kind == PointKind::kTrailDot) rows.push_back(*t.y_px);
  if (rows.empty()) return b;
  std::nth_element(rows.begin(), rows.begin() + rows.size() / 2, rows.end());
  b.w = b.plate.scene.width_px, b.h = band_rows;
  b.y0 = std::clamp(std::lround(rows[rows.size() / 2]) - b.h / 2, 0L, b.plate.scene.height_px - b.h);
  std::vector<float>& values = b.values;
  values.resize(static_cast<size_t>(b.w * b.h));
  sim::SceneRenderer(b.plate.scene).RenderBand(b.y0, b.h, values.data());
  StarDetectorOptions so;
  so.psf_fwhm_px = std::max(0.8, 30.0 / pixel_um);
  so.max_dash_length_px = LongestDashPx(pixel_um);
  so.pair_chi2_gain = 1e12;  // trail images are single: a 3-10 s dot is a short segment, not a pair
  so.threshold_sigma = threshold_sigma;
  b.found = DetectStarsInBuffer(values.data(), b.w, b.h, 65535.0, so);
  for (DetectedStar& f : b.found) f.point.position_px.y_px += static_cast<double>(b.y0);

  TrailOptions to;
  to.psf_fwhm_px = so.psf_fwhm_px;
  to.max_dash_spacing_px = 1.5 * so.max_dash_length_px;
  to.image_min_px = {0.0, static_cast<double>(b.y0)};
  to.image_max_px = {b.w - 1.0, static_cast<double>(b.y0 + b.h - 1)};
  b.options = to;
  const ScanPixels scan = BandPixels(b);  // (a lone trail's run counted in the pixels where detections cannot)
  b.r = LinkTrails(b.found, DutyCycleScheduleOptions{}, to, &scan);

  for (const MeasuredPoint& t : b.plate.truth)
    if (t.kind == PointKind::kTrailDot || t.kind == PointKind::kTrailDash) b.truth.push_back(&t);
  std::map<std::string, int> images_per_trail;
  for (const auto* t : b.truth) images_per_trail[t->star_id + t->trail]++;
  for (const auto* t : b.truth) {
    const int dashes = std::stoi(t->trail.substr(1)) + 1 + 4;  // T1..T4: 2..5 leading dashes (Table 1 defaults)
    const bool in = *t->y_px > b.y0 + 10 && *t->y_px < b.y0 + b.h - 10 &&
                    images_per_trail[t->star_id + t->trail] == 25 + dashes;
    auto [it, added] = b.inside.insert({t->star_id + t->trail, in});
    if (!added) it->second = it->second && in;
  }
  for (const DetectedStar& f : b.found) {
    const MeasuredPoint* best = nullptr;
    double bd = 1.5;
    for (const auto* t : b.truth) {
      const double d = std::hypot(*t->x_px - f.point.position_px.x_px, *t->y_px - f.point.position_px.y_px);
      if (d < bd) bd = d, best = t;
    }
    b.match.push_back(best);
  }
  return b;
}

// The band of the tests below, built once: catalog stars to V = 3.5, a V = 3.5 point image exposed 10 s
// peaking at 2500 DN over 28 DN of noise, so the 0.6 s dots of the faintest stars are near the
// detection limit (SNR ~6), as seed 001's eighth-magnitude stars on its plates. 12.5 um pixels:
// a 20 s dash is 5-19 px long, its 10 s gaps 2.5-9 px (the PSF's FWHM is 2.4 px).
const BandRun& Band() {
  static const BandRun band = [] {
    // Experiments (docs/trails.md): TRAIL_MAG sets the magnitude limit and reference to another magnitude
    // (more, fainter stars), TRAIL_PIXEL_UM another pixel size.
    const double mag = std::getenv("TRAIL_MAG") ? std::atof(std::getenv("TRAIL_MAG")) : 3.5;
    const double pixel_um = std::getenv("TRAIL_PIXEL_UM") ? std::atof(std::getenv("TRAIL_PIXEL_UM")) : 12.5;
    std::string spec = SpecTrails(mag, pixel_um);
    if (const char* path = std::getenv("TRAIL_SPEC")) {  // experiments: another spec (its pixel size: TRAIL_PIXEL_UM)
      std::ifstream in(path);
      spec.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    return RunBand(spec, pixel_um, static_cast<long>(1400 * 12.5 / pixel_um), 4.0);
  }();
  return band;
}

bool TagsRight(const TrailImage& ti, const MeasuredPoint& t) {
  const bool dot = ti.kind == ExposureKind::kDot;
  return (t.kind == PointKind::kTrailDot) == dot && t.trail == "T" + std::to_string(ti.trail) &&
         *t.dot == (dot ? ti.dot_index : ti.dash_index) && std::abs(SecondsAfter0530(t.mid_time_utc) - ti.mid_s) < 0.0015;
}

TEST(TrailLinker, DecodesTheTrailsOfASimulatedOrbigonPlate) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  const TrailLinkResult& r = b.r;
  ASSERT_EQ(r.images.size(), b.found.size());
  long truth_dots = 0;
  for (const auto* t : b.truth) truth_dots += t->kind == PointKind::kTrailDot && b.inside.at(t->star_id + t->trail);
  std::set<const MeasuredPoint*> good_dots;
  long wrong = 0, assigned_no_truth = 0, bad = 0;
  std::map<int, std::set<std::string>> star_ids;          // linker star -> truth stars
  std::map<std::string, std::set<int>> stars_of_truth;    // truth star -> linker stars
  double before = 0, after = 0, crb = 0, normalised = 0;
  long fitted = 0;
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = r.images[i];
    if (!ti.assigned) continue;
    const MeasuredPoint* t = b.match[i];
    if (!t) {
      ++assigned_no_truth;
      continue;
    }
    if (ti.star >= 0) star_ids[ti.star].insert(t->star_id), stars_of_truth[t->star_id].insert(ti.star);
    if (!TagsRight(ti, *t)) {
      ++wrong;
      ADD_FAILURE() << "image " << i << " tagged T" << ti.trail << (ti.kind == ExposureKind::kDot ? " D" : " L")
                    << (ti.kind == ExposureKind::kDot ? ti.dot_index : ti.dash_index) << " is " << t->id;
      continue;
    }
    if (ti.bad) {
      ++bad;
      continue;
    }
    if (ti.kind != ExposureKind::kDot) continue;
    if (b.inside.at(t->star_id + t->trail)) good_dots.insert(t);
    const PixelPoint p = b.found[i].point.position_px;
    before += std::pow(p.x_px - *t->x_px, 2) + std::pow(p.y_px - *t->y_px, 2);
    after += std::pow(ti.refined_px.x_px - *t->x_px, 2) + std::pow(ti.refined_px.y_px - *t->y_px, 2);
    // The renderer's Cramer-Rao bound of this dot (computed here only for the dots compared: the whole
    // plate's bounds would take most of the test's time).
    const sim::MarkCramerRao bound = sim::CramerRaoBound(
        b.plate.scene, b.plate.scene.marks[static_cast<size_t>(b.plate.truth_mark[t - b.plate.truth.data()])]);
    crb += std::pow(bound.sigma_x_px, 2) + std::pow(bound.sigma_y_px, 2);
    normalised += std::pow((ti.refined_px.x_px - *t->x_px) / ti.sigma_refined_x_px, 2) +
                  std::pow((ti.refined_px.y_px - *t->y_px) / ti.sigma_refined_y_px, 2);
    ++fitted;
  }
  long mixed = 0, joined = 0, split_stars = 0;
  for (const auto& [s, ids] : star_ids) mixed += ids.size() != 1;
  for (const auto& [id, stars] : stars_of_truth) split_stars += stars.size() != 1;
  for (const TrailStar& s : r.stars) joined += s.chains.size() > 1;
  std::map<std::string, long> reasons;
  for (const TrailImage& ti : r.images)
    if (!ti.assigned) reasons[TrailReasonName(ti.reason)]++;
  std::string why;
  for (const auto& [k, n] : reasons) why += k + "=" + std::to_string(n) + " ";
  const double coverage = truth_dots > 0 ? static_cast<double>(good_dots.size()) / truth_dots : 0.0;
  std::printf("[trails] %ldx%ld px, %zu detections, %zu runs, %zu stars (%ld of several trails), %ld truth dots on "
              "trails inside, %zu right (%.1f %%), %ld wrong, %ld assigned without truth, %ld flagged bad; %zu truth "
              "stars decoded, %ld of them in more than one linker star; dot RMS vs truth (px, radial) measured %.4f, "
              "track-refined %.4f, CRB %.4f; refined error / its sigma RMS %.2f per axis; unassigned: %s\n",
              b.w, b.h, b.found.size(), r.chains.size(), r.stars.size(), joined, truth_dots, good_dots.size(),
              100 * coverage, wrong, assigned_no_truth, bad, stars_of_truth.size(), split_stars,
              std::sqrt(before / fitted), std::sqrt(after / fitted), std::sqrt(crb / fitted),
              std::sqrt(normalised / (2.0 * fitted)), why.c_str());
  std::printf("[trails] %s\n", r.Summary().c_str());
  EXPECT_EQ(r.Summary().rfind(std::to_string(r.assigned_dots) + " dots and ", 0), 0u);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(assigned_no_truth, 0);
  EXPECT_EQ(mixed, 0) << "a linker star holds images of two truth stars";
  EXPECT_GE(truth_dots, 50);
  EXPECT_GE(coverage, 0.95);  // issue #5
  EXPECT_LE(after, before);   // the sidereal fit refines the dots' positions
  // With require_joined (lone trails refused too): no wrong tag either; the coverage printed.
  TrailOptions confirm = b.options;
  confirm.require_joined = true;
  const TrailLinkResult rj = LinkTrails(b.found, DutyCycleScheduleOptions{}, confirm);
  long right_joined = 0, wrong_joined = 0;
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = rj.images[i];
    if (!ti.assigned) continue;
    const bool ok = b.match[i] && TagsRight(ti, *b.match[i]);
    wrong_joined += !ok;
    right_joined += ok && ti.kind == ExposureKind::kDot && b.inside.at(b.match[i]->star_id + b.match[i]->trail);
  }
  std::printf("[trails, require_joined] %ld of %ld dots right (%.1f %%), %ld wrong\n", right_joined, truth_dots,
              100.0 * right_joined / truth_dots, wrong_joined);
  EXPECT_EQ(wrong_joined, 0);
  EXPECT_EQ(split_stars, 0) << "the trails of a star not joined";
}

// Per decoded trail lying wholly in the band, its dot `dot_index` (tagged, not bad, SNR >= min_snr): chain ->
// image. Mid-trail dots: at a cut trail's end the track follows an image more (its leverage is high).
std::map<int, size_t> OneDotPerTrail(const BandRun& b, int dot_index, double min_snr) {
  std::map<int, size_t> dots;
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (!ti.assigned || ti.bad || ti.kind != ExposureKind::kDot || ti.dot_index != dot_index || !b.match[i] ||
        !b.inside.at(b.match[i]->star_id + b.match[i]->trail) ||
        b.found[i].flux_dn < min_snr * b.found[i].sigma_flux_dn)
      continue;
    dots[ti.chain] = i;
  }
  return dots;
}

// The unit vector along a decoded trail of the band, from its first image to its last.
PixelPoint AlongTrack(const BandRun& b, int chain) {
  const auto& imgs = b.r.chains[chain].images;
  const PixelPoint a = b.found[imgs.front()].point.position_px, z = b.found[imgs.back()].point.position_px;
  const double n = std::hypot(z.x_px - a.x_px, z.y_px - a.y_px);
  return {(z.x_px - a.x_px) / n, (z.y_px - a.y_px) / n};
}

// Dots displaced by 1 px (12.5 um: a measuring blunder, dust on the dot) are exposed by the
// sidereal fit of their trail: flagged bad, their tags kept, and their refined position (the track
// at their mid time, fitted without them) still on the truth.
TEST(TrailLinker, TheSiderealFitExposesDisplacedDots) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found = b.found;
  // One dot per decoded trail lying wholly in the band (its 12th, a 3.2 s dot, mid-trail), moved 1 px
  // across the track (at a cut trail's end a 1 px shift can hide in the cubic).
  const std::map<int, size_t> moved = OneDotPerTrail(b, 12, 0.0);  // chain -> image
  ASSERT_GE(moved.size(), 5u);
  for (const auto& [chain, i] : moved) {
    const PixelPoint u = AlongTrack(b, chain);
    found[i].point.position_px.x_px += -u.y_px;
    found[i].point.position_px.y_px += u.x_px;
  }
  TrailOptions to = b.options;
  const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
  long exposed = 0, false_bad = 0;
  for (const auto& [chain, i] : moved) {
    const TrailImage& ti = r.images[i];
    const MeasuredPoint& t = *b.match[i];
    EXPECT_TRUE(ti.assigned && TagsRight(ti, t)) << t.id;
    EXPECT_TRUE(ti.bad) << t.id << " residual " << ti.residual_px << " px";
    if (!ti.bad && ti.chain >= 0) {
      std::string ids;
      for (int k : r.chains[ti.chain].images) ids += " " + (b.match[k] ? b.match[k]->id : std::string("?"));
      ADD_FAILURE() << "its trail now:" << ids << "; before: " << b.r.chains[chain].images.size() << " images";
    }
    exposed += ti.bad;
    EXPECT_NEAR(ti.residual_px, 1.0, 0.3) << t.id;
    EXPECT_LT(std::hypot(ti.refined_px.x_px - *t.x_px, ti.refined_px.y_px - *t.y_px), 0.1) << t.id;
  }
  for (size_t i = 0; i < found.size(); ++i) {
    if (!r.images[i].assigned) continue;
    EXPECT_TRUE(b.match[i] && TagsRight(r.images[i], *b.match[i])) << "image " << i;
    false_bad += r.images[i].bad && !b.r.images[i].bad && !moved.count(b.r.images[i].chain);
  }
  std::printf("[bad dots] %zu dots moved by 1 px across their track, %ld exposed, %ld other images newly flagged bad\n",
              moved.size(), exposed, false_bad);
  EXPECT_EQ(false_bad, 0);
}

// Two images closer than the PSF resolves are detected as one, holding both images' light at their
// flux-weighted centre. One dot per decoded trail lying wholly in the band (its 22nd, a 10 s dot, SNR >= 60)
// is so merged with an image of a quarter of its flux 1 px further along the track: the detection holds 1.25
// times the dot's flux (within the growth's flux tolerance of 30 %) and lies 0.2 px along the track from it
// (10-20 of its sigmas). It holds more light than its star gives a 10 s exposure: it is not tagged
// (`blended`), and its trail keeps every other image it had.
TEST(TrailLinker, AnImageHoldingAnotherImagesLightIsNotTheStars) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found = b.found;
  const std::map<int, size_t> merged = OneDotPerTrail(b, 22, 60.0);  // chain -> image
  ASSERT_GE(merged.size(), 5u);
  for (const auto& [chain, i] : merged) {
    const PixelPoint u = AlongTrack(b, chain);
    found[i].point.position_px.x_px += 0.2 * u.x_px;
    found[i].point.position_px.y_px += 0.2 * u.y_px;
    found[i].flux_dn *= 1.25;
    found[i].sigma_flux_dn *= std::sqrt(1.25);
  }
  const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, b.options);
  long refused = 0, others_kept = 0, others_lost = 0;
  for (const auto& [chain, i] : merged) {
    EXPECT_FALSE(r.images[i].assigned) << b.match[i]->id;
    EXPECT_EQ(r.images[i].reason, TrailReason::kBlended) << b.match[i]->id;
    refused += !r.images[i].assigned;
    for (int k : b.r.chains[chain].images) {
      if (static_cast<size_t>(k) == i) continue;
      const bool kept = r.images[k].assigned && b.match[k] && TagsRight(r.images[k], *b.match[k]);
      (kept ? others_kept : others_lost)++;
    }
  }
  for (size_t i = 0; i < found.size(); ++i) {
    if (r.images[i].assigned) EXPECT_TRUE(b.match[i] && TagsRight(r.images[i], *b.match[i])) << "image " << i;
  }
  std::printf("[merged dots] %zu dots given a quarter more light 1 px along their track: %ld not tagged; their "
              "trails' other images kept %ld, lost %ld\n",
              merged.size(), refused, others_kept, others_lost);
  EXPECT_EQ(others_lost, 0);
}

// A decoded trail's dots the detector missed are measured where the trail's track puts them. The band of
// the tests above detected at 10 sigma instead of 4 (the faint stars' 0.6-1.2 s dots, SNR 6-20, missed:
// what a crowded cell's overstated noise does to the whole V <= 8 plate's 4 sigma): every one taken is the right star's right dot (the
// simulator's truth within 1.5 px, its time to 1.5 ms), its position error agrees with its sigma, and the
// band's coverage of dots grows. Under a program shifted by 20 s (the track then predicts each dot half
// an exposure spacing away from it, on empty plate) nothing is taken.
const BandRun& FaintDotsBand() {
  static const BandRun b = RunBand(SpecTrails(3.5), 12.5, 1400, 10.0);
  return b;
}

TEST(TrailLinker, ADecodedTrailsUndetectedDotsAreMeasuredAtItsTrack) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = FaintDotsBand();
  const ScanPixels scan = BandPixels(b);
  TrailOptions to = b.options;
  ForcedDotStats stats;
  const std::vector<ForcedDot> forced = MeasureMissingDots(scan, b.found, b.r, DutyCycleScheduleOptions{}, to, {}, &stats);
  std::set<const MeasuredPoint*> before;  // the linker's right dots of whole trails
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (ti.assigned && !ti.bad && b.match[i] && TagsRight(ti, *b.match[i]) && ti.kind == ExposureKind::kDot &&
        b.inside.at(b.match[i]->star_id + b.match[i]->trail))
      before.insert(b.match[i]);
  }
  long wrong = 0, added = 0, remeasured = 0;
  double err2 = 0, norm2 = 0;
  for (const ForcedDot& f : forced) {
    const PixelPoint p = f.image.point.position_px;
    const MeasuredPoint* t = nullptr;
    double best = 1.5;
    for (const auto* u : b.truth)
      if (const double d = std::hypot(*u->x_px - p.x_px, *u->y_px - p.y_px); d < best) best = d, t = u;
    if (!t || !TagsRight(f.tag, *t)) {
      ++wrong;
      ADD_FAILURE() << "forced dot T" << f.tag.trail << " D" << f.tag.dot_index << " at " << p.x_px << " " << p.y_px
                    << " is " << (t ? t->id : "no truth image");
      continue;
    }
    remeasured += f.replaces >= 0;
    if (b.inside.at(t->star_id + t->trail) && !before.count(t)) ++added;
    const double ex = p.x_px - *t->x_px, ey = p.y_px - *t->y_px;
    err2 += ex * ex + ey * ey;
    norm2 += ex * ex / (f.tag.sigma_refined_x_px * f.tag.sigma_refined_x_px) +
             ey * ey / (f.tag.sigma_refined_y_px * f.tag.sigma_refined_y_px);
  }
  const double n = std::max<double>(1.0, static_cast<double>(forced.size() - wrong));
  std::printf("[forced dots] %ld tried, %ld measured (%ld re-measured detections), %ld wrong; %ld dots of whole trails "
              "added to the linker's %zu; position error RMS %.4f px per axis, RMS(error / sigma) %.2f; refused: "
              "outside %ld, crowded %ld, clipped %ld, failed %ld, faint %ld, off place %ld, off flux %ld\n",
              stats.tried, stats.measured, remeasured, wrong, added, before.size(), std::sqrt(err2 / (2 * n)),
              std::sqrt(norm2 / (2 * n)), stats.outside, stats.crowded, stats.clipped, stats.failed, stats.faint,
              stats.off_place, stats.off_flux);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(stats.measured, static_cast<long>(forced.size()));
  EXPECT_GE(added, 20);
  EXPECT_LT(std::sqrt(norm2 / (2 * n)), 2.0);  // honest sigmas (the linker's own dots: see the first test)

  DutyCycleScheduleOptions shifted;
  shifted.start_s = 20.0;
  ForcedDotStats shifted_stats;
  const std::vector<ForcedDot> none = MeasureMissingDots(scan, b.found, b.r, shifted, to, {}, &shifted_stats);
  std::printf("[forced dots, program shifted by 20 s] %ld tried, %ld measured, %ld off place, %ld faint\n",
              shifted_stats.tried, shifted_stats.measured, shifted_stats.off_place, shifted_stats.faint);
  EXPECT_GE(shifted_stats.tried, stats.tried / 2);
  EXPECT_EQ(none.size(), 0u);
}

// A saturated image beside an undetected dot: its clipped pixels hold no measurement. Where they lie in the
// fit window's corners, beyond window_fwhm FWHM of the dot's sweep, the dot is measured without the pixels
// near them, as right and as honest as without the neighbour; nearer, it is refused (clipped). Here a
// clipped disk (1 px radius, at the film's floor) is painted beside each dot the test above measured (20 or
// more, apart from each other): in the window's corner, then at 1.5 FWHM. (Before, any clipped pixel in the
// window refused the dot: the benchmark plate lost 16 measurable dots so.)
TEST(TrailLinker, AnUndetectedDotBesideASaturatedImageIsMeasuredWhereItsLightIsClear) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = FaintDotsBand();
  const ForcedDotOptions fo;
  const std::vector<ForcedDot> plain = MeasureMissingDots(BandPixels(b), b.found, b.r, DutyCycleScheduleOptions{},
                                                          b.options, fo);
  std::vector<const ForcedDot*> chosen;  // new dots, short (a point's window), 40 px apart, inside the band
  for (const ForcedDot& f : plain) {
    const PixelPoint p = f.image.point.position_px;
    const bool apart = std::none_of(chosen.begin(), chosen.end(), [&](const ForcedDot* c) {
      return std::hypot(c->image.point.position_px.x_px - p.x_px, c->image.point.position_px.y_px - p.y_px) < 40.0;
    });
    if (f.replaces < 0 && f.image.length_px < 1.0 && apart && p.y_px > b.y0 + 20 && p.y_px < b.y0 + b.h - 20)
      chosen.push_back(&f);
  }
  ASSERT_GE(chosen.size(), 20u);
  // Each dot's disk at (d, d) FWHM from it: d = 2.3 puts its nearest pixel 2.6-2.9 FWHM from the sweep, in the
  // window's corner (half width: window_fwhm FWHM beyond the sweep); d = 1.06 puts it at 1.5 FWHM.
  const auto painted = [&](double d_fwhm) {
    std::vector<float> values = b.values;
    for (const ForcedDot* f : chosen) {
      const double fwhm_px = f->image.fwhm_px, half_px = 0.5 * f->image.length_px + fo.window_fwhm * fwhm_px;
      const PixelPoint p = f->image.point.position_px;
      const double cx = p.x_px + d_fwhm * fwhm_px, cy = p.y_px + d_fwhm * fwhm_px;
      bool in_window = false;
      for (long y = std::lround(cy) - 2; y <= std::lround(cy) + 2; ++y)
        for (long x = std::lround(cx) - 2; x <= std::lround(cx) + 2; ++x)
          if (std::hypot(x - cx, y - cy) <= 1.0) {
            values[static_cast<size_t>((y - b.y0) * b.w + x)] = 0.0f;
            in_window = in_window || (std::abs(x - p.x_px) < half_px && std::abs(y - p.y_px) < half_px);
          }
      EXPECT_TRUE(in_window) << "the disk beside the dot at " << p.x_px << " " << p.y_px << " misses its window";
    }
    return values;
  };
  // Each chosen dot measured again on the painted pixels (its tag, within 1 px of its plain place), or none.
  const auto remeasured = [&](const std::vector<float>& values, long* refused_clipped) {
    ForcedDotStats stats;
    const std::vector<ForcedDot> again =
        MeasureMissingDots(BandPixels(b, values), b.found, b.r, DutyCycleScheduleOptions{}, b.options, fo, &stats);
    *refused_clipped = stats.clipped;
    std::vector<std::optional<ForcedDot>> same(chosen.size());
    for (size_t k = 0; k < chosen.size(); ++k)
      for (const ForcedDot& f : again) {
        const PixelPoint p = f.image.point.position_px, q = chosen[k]->image.point.position_px;
        if (f.tag.trail == chosen[k]->tag.trail && f.tag.dot_index == chosen[k]->tag.dot_index &&
            std::hypot(p.x_px - q.x_px, p.y_px - q.y_px) < 1.0)
          same[k] = f;
      }
    return same;
  };
  long clipped_clear = 0, clipped_near = 0;
  const std::vector<std::optional<ForcedDot>> clear = remeasured(painted(2.3), &clipped_clear);
  const std::vector<std::optional<ForcedDot>> near = remeasured(painted(1.06), &clipped_near);
  long measured = 0, right = 0;
  double norm2 = 0, shift2 = 0;
  const auto sq = [](double v) { return v * v; };
  for (size_t k = 0; k < chosen.size(); ++k) {
    EXPECT_FALSE(near[k].has_value()) << "a dot with a clipped pixel 1.5 FWHM away was measured";
    if (!clear[k]) continue;
    ++measured;
    const PixelPoint p = clear[k]->image.point.position_px, q = chosen[k]->image.point.position_px;
    const MeasuredPoint* t = nullptr;
    for (const auto* u : b.truth)
      if (std::hypot(*u->x_px - p.x_px, *u->y_px - p.y_px) < 1.5 && TagsRight(clear[k]->tag, *u)) t = u;
    if (!t) continue;
    ++right;
    const double sx = clear[k]->tag.sigma_refined_x_px, sy = clear[k]->tag.sigma_refined_y_px;
    norm2 += sq((p.x_px - *t->x_px) / sx) + sq((p.y_px - *t->y_px) / sy);
    shift2 += sq((p.x_px - q.x_px) / sx) + sq((p.y_px - q.y_px) / sy);
  }
  const double n = std::max(1.0, 2.0 * static_cast<double>(right));
  std::printf("[forced dots beside a saturated image] of %zu: in the window's corner %ld measured, %ld right, "
              "RMS(error / sigma) %.2f, RMS(shift from the plain fit / sigma) %.3f; at 1.5 FWHM %ld refused as "
              "clipped\n",
              chosen.size(), measured, right, std::sqrt(norm2 / n), std::sqrt(shift2 / n), clipped_near - clipped_clear);
  const long all = static_cast<long>(chosen.size());
  EXPECT_GE(measured, all - all / 10);
  EXPECT_EQ(right, measured);
  EXPECT_LT(std::sqrt(norm2 / n), 1.5);
  EXPECT_LT(std::sqrt(shift2 / n), 0.1);  // the pixels near the disk hold little of the dot's light (0.004)
  EXPECT_GE(clipped_near - clipped_clear, all - all / 10);
}

// A detection the linker left unassigned right where a decoded trail's track puts one of its dots is
// re-measured there as that dot (remeasure): here every fourth dot the linker tagged in the band of the
// first test, untagged again ("unlinked"), comes back with its right tag, replacing its detection.
TEST(TrailLinker, AnUnassignedDetectionAtATracksDotIsRemeasuredAsIt) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  TrailLinkResult r = b.r;
  std::set<int> untagged;
  int n = 0;
  for (size_t i = 0; i < r.images.size(); ++i) {
    TrailImage& ti = r.images[i];
    if (!ti.assigned || ti.bad || ti.kind != ExposureKind::kDot || ++n % 4) continue;
    ti = TrailImage{};
    ti.reason = TrailReason::kUnlinked;
    untagged.insert(static_cast<int>(i));
  }
  ASSERT_GE(untagged.size(), 50u);
  ForcedDotStats stats;
  const std::vector<ForcedDot> forced =
      MeasureMissingDots(BandPixels(b), b.found, r, DutyCycleScheduleOptions{}, b.options, {}, &stats);
  long back = 0, wrong = 0;
  for (const ForcedDot& f : forced) {
    if (!untagged.count(f.replaces)) continue;
    const MeasuredPoint* t = b.match[f.replaces];
    const bool ok = t && TagsRight(f.tag, *t) &&
                    std::hypot(*t->x_px - f.image.point.position_px.x_px, *t->y_px - f.image.point.position_px.y_px) < 1.5;
    back += ok, wrong += !ok;
  }
  std::printf("[re-measured dots] %zu dots untagged, %ld re-measured with their right tags, %ld wrong; %zu dots "
              "measured in all; refused: outside %ld, crowded %ld, clipped %ld, failed %ld, faint %ld, off place %ld, "
              "off flux %ld\n", untagged.size(), back, wrong, forced.size(), stats.outside, stats.crowded, stats.clipped,
              stats.failed, stats.faint, stats.off_place, stats.off_flux);
  EXPECT_EQ(wrong, 0);
  // A true dot at its place is never refused for its place or its flux; the few not back lie near the
  // band's edge, near another image, or are saturated (clipped): refused by design.
  EXPECT_EQ(stats.off_place + stats.off_flux, 0);
  EXPECT_GE(back, static_cast<long>(0.85 * untagged.size()));
}

// A first leading dash lost without trace (not even a defect in its place) makes trail N + 1 look
// like a complete trail N. Such a trail must not be tagged with the wrong number: its re-timed track
// falls on its star's other trails, so it is refused (doubtful_number). A lone trail (its star's
// other trails not decoded: here cut by the band) cannot be checked: require_joined refuses those.
TEST(TrailLinker, ALostLeadingDashNeverRenumbersATrail) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found;
  std::vector<const MeasuredPoint*> match;
  long dropped = 0;
  std::set<std::string> renumbered;  // trails (star + trail) whose first dash is gone
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (ti.assigned && ti.kind == ExposureKind::kDash && ti.dash_index == 1 && ti.trail >= 2) {
      ++dropped;
      if (b.match[i]) renumbered.insert(b.match[i]->star_id + b.match[i]->trail);
      continue;
    }
    found.push_back(b.found[i]);
    match.push_back(b.match[i]);
  }
  ASSERT_GE(dropped, 5);
  TrailOptions to = b.options;
  to.require_joined = true;
  const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
  long wrong = 0, regrown = 0;
  for (size_t i = 0; i < found.size(); ++i) {
    if (!r.images[i].assigned) continue;
    const bool ok = match[i] && TagsRight(r.images[i], *match[i]);
    wrong += !ok;
    regrown += ok && renumbered.count(match[i]->star_id + match[i]->trail);
    EXPECT_TRUE(ok) << (match[i] ? match[i]->id : "?") << " tagged T" << r.images[i].trail;
  }
  std::printf("[lost dashes] first dash of %ld trails T2..T4 removed: %ld wrong tags, %ld images of those trails "
              "tagged right (their runs refused, the trails grown from their siblings), %ld dots tagged\n",
              dropped, wrong, regrown, r.assigned_dots);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(regrown, 20 * dropped);  // a trail's ~30 images, grown back with the right number
  // Default options (lone trails kept): a wrong number only on a lone trail, never on a trail joined
  // to others of its star.
  to.require_joined = false;
  const TrailLinkResult d = LinkTrails(found, DutyCycleScheduleOptions{}, to);
  long wrong_lone = 0, wrong_joined = 0;
  for (size_t i = 0; i < found.size(); ++i) {
    const TrailImage& ti = d.images[i];
    if (!ti.assigned || (match[i] && TagsRight(ti, *match[i]))) continue;
    (ti.star >= 0 && d.stars[ti.star].chains.size() > 1 ? wrong_joined : wrong_lone)++;
  }
  std::printf("[lost dashes, default options] wrong tags on lone trails %ld, on joined trails %ld\n", wrong_lone,
              wrong_joined);
  EXPECT_EQ(wrong_joined, 0);
}

// Houston (docs/trails_record.md, 2026-12-07, stop 49): a first leading dash lost in a reseau cross the
// detector masked leaves no trace, so its trail's run of N - 1 dashes looked like a complete trail N (lone
// trails kept). The decoder is told where the detector was blind (TrailOptions::blind, the detector's
// StarMask): the place before such a run is not empty, and the number needs its siblings.
TEST(TrailLinker, ALeadingDashLostInAMaskedCrossLeavesTheRunsCountInDoubt) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found;
  std::vector<const MeasuredPoint*> match;
  StarMask crosses;  // a mask disk on every removed dash
  crosses.radius_px = 3.0;
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (ti.assigned && ti.kind == ExposureKind::kDash && ti.dash_index == 1 && ti.trail >= 2) {
      crosses.points_px.push_back(b.found[i].point.position_px);
      continue;
    }
    found.push_back(b.found[i]);
    match.push_back(b.match[i]);
  }
  ASSERT_GE(crosses.points_px.size(), 5u);
  const auto wrong_tags = [&](const TrailOptions& to) {
    const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
    long wrong = 0;
    for (size_t i = 0; i < found.size(); ++i) wrong += r.images[i].assigned && !(match[i] && TagsRight(r.images[i], *match[i]));
    return wrong;
  };
  TrailOptions seeing = b.options, blind = b.options;
  blind.blind = crosses;
  const long unaware = wrong_tags(seeing), aware = wrong_tags(blind);
  std::printf("[masked dashes] first dash of %zu trails T2..T4 lost in a mask: %ld wrong tags, %ld told where the "
              "detector was blind\n", crosses.points_px.size(), unaware, aware);
  EXPECT_GT(unaware, 0);  // (the case is real: renumbered lone trails)
  EXPECT_EQ(aware, 0);
  // A mask's geometry (hand-derived): a disk of 3 px widened by an image's reach; arms of half-width 1 px.
  const PixelPoint m = crosses.points_px.front();
  EXPECT_TRUE(crosses.Covers({m.x_px + 4.9, m.y_px}, 2.0));
  EXPECT_FALSE(crosses.Covers({m.x_px + 5.1, m.y_px}, 2.0));
  StarMask arms;
  arms.points_px = {{0.0, 0.0}};
  arms.radius_px = 20.0, arms.arm_reach_px = 1.0;
  EXPECT_TRUE(arms.Covers({15.0, 2.9}, 2.0));    // 2.9 px off the x arm: within 1 + 2
  EXPECT_FALSE(arms.Covers({15.0, 3.1}, 2.0));
  EXPECT_FALSE(arms.Covers({8.0, 8.0}, 2.0));    // between the arms: seen
  EXPECT_FALSE(arms.Covers({22.5, 0.0}, 2.0));   // beyond the arm's reach (20 + 2)
  EXPECT_TRUE(arms.Covers({21.5, 0.0}, 2.0));
}

// Munich (docs/trails_record.md, 2026-12-07, stop 50): a bright star's first leading dashes fused with
// another star's in a saturated clump the detector reported as one image, so its run of the last two
// dashes looked clean before it and was confirmed alone as a whole trail of 2. Where the scan is given, the
// place before a run confirmed by nothing but its clean field is asked in the pixels too: a dash's light
// there, or a clipped pixel (a saturated image the detector does not see into), leaves the count in doubt.
// Here the first leading dash of trails T2..T4 is taken out of the detections: without the pixels the runs
// of N - 1 pass for trails N - 1; with them (the dash's light still there, or a clipped core painted on it)
// none does.
TEST(TrailLinker, ThePixelsBeforeARunConfirmedAloneMustShowNoDash) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found;
  std::vector<const MeasuredPoint*> match;
  std::vector<float> clipped = b.values;  // a clipped core (dark images: the film's floor) on each lost dash
  long lost = 0;
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (ti.assigned && ti.kind == ExposureKind::kDash && ti.dash_index == 1 && ti.trail >= 2) {
      const PixelPoint q = b.found[i].point.position_px;
      for (long y = std::lround(q.y_px) - 1; y <= std::lround(q.y_px) + 1; ++y)
        for (long x = std::lround(q.x_px) - 1; x <= std::lround(q.x_px) + 1; ++x)
          if (y >= b.y0 && y < b.y0 + b.h && x >= 0 && x < b.w) clipped[static_cast<size_t>((y - b.y0) * b.w + x)] = 0.0f;
      ++lost;
      continue;
    }
    found.push_back(b.found[i]);
    match.push_back(b.match[i]);
  }
  ASSERT_GE(lost, 5);
  const auto wrong_tags = [&](const ScanPixels* scan, long* right) {
    const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, b.options, scan);
    long wrong = 0;
    *right = 0;
    for (size_t i = 0; i < found.size(); ++i)
      if (r.images[i].assigned) (match[i] && TagsRight(r.images[i], *match[i]) ? *right : wrong)++;
    return wrong;
  };
  const ScanPixels as_is = BandPixels(b), saturated = BandPixels(b, clipped);
  long right_blind = 0, right_seen = 0, right_clipped = 0;
  const long blind = wrong_tags(nullptr, &right_blind), seen = wrong_tags(&as_is, &right_seen),
             in_clipped = wrong_tags(&saturated, &right_clipped);
  std::printf("[dashes lost to the detections] first dash of %ld trails: %ld wrong tags (%ld right) without the "
              "pixels, %ld (%ld) with them, %ld (%ld) with a clipped core on each\n",
              lost, blind, right_blind, seen, right_seen, in_clipped, right_clipped);
  EXPECT_GT(blind, 0);  // (the case is real)
  EXPECT_EQ(seen, 0);
  EXPECT_EQ(in_clipped, 0);
}

// Lisbon (docs/trails_record.md, 2026-12-07, stop 49): two stars on one diurnal path, one's last leading
// dash on the other's first (merged: both lights), read as one run of their summed count. The merged dash's
// flux is off the run's, so it is not tagged, and the run's count is in doubt: no clean field confirms it.
// Here every decoded trail's run gets another star's dash one spacing before it and its first dash twice
// the light; the band's lone trails (cut by the band) would otherwise be read one number too high.
TEST(TrailLinker, ARunHoldingAMergedDashMayBeTwoStarsRunsEndToEnd) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  std::vector<DetectedStar> found = b.found;
  std::vector<const MeasuredPoint*> match = b.match;
  std::map<int, std::pair<int, int>> run_ends;  // chain -> images of its dashes 1 and 2
  for (size_t i = 0; i < b.found.size(); ++i) {
    const TrailImage& ti = b.r.images[i];
    if (!ti.assigned || ti.kind != ExposureKind::kDash || ti.dash_index > 2) continue;
    auto& ends = run_ends.try_emplace(ti.chain, -1, -1).first->second;
    (ti.dash_index == 1 ? ends.first : ends.second) = static_cast<int>(i);
  }
  long added = 0;
  for (const auto& [chain, ends] : run_ends) {
    if (ends.first < 0 || ends.second < 0) continue;
    const PixelPoint p1 = b.found[ends.first].point.position_px, p2 = b.found[ends.second].point.position_px;
    DetectedStar stray = b.found[ends.first];
    stray.point.position_px = {2 * p1.x_px - p2.x_px, 2 * p1.y_px - p2.y_px};
    found.push_back(stray);
    match.push_back(nullptr);  // (another star's: any tag on it is wrong)
    found[ends.first].flux_dn *= 2.0, found[ends.first].sigma_flux_dn *= std::sqrt(2.0);
    match[ends.first] = nullptr;  // (a blend: its position is neither star's)
    ++added;
  }
  ASSERT_GE(added, 20);
  const auto score = [&](const TrailOptions& to, long* right) {
    const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
    long wrong = 0;
    *right = 0;
    for (size_t i = 0; i < found.size(); ++i)
      if (r.images[i].assigned) (match[i] && TagsRight(r.images[i], *match[i]) ? *right : wrong)++;
    return wrong;
  };
  // The run step and all but the lone trails: none of the summed counts numbers a trail.
  TrailOptions no_lone = b.options;
  no_lone.ablation.flow_lone_trails = false;
  long right = 0, right_lone = 0;
  const long wrong = score(no_lone, &right), wrong_lone = score(b.options, &right_lone);
  std::printf("[merged runs] %ld runs given a stray dash before a merged first dash: %ld wrong tags, %ld right; "
              "with lone trails %ld wrong, %ld right\n", added, wrong, right, wrong_lone, right_lone);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(right, static_cast<long>(0.8 * (b.r.assigned_dots + b.r.assigned_dashes)));  // still decoded
  // With lone trails (the default): a lone trail's count back reaching the merged dash finds room in it for
  // the stray before it, so the run may end there as well as go on; the trail is not numbered.
  EXPECT_EQ(wrong_lone, 0);
  EXPECT_GE(right_lone, right);
}

// Two stars on one diurnal path a fixed time apart merge at every exposure (Lisbon's KS11950 and KS12231,
// 1.2 FWHM apart): each detection holds both, at their flux-weighted centre (neither star's position),
// longer than the exposure's sweep by about their offset (docs/trails.md, "Settle"). The band rendered
// again with a companion of like flux 1.2 FWHM along the path of every other star: a tag on an
// image within a FWHM of a doubled star's image is on a blend (wrong). With the rule switched off the
// blends decode as stars.
TEST(TrailLinker, TwoStarsOnOnePathMergedAtEveryExposureAreNoStar) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const double pixel_um = 12.5, fwhm_px = 30.0 / pixel_um;
  std::set<std::string> doubled;
  const auto add_companions = [&](sim::Scene* scene) {
    std::vector<sim::SceneMark> companions;
    for (const sim::SceneMark& m : scene->marks) {
      if (m.kind != sim::MarkKind::kTrailDot && m.kind != sim::MarkKind::kTrailDash) continue;
      const std::string star = m.id.substr(0, m.id.find("-T"));
      if ((star.back() - '0') % 2 != 0) continue;  // (every other star, by its catalog number's last digit)
      doubled.insert(star);
      // The sweep's direction on the scan (the mark frame's segment through the local affine map).
      const double dx = m.px_from_um[0] * m.segment_u_um + m.px_from_um[1] * m.segment_v_um;
      const double dy = m.px_from_um[2] * m.segment_u_um + m.px_from_um[3] * m.segment_v_um;
      const double len_px = std::hypot(dx, dy);
      if (!(len_px > 0)) continue;
      sim::SceneMark c = m;
      c.id += "c";
      c.centre_px.x_px += 1.2 * fwhm_px * dx / len_px, c.centre_px.y_px += 1.2 * fwhm_px * dy / len_px;
      companions.push_back(c);
    }
    scene->marks.insert(scene->marks.end(), companions.begin(), companions.end());
  };
  const BandRun b = RunBand(SpecTrails(3.5, pixel_um), pixel_um, 1400, 4.0, add_companions);
  ASSERT_GE(doubled.size(), 5u);
  std::vector<bool> on_blend(b.found.size(), false);
  for (size_t i = 0; i < b.found.size(); ++i)
    for (const MeasuredPoint* t : b.truth)
      if (doubled.count(t->star_id) &&
          std::hypot(*t->x_px - b.found[i].point.position_px.x_px, *t->y_px - b.found[i].point.position_px.y_px) <
              fwhm_px + 0.5 * b.found[i].length_px)
        on_blend[i] = true;
  const auto score = [&](bool rule, long* right) {
    TrailOptions to = b.options;
    to.ablation.two_stars = rule;
    const ScanPixels scan = BandPixels(b);
    const TrailLinkResult r = LinkTrails(b.found, DutyCycleScheduleOptions{}, to, &scan);
    long blend_tags = 0;
    *right = 0;
    for (size_t i = 0; i < b.found.size(); ++i) {
      if (!r.images[i].assigned) continue;
      if (on_blend[i]) ++blend_tags;
      else if (b.match[i] && TagsRight(r.images[i], *b.match[i])) ++*right;
    }
    return blend_tags;
  };
  long right_unaware = 0, right = 0;
  const long blends_unaware = score(false, &right_unaware), blends = score(true, &right);
  std::printf("[two stars] %zu stars given a companion 1.2 FWHM along their path: tags on blends %ld without the "
              "rule (%ld other tags right), %ld with it (%ld right)\n",
              doubled.size(), blends_unaware, right_unaware, blends, right);
  EXPECT_GT(blends_unaware, 100);  // the blends decode as stars when their lengths are not asked
  EXPECT_EQ(blends, 0);
  EXPECT_GE(right, right_unaware - 10);  // the other stars as before
}

// The deblender may cut a dash crossed by other images into parts, each fainter than half a dash, and
// flags them crowded. Where the first leading dash of trails T2..T4 is so cut (two point pieces of 0.2 x
// its flux, together under half a dash, a third of its length on either side of it), the place before
// the run of N - 1 is not empty: no trail is numbered by the shortened run, with lone trails kept
// (default options). The same pieces unflagged pass for other stars' faint dots: 22 wrong tags. Plain
// pieces of 0.4 x its flux add up to more than half a dash: they hold it too.
TEST(TrailLinker, APieceOfACrowdedClumpHoldsTheDashItMayBe) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  // The first leading dash of trails T2..T4 replaced by two point pieces of this fraction of its flux each.
  auto cut_first_dashes = [&](double fraction, unsigned flags, std::vector<DetectedStar>* found,
                              std::vector<const MeasuredPoint*>* match) {
    long cut = 0;
    for (size_t i = 0; i < b.found.size(); ++i) {
      const TrailImage& ti = b.r.images[i];
      const DetectedStar& d = b.found[i];
      if (ti.assigned && ti.kind == ExposureKind::kDash && ti.dash_index == 1 && ti.trail >= 2 && d.length_px > 0) {
        ++cut;
        const double a = d.angle_deg * M_PI / 180.0, half_px = d.length_px / 3.0;
        for (int side : {-1, 1}) {
          DetectedStar piece = d;
          piece.point.position_px.x_px += side * half_px * std::cos(a);
          piece.point.position_px.y_px += side * half_px * std::sin(a);
          piece.flux_dn = fraction * d.flux_dn;
          piece.length_px = 0.0;
          piece.flags = flags;
          found->push_back(piece);
          match->push_back(nullptr);
        }
        continue;
      }
      found->push_back(d);
      match->push_back(b.match[i]);
    }
    return cut;
  };
  // Crowded pieces of 0.2 x the flux (together under half a dash: only the flag says they may hold it),
  // plain pieces of 0.4 x (together more than half: their fluxes add up).
  for (const auto& [fraction, flags] : {std::pair<double, unsigned>{0.2, kStarCrowded | kStarBlended}, {0.4, 0u}}) {
    std::vector<DetectedStar> found;
    std::vector<const MeasuredPoint*> match;
    const long cut = cut_first_dashes(fraction, flags, &found, &match);
    ASSERT_GE(cut, 5);
    const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, b.options);
    long wrong = 0, right = 0;
    for (size_t i = 0; i < found.size(); ++i) {
      if (!r.images[i].assigned) continue;
      const bool ok = match[i] && TagsRight(r.images[i], *match[i]);
      wrong += !ok, right += ok;
      EXPECT_TRUE(ok) << (match[i] ? match[i]->id : "a piece") << " tagged T" << r.images[i].trail;
    }
    std::printf("[cut dashes] first dash of %ld trails T2..T4 cut into two %s pieces of %.1f x its flux: %ld wrong "
                "tags, %ld right\n", cut, flags ? "crowded" : "plain", fraction, wrong, right);
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(right, 0);
  }
}

// A rejected line reaches only its own pixels: a line along the scan's edge (the detector sees the
// format's border as one, 600 px long and a few px wide) holds no dash 100 px inside the scan, where a
// disk of half its length around its centre would (docs/trails_record.md, "Trails entering the format, and lines"). Here such lines run along
// both edges of the band: tags as without them; the same lines without their box, fewer (a trail's run
// within 300 px of one is "occupied" before its first dash).
TEST(TrailLinker, ALineAlongTheEdgeHidesNothingBeyondItsBox) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const BandRun& b = Band();
  auto right_tags = [&](const std::vector<DetectedStar>& found) {
    const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, b.options);
    long right = 0, wrong = 0;
    for (size_t i = 0; i < b.found.size(); ++i) {
      if (!r.images[i].assigned) continue;
      const bool ok = b.match[i] && TagsRight(r.images[i], *b.match[i]);
      right += ok, wrong += !ok;
    }
    EXPECT_EQ(wrong, 0);
    return right;
  };
  const double length_px = 600.0, width_px = 6.0;
  auto with_lines = [&](bool boxed) {
    std::vector<DetectedStar> found = b.found;  // the lines after the images: the same indices
    for (const double y_px : {b.y0 + 3.0, b.y0 + b.h - 4.0})
      for (double x_px = 0.5 * length_px; x_px < b.w; x_px += length_px) {
        DetectedStar line;
        line.point.kind = PointKind::kStar;
        line.point.status = PointStatus::kRejected;
        line.point.reason = "line";
        line.point.position_px = {x_px, y_px};
        line.flags = kStarDefect;
        line.length_px = std::hypot(length_px, width_px);
        if (boxed)
          line.box_min_px = {x_px - 0.5 * length_px, y_px - 0.5 * width_px},
          line.box_max_px = {x_px + 0.5 * length_px, y_px + 0.5 * width_px};
        found.push_back(line);
      }
    return found;
  };
  const long plain = right_tags(b.found), boxed = right_tags(with_lines(true)), disks = right_tags(with_lines(false));
  std::printf("[edge lines] right tags: %ld without lines, %ld with boxed lines, %ld with lines as disks\n", plain,
              boxed, disks);
  EXPECT_GE(boxed, plain * 99 / 100);
  EXPECT_LT(disks + 10, boxed);  // 23 trail images fewer when written (docs/trails.md)
}

// The linker alone on the simulator's true images of a whole plate: every trail dot and dash as
// a detection at its true pixel position plus 0.15 px of deterministic jitter, dashes flagged
// elongated, every 13th dot missing, and a stray detection beside every 40th image.
TEST(TrailLinker, DecodesTheTrueImagesOfAWholePlate) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const sim::SimulatedPlate plate =
      sim::BuildSimulatedPlate(sim::ParseSimulationSpec(SpecTrails(), "trails.toml"), DefinitionRegistry());
  std::vector<DetectedStar> found;
  std::vector<const MeasuredPoint*> source;  // truth row of each detection (nullptr: stray)
  // Decodable trails: all 25 dots and all N + 4 dashes on the format (the others are cut by its edge).
  std::map<std::string, int> images_per_trail;
  for (const MeasuredPoint& t : plate.truth)
    if (t.kind == PointKind::kTrailDot || t.kind == PointKind::kTrailDash) images_per_trail[t.star_id + t.trail]++;
  auto complete = [&](const MeasuredPoint& t) {
    const int N = std::stoi(t.trail.substr(1)) + 1;  // T1..T4 have 2..5 leading dashes (Table 1 defaults)
    return images_per_trail[t.star_id + t.trail] == 25 + N + 4;
  };
  long n = 0, truth_dots = 0, expected = 0;
  for (const MeasuredPoint& t : plate.truth) {
    if (t.kind != PointKind::kTrailDot && t.kind != PointKind::kTrailDash) continue;
    ++n;
    truth_dots += t.kind == PointKind::kTrailDot;
    expected += t.kind == PointKind::kTrailDot && complete(t) && n % 13 != 0;
    if (t.kind == PointKind::kTrailDot && n % 13 == 0) continue;  // missed
    DetectedStar d;
    d.point.kind = PointKind::kStar;
    d.point.status = PointStatus::kMeasured;
    d.point.position_px = {*t.x_px + 0.15 * std::sin(1.7 * n), *t.y_px + 0.15 * std::cos(2.3 * n)};
    if (t.kind == PointKind::kTrailDash) d.flags = kStarElongated;
    found.push_back(d);
    source.push_back(&t);
    if (n % 40 == 0) {  // a stray image 21 px off the trail (closer ones can displace a true image: see report)
      DetectedStar s = d;
      s.flags = 0;
      s.point.position_px.x_px += 15.0;
      s.point.position_px.y_px -= 15.0;
      found.push_back(s);
      source.push_back(nullptr);
    }
  }
  TrailOptions to;
  to.max_dash_spacing_px = 40.0;  // 30 s at the fastest rate (~0.94 px/s at 12.5 um)
  to.exposed_outline_px = OrbigonFormatOutline_px(plate);  // the simulator draws no image outside the format
  const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
  ASSERT_EQ(r.images.size(), found.size());
  long right = 0, wrong = 0, strays_assigned = 0;
  for (size_t i = 0; i < found.size(); ++i) {
    const TrailImage& ti = r.images[i];
    if (!ti.assigned) continue;
    const MeasuredPoint* t = source[i];
    if (!t) {
      ++strays_assigned;
      continue;
    }
    const bool dot = ti.kind == ExposureKind::kDot;
    const bool ok = (t->kind == PointKind::kTrailDot) == dot && t->trail == "T" + std::to_string(ti.trail) &&
                    *t->dot == (dot ? ti.dot_index : ti.dash_index) &&
                    std::abs(SecondsAfter0530(t->mid_time_utc) - ti.mid_s) < 0.0015;
    if (!ok) {
      ++wrong;
      ADD_FAILURE() << "tagged T" << ti.trail << (dot ? " D" : " L") << (dot ? ti.dot_index : ti.dash_index)
                    << " is " << t->id;
    } else if (dot && complete(*t)) {
      ++right;
    }
  }
  // One chain, one star.
  std::map<int, std::set<std::string>> chain_stars;
  for (size_t i = 0; i < found.size(); ++i)
    if (r.images[i].assigned && source[i]) chain_stars[r.images[i].chain].insert(source[i]->star_id);
  for (const auto& [chain, stars] : chain_stars) EXPECT_EQ(stars.size(), 1u) << "chain " << chain;
  std::map<std::string, long> reasons;
  for (const TrailImage& ti : r.images)
    if (!ti.assigned) reasons[TrailReasonName(ti.reason)]++;
  std::string why;
  for (const auto& [k, c] : reasons) why += k + "=" + std::to_string(c) + " ";
  std::printf("[true images] %zu detections, %zu chains, %ld truth dots, %ld present on complete trails, %ld of them "
              "right, %ld wrong, %ld strays assigned; unassigned: %s\n",
              found.size(), r.chains.size(), truth_dots, expected, right, wrong, strays_assigned, why.c_str());
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(strays_assigned, 0);
  {  // require_joined: lone trails (siblings cut by the format's edge) refused; no wrong tag either.
    TrailOptions strict = to;
    strict.require_joined = true;
    const TrailLinkResult rs = LinkTrails(found, DutyCycleScheduleOptions{}, strict);
    long right_strict = 0, wrong_strict = 0;
    for (size_t i = 0; i < found.size(); ++i) {
      const TrailImage& ti = rs.images[i];
      if (!ti.assigned || !source[i]) {
        wrong_strict += ti.assigned;
        continue;
      }
      const bool dot = ti.kind == ExposureKind::kDot;
      const MeasuredPoint* t = source[i];
      const bool ok = (t->kind == PointKind::kTrailDot) == dot && t->trail == "T" + std::to_string(ti.trail) &&
                      *t->dot == (dot ? ti.dot_index : ti.dash_index) &&
                      std::abs(SecondsAfter0530(t->mid_time_utc) - ti.mid_s) < 0.0015;
      wrong_strict += !ok;
      right_strict += ok && dot && complete(*t);
    }
    std::printf("[true images, require_joined] %ld of %ld right, %ld wrong\n", right_strict, expected, wrong_strict);
    EXPECT_EQ(wrong_strict, 0);
  }
  EXPECT_GT(truth_dots, 500);
  EXPECT_GT(expected, 300);
  // Issue #5: at least 95 % of the dots present (a missing dot or a stray beside one must not break
  // the trail: the growth predicts along the track and skips them).
  EXPECT_GE(static_cast<double>(right), 0.95 * expected);
}

}  // namespace
}  // namespace platemeter
