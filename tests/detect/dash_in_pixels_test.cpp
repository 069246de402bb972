// MeasureDashInPixels (detect/dash_in_pixels.h): whether the pixels show a trail's dash at the place the
// plate's flow puts it. The scenes are rendered here by their own means (each pixel's light integrated on a
// 9 x 9 grid of a Gaussian PSF swept along the segment in 20 steps), on a negative (star light darker),
// with Gaussian noise; the truth is what was rendered.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "platemeter/detect/dash_in_pixels.h"

namespace platemeter {
namespace {

constexpr double kBackground_dn = 30000.0, kNoise_dn = 25.0, kFwhm_px = 2.0;
constexpr double kDashFlux_dn = 60000.0, kDashLength_px = 7.0;
constexpr double kAngle_rad = 0.3;

struct ImageBuffer {
  long width_px = 64, height_px = 64;
  std::vector<float> values_dn = std::vector<float>(64 * 64, static_cast<float>(kBackground_dn));

  // A segment (a point image: length 0) of total flux flux_dn centred at (x_px, y_px), darkening the pixels.
  void Add(double x_px, double y_px, double length_px, double angle_rad, double flux_dn) {
    const double sigma_px = kFwhm_px / (2.0 * std::sqrt(2.0 * std::log(2.0)));
    constexpr int kSteps = 20, kSub = 9;
    for (long y = 0; y < height_px; ++y)
      for (long x = 0; x < width_px; ++x) {
        double sum = 0;
        for (int t = 0; t < kSteps; ++t) {
          const double along = length_px * ((t + 0.5) / kSteps - 0.5);
          const double cx = x_px + along * std::cos(angle_rad), cy = y_px + along * std::sin(angle_rad);
          if (std::abs(cx - x) > 6 * sigma_px + 1 || std::abs(cy - y) > 6 * sigma_px + 1) continue;
          for (int i = 0; i < kSub; ++i)
            for (int j = 0; j < kSub; ++j) {
              const double dx = x - 0.5 + (i + 0.5) / kSub - cx, dy = y - 0.5 + (j + 0.5) / kSub - cy;
              sum += std::exp(-0.5 * (dx * dx + dy * dy) / (sigma_px * sigma_px));
            }
        }
        const double fraction = sum / (kSteps * kSub * kSub) / (2.0 * std::numbers::pi * sigma_px * sigma_px);
        values_dn[static_cast<size_t>(y * width_px + x)] -= static_cast<float>(flux_dn * fraction);
      }
  }
  void AddNoise(unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, kNoise_dn);
    for (float& v : values_dn) v += static_cast<float>(noise(rng));
  }
  ScanPixels Scan() const {
    ScanPixels scan;
    scan.read = [this](const PixelRect& rect, float* out) {
      for (long y = 0; y < rect.height_px; ++y)
        for (long x = 0; x < rect.width_px; ++x)
          out[y * rect.width_px + x] = values_dn[static_cast<size_t>((rect.y0_px + y) * width_px + rect.x0_px + x)];
    };
    scan.width_px = width_px, scan.height_px = height_px;
    scan.dark = true;
    scan.low_dn = 0.0, scan.high_dn = 65535.0;
    return scan;
  }
};

// The place asked about: the window's middle.
DashPlace Place() {
  DashPlace p;
  p.centre_px = {32.0, 32.0};
  p.angle_rad = kAngle_rad;
  p.length_px = kDashLength_px;
  p.fwhm_px = kFwhm_px;
  p.flux_dn = kDashFlux_dn;
  return p;
}

// A detection as the detector would report it.
DetectedStar Detection(double x_px, double y_px, double length_px, double angle_rad, double flux_dn) {
  DetectedStar d;
  d.point.position_px = {x_px, y_px};
  d.length_px = length_px;
  d.angle_deg = angle_rad * 180.0 / std::numbers::pi;
  d.flux_dn = flux_dn;
  d.fwhm_px = kFwhm_px;
  return d;
}

PixelPoint Along(double along_px, double across_px = 0.0) {
  return {32.0 + along_px * std::cos(kAngle_rad) - across_px * std::sin(kAngle_rad),
          32.0 + along_px * std::sin(kAngle_rad) + across_px * std::cos(kAngle_rad)};
}

TEST(DashInPixels, ADashAloneShowsInItsThirds) {
  ImageBuffer image;
  image.Add(32.2, 31.9, kDashLength_px, kAngle_rad, kDashFlux_dn);  // 0.2 px off the place: the flow's tolerance
  image.AddNoise(1);
  const DashInPixels seen = MeasureDashInPixels(image.Scan(), Place(), {});
  ASSERT_TRUE(seen.measured);
  EXPECT_TRUE(seen.shown);
  EXPECT_FALSE(seen.absent);
  double sum_dn = 0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(seen.third_sigma_dn[k], 0.0);
    EXPECT_LT(seen.third_sigma_dn[k], 0.02 * kDashFlux_dn);
    sum_dn += seen.third_flux_dn[k];
  }
  EXPECT_NEAR(sum_dn, kDashFlux_dn, 0.05 * kDashFlux_dn);  // the thirds add up to the dash
}

TEST(DashInPixels, ADashMergedWithANeighbourIntoOneDetectionShows) {
  // The dash and a point image of half its flux 1.5 px beside its forward end, detected as one segment whose
  // centre, length and flux are no dash's: its centre lies on the sweep, so its light is what is asked about.
  ImageBuffer image;
  image.Add(32.0, 32.0, kDashLength_px, kAngle_rad, kDashFlux_dn);
  const PixelPoint n = Along(3.0, 1.5);
  image.Add(n.x_px, n.y_px, 0.0, 0.0, 0.5 * kDashFlux_dn);
  image.AddNoise(2);
  const PixelPoint merged = Along(1.0, 0.5);
  const DashInPixels seen = MeasureDashInPixels(
      image.Scan(), Place(), {Detection(merged.x_px, merged.y_px, 9.0, kAngle_rad + 0.1, 1.5 * kDashFlux_dn)});
  ASSERT_TRUE(seen.measured);
  EXPECT_EQ(seen.modelled, 0);
  EXPECT_TRUE(seen.shown);
  EXPECT_FALSE(seen.absent);
}

TEST(DashInPixels, AForeignImageBesideAnEmptyPlaceLeavesItEmpty) {
  // The place before a run is empty; another star's bright point image lies 3 px beside it, detected.
  ImageBuffer image;
  const PixelPoint f = Along(0.5, 3.0);
  image.Add(f.x_px, f.y_px, 0.0, 0.0, 2.0 * kDashFlux_dn);
  image.AddNoise(3);
  const DashInPixels seen =
      MeasureDashInPixels(image.Scan(), Place(), {Detection(f.x_px, f.y_px, 0.0, 0.0, 2.0 * kDashFlux_dn)});
  ASSERT_TRUE(seen.measured);
  EXPECT_EQ(seen.modelled, 1);
  EXPECT_FALSE(seen.shown);
  EXPECT_TRUE(seen.absent);
  EXPECT_LT(seen.max_overlap, 0.3);
}

TEST(DashInPixels, AForeignPointImageOnThePlaceIsNoDash) {
  // A point image of a dash's flux right on the place: its light fills the middle third, not the ends.
  ImageBuffer image;
  image.Add(32.0, 32.0, 0.0, 0.0, kDashFlux_dn);
  image.AddNoise(4);
  const DashInPixels seen = MeasureDashInPixels(image.Scan(), Place(), {Detection(32.0, 32.0, 0.0, 0.0, kDashFlux_dn)});
  ASSERT_TRUE(seen.measured);
  EXPECT_FALSE(seen.shown);
  EXPECT_FALSE(seen.absent);
  EXPECT_LT(seen.third_flux_dn[0], 0.5 * kDashFlux_dn / 3.0);
  EXPECT_LT(seen.third_flux_dn[2], 0.5 * kDashFlux_dn / 3.0);
}

TEST(DashInPixels, AnotherDashHalfADashAlongTheTrackIsNoDash) {
  // Another star's dash (the same direction and length: the flow's) half a dash along the track.
  ImageBuffer image;
  const PixelPoint f = Along(0.5 * kDashLength_px);
  image.Add(f.x_px, f.y_px, kDashLength_px, kAngle_rad, kDashFlux_dn);
  image.AddNoise(5);
  const DashInPixels seen =
      MeasureDashInPixels(image.Scan(), Place(), {Detection(f.x_px, f.y_px, kDashLength_px, kAngle_rad, kDashFlux_dn)});
  ASSERT_TRUE(seen.measured);
  EXPECT_FALSE(seen.shown);
  EXPECT_FALSE(seen.absent);
}

TEST(DashInPixels, AnotherStarsBrighterDashBesideTheTrackIsNoDash) {
  // Another star's dash on a nearly parallel path, 1.6 times the dash's flux, 0.8 FWHM beside the track (Cairo:
  // KS7763's dash before KS13496's run). Its light spreads over all three thirds, but a detection holding the
  // dash merged with another image of a third of its light would lie within a third of a FWHM of the track:
  // this one is another star's image, modelled, and the place shows no dash.
  ImageBuffer image;
  const PixelPoint f = Along(0.3, 0.8 * kFwhm_px);
  image.Add(f.x_px, f.y_px, kDashLength_px, kAngle_rad, 1.6 * kDashFlux_dn);
  image.AddNoise(8);
  const DetectedStar other = Detection(f.x_px, f.y_px, kDashLength_px, kAngle_rad, 1.6 * kDashFlux_dn);
  DashPlace place = Place();
  place.tolerance_px = 0.4;  // the flow's
  const DashInPixels seen = MeasureDashInPixels(image.Scan(), place, {other});
  ASSERT_TRUE(seen.measured);
  EXPECT_EQ(seen.modelled, 1);
  EXPECT_FALSE(seen.shown);
  EXPECT_FALSE(seen.absent);  // (its light overlaps the dash's: no place to call empty either)
  // Where the flow put the place 1 px off the track, the detection may be the dash merged: asked about.
  place.tolerance_px = 1.0;
  EXPECT_EQ(MeasureDashInPixels(image.Scan(), place, {other}).modelled, 0);
}

TEST(DashInPixels, ADetectionThatMayHoldTheDashLeavesItUndecided) {
  // The dash merged with a point image of its flux 3 px beside it into one broad detection (FWHM 3.5 px),
  // centred 2.2 px off the track: off the sweep, so it is modelled, its flux free, and its model may take
  // the dash's light. The place is not called empty.
  ImageBuffer image;
  image.Add(32.0, 32.0, kDashLength_px, kAngle_rad, kDashFlux_dn);
  const PixelPoint n = Along(0.0, 3.0);
  image.Add(n.x_px, n.y_px, 0.0, 0.0, kDashFlux_dn);
  image.AddNoise(6);
  const PixelPoint merged = Along(0.0, 2.2);
  DetectedStar blob = Detection(merged.x_px, merged.y_px, 6.0, kAngle_rad, 2.0 * kDashFlux_dn);
  blob.fwhm_px = 3.5;
  const DashInPixels seen = MeasureDashInPixels(image.Scan(), Place(), {blob});
  EXPECT_EQ(seen.modelled, 1);
  EXPECT_GT(seen.max_overlap, 0.3);
  EXPECT_FALSE(seen.absent);
}

TEST(DashInPixels, NothingIsMeasuredOffTheScanOrBesideAClippedPixel) {
  ImageBuffer image;
  image.Add(32.0, 32.0, kDashLength_px, kAngle_rad, kDashFlux_dn);
  image.AddNoise(7);
  DashPlace near_edge = Place();
  near_edge.centre_px = {4.0, 32.0};
  EXPECT_FALSE(MeasureDashInPixels(image.Scan(), near_edge, {}).measured);
  // A saturated pixel on the sweep: the dash's light there is not measured.
  image.values_dn[32 * 64 + 33] = 0.0f;
  const DashInPixels seen = MeasureDashInPixels(image.Scan(), Place(), {});
  EXPECT_FALSE(seen.measured);
  EXPECT_FALSE(seen.shown);
  EXPECT_FALSE(seen.absent);
}

}  // namespace
}  // namespace platemeter
