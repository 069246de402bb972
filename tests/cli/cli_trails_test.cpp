// `platemeter detect --stars --trails-start-utc` end to end on a simulated
// Orbigon star plate (12.5 um pixels, catalog stars to V = 3.5): every trail
// row the tool writes is checked against the simulator's truth file (nearest
// truth trail image within 1.5 px: same kind, trail, dot or dash index and
// mid-time; one truth star per found star), the share of dots tagged, and the
// dots' own positions against their stated sigmas (the track's in the flags).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/measure/measurement_file.h"
#include "support/orbigon_trails.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;
using testing::TempDir;

using testing::OrbigonTrailSpec;
using testing::SecondsAfter0530;

// The text of a flag "name=text" of a row, "" if it has none.
std::string FlagText(const MeasuredPoint& m, const std::string& name) {
  for (const std::string& f : m.flags)
    if (f.size() > name.size() && f.compare(0, name.size() + 1, name + "=") == 0) return f.substr(name.size() + 1);
  return "";
}

// The value of a flag "name=value" of a row, if it has one.
std::optional<double> FlagValue(const MeasuredPoint& m, const std::string& name) {
  const std::string text = FlagText(m, name);
  if (text.empty()) return std::nullopt;
  return std::stod(text);
}

TEST(CliTrails, DetectWritesTimeTaggedTrailDotsThatMatchTheTruth) {
  if (!std::filesystem::exists(calib::DefaultStarCatalogPath()))
    GTEST_FAIL() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  TempDir dir;
  // The photometry of tests/detect/trail_linker_test.cpp: the 0.6 s dots of the faintest stars at SNR ~6.
  std::ofstream(dir.file("trails.toml")) << OrbigonTrailSpec("trails", 3.5, 3.5, 2500.0, 12.5, 20.0);
  ASSERT_EQ(RunPlatemeter("simulate '" + dir.file("trails.toml") + "' -o '" + dir.file("sim") + "' -q").exit_code, 0);
  const auto r = RunPlatemeter("detect '" + dir.file("sim/trails.tif") +
                               "' --camera orbigon --orientation 0 --stars --star-fwhm-px 2.4 "
                               "--trails-start-utc 1972-05-12T05:30:00Z -o '" + dir.file("out") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MeasurementFile truth = ReadMeasurementFile(dir.file("sim/trails.truth.csv"));
  const MeasurementFile found = ReadMeasurementFile(dir.file("out/trails.measurements.csv"));

  // Truth trail images; the dots counted are those of whole trails (the simulator writes no image outside
  // the format): 25 dots and the trail's N = 1 + trail number leading dashes plus 4 separators (Table 1).
  std::vector<const MeasuredPoint*> images;
  std::map<std::string, std::pair<long, long>> dots_dashes;  // star + trail -> (dots, dashes)
  for (const MeasuredPoint& t : truth.points)
    if (t.kind == PointKind::kTrailDot || t.kind == PointKind::kTrailDash) {
      images.push_back(&t);
      auto& [dots, dashes] = dots_dashes[t.star_id + "/" + t.trail];
      (t.kind == PointKind::kTrailDot ? dots : dashes)++;
    }
  auto whole = [&](const MeasuredPoint& t) {
    const auto [dots, dashes] = dots_dashes[t.star_id + "/" + t.trail];
    return dots == 25 && dashes == std::stol(t.trail.substr(1)) + 1 + 4;
  };
  long truth_dots = 0;
  for (const MeasuredPoint* t : images) truth_dots += t->kind == PointKind::kTrailDot && whole(*t);
  ASSERT_GT(truth_dots, 300);

  long right_dots = 0, wrong = 0, rows = 0, forced_dots = 0;
  double own_z2_x = 0, own_z2_y = 0;  // the tracked dots' own errors over their stated sigmas, squared
  long own_dots = 0, own_beyond_4 = 0;
  std::map<std::string, std::set<std::string>> truth_stars_of;
  std::map<std::string, std::set<std::string>> trails_by_step;  // a row's trail_step= -> its star + trail
  std::set<std::string> ids;
  for (const MeasuredPoint& m : found.points) {
    if (m.kind != PointKind::kTrailDot && m.kind != PointKind::kTrailDash) continue;
    ++rows;
    trails_by_step[FlagText(m, "trail_step")].insert(m.star_id + "-" + m.trail);
    EXPECT_TRUE(ids.insert(m.id).second) << m.id;
    EXPECT_EQ(m.id, m.star_id + "-" + m.trail + (m.kind == PointKind::kTrailDot ? "-D" : "-L") + std::to_string(*m.dot));
    const MeasuredPoint* best = nullptr;
    double bd = 1.5;
    for (const MeasuredPoint* t : images) {
      const double d = std::hypot(*t->x_px - *m.x_px, *t->y_px - *m.y_px);
      if (d < bd) bd = d, best = t;
    }
    ASSERT_NE(best, nullptr) << m.id << " has no truth image within 1.5 px";
    truth_stars_of[m.star_id].insert(best->star_id);
    const bool ok = best->kind == m.kind && best->trail == m.trail && best->dot == m.dot &&
                    std::abs(SecondsAfter0530(best->mid_time_utc) - SecondsAfter0530(m.mid_time_utc)) < 0.0015;
    if (!ok) {
      ++wrong;
      ADD_FAILURE() << m.id << " at " << m.mid_time_utc << " is " << best->id << " at " << best->mid_time_utc;
    } else if (m.kind == PointKind::kTrailDot && m.status == PointStatus::kMeasured && whole(*best)) {
      ++right_dots;
      // Every row's position and sigmas are the dot's own measurement (a faint dot's for one measured at its
      // track's prediction, forced_fit); the track's position at the mid-time is in the flags of the dots it
      // was fitted to (track_fit).
      const double zx = (*m.x_px - *best->x_px) / *m.sigma_x_px, zy = (*m.y_px - *best->y_px) / *m.sigma_y_px;
      if (std::find(m.flags.begin(), m.flags.end(), "forced_fit") != m.flags.end()) {
        ++forced_dots;
        EXPECT_LT(bd, 4.0 * std::hypot(*m.sigma_x_px, *m.sigma_y_px)) << m.id << ": the forced fit's position";
      } else if (std::find(m.flags.begin(), m.flags.end(), "track_fit") != m.flags.end()) {
        const std::optional<double> track_x = FlagValue(m, "track_x_px"), track_y = FlagValue(m, "track_y_px");
        ASSERT_TRUE(track_x && track_y && FlagValue(m, "track_sigma_x_px") && FlagValue(m, "track_sigma_y_px"))
            << m.id << ": the track's position and sigmas in the flags";
        EXPECT_LT(std::hypot(*track_x - *best->x_px, *track_y - *best->y_px), 0.2) << m.id << ": the track's position";
        own_z2_x += zx * zx, own_z2_y += zy * zy, ++own_dots;
        own_beyond_4 += std::abs(zx) > 4.0 || std::abs(zy) > 4.0;
      }
    }
  }
  for (const auto& [star, truths] : truth_stars_of) EXPECT_EQ(truths.size(), 1u) << star << " mixes truth stars";
  // Every trail row names the step that decoded its trail, and the rows' trails per step are the ones
  // detect.json counts (two outputs written from different places agree).
  const nlohmann::json counts = nlohmann::json::parse(
      testing::ReadTextFile(dir.file("out/trails.detect.json")))["stars"]["trails"]["decoded_trails_by_step"];
  EXPECT_EQ(trails_by_step.count(""), 0u) << "trail rows without a trail_step flag";
  EXPECT_GT(trails_by_step["run"].size(), 10u);
  for (const auto& [step, trails] : trails_by_step)
    EXPECT_EQ(static_cast<long>(trails.size()), counts.value(step, -1L)) << "trail_step=" << step;
  EXPECT_EQ(counts.size(), trails_by_step.size());
  std::printf("[cli trails] %ld trail rows, %ld of %ld dots of whole trails right (%.1f %%; %ld measured at their "
              "tracks' predictions), %ld wrong, %zu stars\n", rows, right_dots, truth_dots,
              100.0 * right_dots / truth_dots, forced_dots, wrong, truth_stars_of.size());
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(right_dots, 0.9 * truth_dots);
  // The stated sigmas are honest: an adjustment takes the rows as independent observations with them
  // (docs/stellar.md, "End to end through rendering and detection": 1.05 / 1.04 on a V <= 5 plate).
  ASSERT_GT(own_dots, 200);
  const double rms_z_x = std::sqrt(own_z2_x / own_dots), rms_z_y = std::sqrt(own_z2_y / own_dots);
  std::printf("[cli trails] %ld tracked dots: own error / stated sigma rms %.3f (x) %.3f (y), %ld beyond 4 sigma\n",
              own_dots, rms_z_x, rms_z_y, own_beyond_4);
  EXPECT_GT(rms_z_x, 0.8);
  EXPECT_LT(rms_z_x, 1.25);
  EXPECT_GT(rms_z_y, 0.8);
  EXPECT_LT(rms_z_y, 1.25);
  EXPECT_LE(own_beyond_4, 0.01 * own_dots);

  // With --trails-require-joined every tagged trail has a sibling of its star.
  const auto joined = RunPlatemeter("detect '" + dir.file("sim/trails.tif") +
                                    "' --camera orbigon --orientation 0 --stars --star-fwhm-px 2.4 "
                                    "--trails-start-utc 1972-05-12T05:30:00Z --trails-require-joined -o '" +
                                    dir.file("joined") + "'");
  ASSERT_EQ(joined.exit_code, 0) << joined.err;
  std::map<std::string, std::set<std::string>> trails_of;
  long joined_rows = 0;
  for (const MeasuredPoint& m : ReadMeasurementFile(dir.file("joined/trails.measurements.csv")).points)
    if (m.kind == PointKind::kTrailDot || m.kind == PointKind::kTrailDash) {
      trails_of[m.star_id].insert(m.trail);
      ++joined_rows;
    }
  for (const auto& [star, trails] : trails_of) EXPECT_GE(trails.size(), 2u) << star << " is a lone trail";
  std::printf("[cli trails, require joined] %ld trail rows of %zu stars\n", joined_rows, trails_of.size());
  EXPECT_GT(joined_rows, rows / 2);
  EXPECT_LE(joined_rows, rows);
}

}  // namespace
}  // namespace platemeter
