// The plate's diurnal flow (detect/sky_flow.h) against the simulator's truth: fitted to the true
// tracks of half the stars of a simulated Orbigon plate (ERFA apparent places with refraction, the
// Orbigon's calibrated distortion), it carries the first image of each star of the other half to
// every other image of that star, across the breaks and the whole 2 h 08 min plate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "../detect/src/trails/trail_internal.h"
#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/detect/sky_flow.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/orbigon_trails.h"

namespace platemeter {
namespace {

struct TruePoint {
  double t_s;
  PixelPoint p;
};

// Every star's true images (all trails), time order.
std::map<std::string, std::vector<TruePoint>> TrueStars(const sim::SimulatedPlate& plate) {
  std::map<std::string, std::vector<TruePoint>> stars;
  for (const MeasuredPoint& t : plate.truth)
    if (t.kind == PointKind::kTrailDot || t.kind == PointKind::kTrailDash)
      stars[t.star_id].push_back({testing::SecondsAfter0530(t.mid_time_utc), {*t.x_px, *t.y_px}});
  for (auto& [id, v] : stars)
    std::sort(v.begin(), v.end(), [](const TruePoint& a, const TruePoint& b) { return a.t_s < b.t_s; });
  return stars;
}

struct Errors {
  double rms_px = 0, max_px = 0, max_distance_px = 0, max_step_difference_px = 0;
};

// The flow of the even-numbered stars (velocities from consecutive images at most 40 s apart: central
// differences at the mean time).
SkyFlow FlowOfEvenStars(const std::map<std::string, std::vector<TruePoint>>& stars, int degree, size_t* samples) {
  std::vector<PixelPoint> p, v;
  int index = 0;
  for (const auto& [id, images] : stars) {
    if (index++ % 2) continue;
    for (size_t k = 1; k < images.size(); ++k) {
      const double dt = images[k].t_s - images[k - 1].t_s;
      if (dt > 41.0) continue;
      const PixelPoint& a = images[k - 1].p;
      const PixelPoint& b = images[k].p;
      p.push_back({0.5 * (a.x_px + b.x_px), 0.5 * (a.y_px + b.y_px)});
      v.push_back({(b.x_px - a.x_px) / dt, (b.y_px - a.y_px) / dt});
    }
  }
  SkyFlow flow;
  EXPECT_TRUE(flow.Fit(p, v, degree));
  *samples = p.size();
  return flow;
}

// The flow of the even-numbered stars carrying the odd-numbered stars' first images.
Errors FlowErrors(const std::map<std::string, std::vector<TruePoint>>& stars, int degree) {
  size_t samples = 0;
  const SkyFlow flow = FlowOfEvenStars(stars, degree, &samples);
  Errors e;
  double sum2 = 0;
  long n = 0;
  int index = 0;
  for (const auto& [id, images] : stars) {
    if (index++ % 2 == 0 || images.size() < 10) continue;
    const FlowPath path(flow, images.front().p, 8000.0), fine(flow, images.front().p, 8000.0, 10.0);
    for (const TruePoint& q : images) {
      const double dt = q.t_s - images.front().t_s;
      const PixelPoint at = path.At(dt), at_fine = fine.At(dt);
      const double err = std::hypot(at.x_px - q.p.x_px, at.y_px - q.p.y_px);
      sum2 += err * err, ++n;
      e.max_px = std::max(e.max_px, err);
      e.max_distance_px = std::max(e.max_distance_px, std::hypot(q.p.x_px - images.front().p.x_px, q.p.y_px - images.front().p.y_px));
      e.max_step_difference_px = std::max(e.max_step_difference_px, std::hypot(at.x_px - at_fine.x_px, at.y_px - at_fine.y_px));
    }
  }
  e.rms_px = std::sqrt(sum2 / std::max(1L, n));
  std::printf("[flow] degree %d: %zu samples (%d kept, residual %.1e px/s); %ld images carried up to %.0f px: error "
              "RMS %.4f px, max %.4f px; 30 s against 10 s steps: %.1e px\n",
              degree, samples, flow.samples_used(), flow.residual_px_per_s(), n, e.max_distance_px, e.rms_px, e.max_px,
              e.max_step_difference_px);
  return e;
}

// The true stars of a simulated Orbigon plate (V <= 5, 20 um), built once.
const std::map<std::string, std::vector<TruePoint>>& PlateStars() {
  static const auto stars = TrueStars(sim::BuildSimulatedPlate(
      sim::ParseSimulationSpec(testing::OrbigonTrailSpec("flow", 5.0, 5.0, 6000.0, 20.0), "flow.toml"), DefinitionRegistry()));
  return stars;
}

TEST(SkyFlow, CarriesAStarsImageToEveryOtherExposureOfThePlate) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const auto& stars = PlateStars();
  ASSERT_GT(stars.size(), 100u);
  // Degree 6 (the default): a tenth of the sibling tolerance of the old parabola (0.5 px + 0.002 x distance,
  // 6 px at 2800 px) across the whole plate.
  const Errors six = FlowErrors(stars, 6);
  EXPECT_GT(six.max_distance_px, 2500.0);
  EXPECT_LT(six.rms_px, 0.04);
  EXPECT_LT(six.max_px, 0.3);
  EXPECT_LT(six.max_step_difference_px, 1e-3);
  // Degree 4 does not follow the Orbigon's distortion near the format's corners.
  const Errors four = FlowErrors(stars, 4);
  EXPECT_GT(four.max_px, 2 * six.max_px);
}

// A trail's images on two flow paths are two stars' (trail_flow.cpp OnTwoFlowPaths; Kyoto's KS19121 T1 and
// KS19130 T4: a run of the one and the other's dots 5 px beside it made one trail). The first 30 true images
// of each odd-numbered star (a trail and a bit), carried by the even-numbered stars' flow: as they are, with
// one or two stray images, and with the last 12 moved 5 px across the motion (another star's path).
TEST(SkyFlow, ATrailsImagesOnTwoFlowPathsAreTwoStars) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  size_t samples = 0;
  const SkyFlow flow = FlowOfEvenStars(PlateStars(), 6, &samples);
  const double fwhm_px = 2.24;  // (Kyoto's)
  int trails = 0, one = 0, strays = 0, two = 0, index = 0;
  for (const auto& [id, all] : PlateStars()) {
    if (index++ % 2 == 0 || all.size() < 30) continue;
    std::vector<std::pair<double, PixelPoint>> images;
    for (size_t k = 0; k < 30; ++k) images.push_back({all[k].t_s, all[k].p});
    const auto moved = [&](std::vector<std::pair<double, PixelPoint>> v, size_t from, size_t to) {
      for (size_t k = from; k < to; ++k) {  // 5 px across the motion at image k
        const PixelPoint& a = all[k == 0 ? 0 : k - 1].p;
        const PixelPoint& b = all[k == 0 ? 1 : k].p;
        const double step = std::hypot(b.x_px - a.x_px, b.y_px - a.y_px);
        v[k].second.x_px -= 5.0 * (b.y_px - a.y_px) / step, v[k].second.y_px += 5.0 * (b.x_px - a.x_px) / step;
      }
      return v;
    };
    ++trails;
    one += trail_internal::OnTwoFlowPaths(flow, images, fwhm_px);
    strays += trail_internal::OnTwoFlowPaths(flow, moved(images, 0, 1), fwhm_px) +
              trail_internal::OnTwoFlowPaths(flow, moved(images, 29, 30), fwhm_px) +
              trail_internal::OnTwoFlowPaths(flow, moved(images, 10, 12), fwhm_px);
    two += trail_internal::OnTwoFlowPaths(flow, moved(images, 18, 30), fwhm_px);
  }
  std::printf("[flow] %d trails: on two paths as they are %d, with strays %d, with their last 12 images 5 px across %d\n",
              trails, one, strays, two);
  ASSERT_GT(trails, 50);
  EXPECT_EQ(one, 0);
  EXPECT_EQ(strays, 0);
  EXPECT_EQ(two, trails);
}

// What the flow decoder (detect/src/trails/trail_flow.cpp) relies on, from the schedule alone: a dash read as
// another dash exposure shifts the whole program in time; the shifted program lines up many images of
// one trail (a trail read as its neighbour) but few dots of a second trail, because the trails' different
// leading-dash counts shift their dot programs 30 s against each other. The decoder asks 4 dots of a second
// trail for a decode and counts 3 as a competing candidate; only the readings 120 s off (leading dash 1 of
// the five-dash trail read as dash 5, and back) line up more, in every trail, and are always candidates.
TEST(SkyFlow, AWrongReadingOfADashLinesUpFewDotsOfASecondTrail) {
  const std::vector<ShutterExposure> plate = BuildShutterSchedule(DutyCycleScheduleOptions{});
  ASSERT_EQ(plate.size(), 130u);
  int worst_second_dots = 0, readings_120 = 0;
  for (const ShutterExposure& truth : plate)
    for (const ShutterExposure& reading : plate) {
      if (truth.kind != ExposureKind::kDash || reading.kind != ExposureKind::kDash || &truth == &reading) continue;
      const double shift_s = reading.mid_s - truth.mid_s;
      // Images of the star (at the exposures' times) that the shifted program predicts (same duration).
      std::vector<int> images(5, 0), dots(5, 0);
      for (const ShutterExposure& e : plate)
        for (const ShutterExposure& f : plate)
          if (std::abs(f.mid_s - (e.mid_s + shift_s)) < 1.0 && f.duration_s == e.duration_s) {
            ++images[e.trail];
            dots[e.trail] += e.kind == ExposureKind::kDot;
          }
      int top = 1;
      for (int t = 1; t <= 4; ++t) top = images[t] > images[top] ? t : top;
      int second_dots = 0;
      for (int t = 1; t <= 4; ++t)
        if (t != top) second_dots = std::max(second_dots, dots[t]);
      if (std::abs(std::abs(shift_s) - 120.0) < 1.0) {
        ++readings_120;
        EXPECT_GE(second_dots, 3) << "a reading 120 s off must stay a candidate";
        continue;
      }
      worst_second_dots = std::max(worst_second_dots, second_dots);
    }
  EXPECT_EQ(readings_120, 2);
  EXPECT_EQ(worst_second_dots, 2);  // below the 3 of a candidate and the 4 of a decode
}

}  // namespace
}  // namespace platemeter
