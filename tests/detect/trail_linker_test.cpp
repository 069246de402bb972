// Duty-cycle trails on a simulated Orbigon star-field plate (bright stars):
// DetectStars, then LinkTrails; every assigned image is compared with the
// simulator's truth rows (star, trail, dot index, mid-time) and the schedule of
// seed 001 Table 1 is the simulator's own (defaults: 2/3/4/5 dashes, 8 min breaks).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/error.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/detect/trail_linker.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace platemeter {
namespace {

// Seconds after 05:30:00 of an ISO time "1972-05-12Thh:mm:ss.sssZ" (independent of the linker).
double SecondsAfter0530(const std::string& iso) {
  int h = 0, mi = 0;
  double s = 0;
  EXPECT_EQ(std::sscanf(iso.c_str() + 11, "%d:%d:%lf", &h, &mi, &s), 3) << iso;
  return (h - 5) * 3600.0 + (mi - 30) * 60.0 + s;
}

constexpr const char* kSpec = R"(
name = "trails"
camera = "orbigon"
seed = 5
[output]
pixel_size_um = 12.5
[stars]
fwhm_um = 30
reference_magnitude = 2.5
reference_peak_dn = 2500
[star_field]
latitude_deg = 39.03
longitude_deg = -76.93
height_m = 50
start_utc = "1972-05-12T05:30:00Z"
magnitude_limit = 2.5
[noise]
sensor_sigma_dn = 20
grain_sigma_dn = 20
)";

TEST(TrailLinker, OptionsAreChecked) {
  TrailOptions o;
  o.max_link_px = -1;
  EXPECT_THROW(LinkTrails({}, DutyCycleScheduleOptions{}, o), Error);
  EXPECT_TRUE(LinkTrails({}, DutyCycleScheduleOptions{}).images.empty());
}

TEST(TrailLinker, DecodesTheTrailsOfASimulatedOrbigonPlate) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const char* text = kSpec;
  const sim::SimulatedPlate plate =
      sim::BuildSimulatedPlate(sim::ParseSimulationSpec(text, "trails.toml"), DefinitionRegistry());
  // A band of rows through the middle of the trails (the whole plate at 12.5 um would be 92 Mpx):
  // pixels small enough that the leading dashes (20 s open, 10 s closed) are resolved.
  std::vector<double> rows;
  for (const MeasuredPoint& t : plate.truth)
    if (t.kind == PointKind::kTrailDot) rows.push_back(*t.y_px);
  ASSERT_FALSE(rows.empty());
  std::nth_element(rows.begin(), rows.begin() + rows.size() / 2, rows.end());
  const long w = plate.scene.width_px, h = 1400;
  const long y0 = std::clamp(std::lround(rows[rows.size() / 2]) - h / 2, 0L, plate.scene.height_px - h);
  std::vector<float> values(static_cast<size_t>(w * h));
  sim::SceneRenderer(plate.scene).RenderBand(y0, h, values.data());
  StarDetectorOptions so;
  so.psf_fwhm_px = 2.6;
  so.max_fwhm_ratio = 8.0;    // dashes are 20 s segments (~18 px): not dust
  so.pair_chi2_gain = 1e12;   // a dash is one image, never a pair
  so.threshold_sigma = 10.0;  // low noise: a high threshold keeps the dashes of the leading run apart
  std::vector<DetectedStar> found = DetectStarsInBuffer(values.data(), w, h, 65535.0, so);
  for (DetectedStar& f : found) f.point.position_px.y_px += static_cast<double>(y0);

  TrailOptions to;
  to.max_link_px = 130.0;  // 108 s (group 3 to its separator) at ~0.9 px/s
  to.image_min_px = {0.0, static_cast<double>(y0)};
  to.image_max_px = {w - 1.0, static_cast<double>(y0 + h - 1)};
  const TrailLinkResult r = LinkTrails(found, DutyCycleScheduleOptions{}, to);
  ASSERT_EQ(r.images.size(), found.size());

  // Truth dots and dashes; each detection matched to the nearest truth image within 1.5 px.
  std::vector<const MeasuredPoint*> truth;
  for (const MeasuredPoint& t : plate.truth)
    if (t.kind == PointKind::kTrailDot || t.kind == PointKind::kTrailDash) truth.push_back(&t);
  // The dots expected: those of trails lying wholly inside the band (10 px margin).
  std::map<std::string, bool> inside;  // star/trail -> all images inside
  for (const auto* t : truth) {
    const bool in = *t->y_px > y0 + 10 && *t->y_px < y0 + h - 10;
    auto [it, added] = inside.insert({t->star_id + t->trail, in});
    if (!added) it->second = it->second && in;
  }
  long truth_dots = 0;
  for (const auto* t : truth) truth_dots += t->kind == PointKind::kTrailDot && inside[t->star_id + t->trail];
  std::set<const MeasuredPoint*> good_dots;
  long wrong = 0, assigned_no_truth = 0;
  std::map<int, std::set<std::string>> chain_stars;
  for (size_t i = 0; i < found.size(); ++i) {
    const TrailImage& ti = r.images[i];
    if (!ti.assigned) continue;
    const PixelPoint p = found[i].point.position_px;
    const MeasuredPoint* best = nullptr;
    double bd = 1.5;
    for (const auto* t : truth) {
      const double d = std::hypot(*t->x_px - p.x_px, *t->y_px - p.y_px);
      if (d < bd) bd = d, best = t;
    }
    if (!best) {
      ++assigned_no_truth;
      continue;
    }
    chain_stars[ti.chain].insert(best->star_id);
    const bool dot = ti.kind == ExposureKind::kDot;
    const bool ok = (best->kind == PointKind::kTrailDot) == dot && best->trail == "T" + std::to_string(ti.trail) &&
                    *best->dot == (dot ? ti.dot_index : ti.dash_index) &&
                    std::abs(SecondsAfter0530(best->mid_time_utc) - ti.mid_s) < 0.0015;
    if (!ok) {
      ++wrong;
      ADD_FAILURE() << "image " << i << " tagged T" << ti.trail << (dot ? " D" : " L")
                    << (dot ? ti.dot_index : ti.dash_index) << " is " << best->id;
    } else if (dot && inside[best->star_id + best->trail]) {
      good_dots.insert(best);
    }
  }
  for (const auto& [chain, stars] : chain_stars) EXPECT_EQ(stars.size(), 1u) << "chain " << chain << " mixes stars";
  std::map<std::string, long> reasons;
  for (const TrailImage& ti : r.images)
    if (!ti.assigned) reasons[ti.reason]++;
  std::string why;
  for (const auto& [k, n] : reasons) why += k + "=" + std::to_string(n) + " ";
  std::printf("[trails] %ldx%ld px, %zu detections, %zu chains, %ld truth dots, %zu right, %ld wrong, "
              "%ld assigned without truth, assigned dashes %ld; unassigned: %s\n",
              w, h, found.size(), r.chains.size(), truth_dots, good_dots.size(), wrong, assigned_no_truth,
              r.assigned_dashes, why.c_str());
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(assigned_no_truth, 0);
  EXPECT_GE(truth_dots, 50);
  // NOT the 95 % target: at this pixel size DetectStars returns the leading dash run of a trail as
  // one defect (or not at all), so the trail number cannot be decoded and every chain must stay
  // unassigned. What must hold is that nothing is assigned wrongly (above). Figures in the printout.
}

// The linker alone on the simulator's true images of a whole plate: every trail dot and dash as
// a detection at its true pixel position plus 0.15 px of deterministic jitter, dashes flagged
// elongated, every 13th dot missing, and a stray detection beside every 40th image.
TEST(TrailLinker, DecodesTheTrueImagesOfAWholePlate) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const sim::SimulatedPlate plate =
      sim::BuildSimulatedPlate(sim::ParseSimulationSpec(kSpec, "trails.toml"), DefinitionRegistry());
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
  to.max_link_px = 130.0;
  // The exposed format (114 mm square: the simulator drops images outside it), in pixels.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (double u : {-57.0, 57.0})
    for (double v : {-57.0, 57.0}) {
      const PixelPoint c = plate.chain.PixelFromPlate({u, v});
      x0 = std::min(x0, c.x_px), x1 = std::max(x1, c.x_px), y0 = std::min(y0, c.y_px), y1 = std::max(y1, c.y_px);
    }
  to.image_min_px = {x0, y0};
  to.image_max_px = {x1, y1};
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
    if (!ti.assigned) reasons[ti.reason]++;
  std::string why;
  for (const auto& [k, c] : reasons) why += k + "=" + std::to_string(c) + " ";
  std::printf("[true images] %zu detections, %zu chains, %ld truth dots, %ld present on complete trails, %ld of them "
              "right, %ld wrong, %ld strays assigned; unassigned: %s\n",
              found.size(), r.chains.size(), truth_dots, expected, right, wrong, strays_assigned, why.c_str());
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(strays_assigned, 0);
  EXPECT_GT(truth_dots, 500);
  EXPECT_GT(expected, 300);
  // The 95 % target of issue #5 is NOT met yet (about 70 % at the time of writing: a missing dot or a
  // stray can break a chain before its leading run, and the broken-off run is then refused).
  // This is a regression floor, not the target; the figure is printed above.
  EXPECT_GE(static_cast<double>(right), 0.6 * expected);
}

}  // namespace
}  // namespace platemeter
