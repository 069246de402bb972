// Masked pixels (core/image.h: NaN as reads return them) in the star detector:
// the matched filter takes them for background and the fits leave them out, so
// a star with a masked pixel in its image is measured where the clean image puts
// it, and one whose fit window is mostly masked is rejected as masked_pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/detect/star_detector.h"

namespace platemeter {
namespace {

constexpr long kSize = 420;
constexpr double kSigmaPx = 1.0;  // PSF sigma
constexpr double kSpacingPx = 70.0;

PixelPoint StarCentre(int k) {
  // A 5 x 5 grid with sub-pixel offsets that differ from star to star.
  return {50.0 + kSpacingPx * (k % 5) + 0.13 * (k % 7), 50.0 + kSpacingPx * (k / 5) + 0.21 * (k % 3)};
}

// Background 1000 DN, white noise of 10 DN, 25 bright Gaussian stars of 20000 DN (pixel-integrated).
std::vector<float> Scene() {
  std::vector<float> v(static_cast<size_t>(kSize * kSize), 1000.0f);
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 10.0f);
  for (float& x : v) x += noise(rng);
  const double s2 = std::sqrt(2.0) * kSigmaPx;
  for (int k = 0; k < 25; ++k) {
    const PixelPoint c = StarCentre(k);
    for (long y = std::lround(c.y_px) - 6; y <= std::lround(c.y_px) + 6; ++y)
      for (long x = std::lround(c.x_px) - 6; x <= std::lround(c.x_px) + 6; ++x) {
        const double fx = 0.5 * (std::erf((x + 0.5 - c.x_px) / s2) - std::erf((x - 0.5 - c.x_px) / s2));
        const double fy = 0.5 * (std::erf((y + 0.5 - c.y_px) / s2) - std::erf((y - 0.5 - c.y_px) / s2));
        v[static_cast<size_t>(y * kSize + x)] += static_cast<float>(20000.0 * fx * fy);
      }
  }
  return v;
}

StarDetectorOptions OptionsNonFinite() {
  StarDetectorOptions o;
  o.dark = false;
  o.psf_fwhm_px = 2.3548 * kSigmaPx;
  return o;
}

const DetectedStar* Nearest(const std::vector<DetectedStar>& stars, const PixelPoint& p) {
  const DetectedStar* best = nullptr;
  for (const DetectedStar& s : stars) {
    const double d = std::hypot(s.point.position_px.x_px - p.x_px, s.point.position_px.y_px - p.y_px);
    if (d < 2.0 && (!best || d < std::hypot(best->point.position_px.x_px - p.x_px,
                                             best->point.position_px.y_px - p.y_px)))
      best = &s;
  }
  return best;
}

TEST(NonFiniteStars, MaskedPixelsAreLeftOutAndAMostlyMaskedStarIsRejected) {
  const std::vector<float> clean = Scene();
  std::vector<float> masked = clean;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto set_nan = [&](long x, long y) { masked[static_cast<size_t>(y * kSize + x)] = nan; };
  // Stars 0..9: one masked pixel in the image's wing, 2 px from its centre.
  for (int k = 0; k < 10; ++k) {
    const PixelPoint c = StarCentre(k);
    set_nan(std::lround(c.x_px) + (k % 2 ? 2 : -2), std::lround(c.y_px) + (k % 3 == 0 ? 1 : 0));
  }
  // Star 12: a 7 x 13 px hole over the right half of its image (its peak still shows).
  const PixelPoint hole = StarCentre(12);
  for (long y = std::lround(hole.y_px) - 6; y <= std::lround(hole.y_px) + 6; ++y)
    for (long x = std::lround(hole.x_px) + 1; x <= std::lround(hole.x_px) + 7; ++x) set_nan(x, y);
  // And 50 scattered between the stars (every star's 13 x 13 box stays clear).
  std::mt19937 rng(28);
  for (int placed = 0; placed < 50;) {
    const long x = static_cast<long>(rng() % kSize), y = static_cast<long>(rng() % kSize);
    const double fx = std::fmod(x - 50.0 + 1000.0 * kSpacingPx, kSpacingPx), fy = std::fmod(y - 50.0 + 1000.0 * kSpacingPx, kSpacingPx);
    if (std::min(fx, kSpacingPx - fx) < 8 || std::min(fy, kSpacingPx - fy) < 8) continue;
    set_nan(x, y), ++placed;
  }
  ASSERT_EQ(CountMaskedPixels(masked.data(), masked.size()), 10u + 91u + 50u);

  const std::vector<DetectedStar> a = DetectStarsInBuffer(clean.data(), kSize, kSize, 65535.0, OptionsNonFinite());
  const std::vector<DetectedStar> b = DetectStarsInBuffer(masked.data(), kSize, kSize, 65535.0, OptionsNonFinite());
  int measured = 0;
  for (const DetectedStar& s : b) {
    EXPECT_FALSE(std::isnan(s.point.position_px.x_px) || std::isnan(s.flux_dn));
    measured += s.point.status == PointStatus::kMeasured;
  }
  EXPECT_EQ(measured, 24);  // all but the one in the hole; no false image at a masked pixel
  for (int k = 0; k < 25; ++k) {
    const DetectedStar* c = Nearest(a, StarCentre(k));
    const DetectedStar* m = Nearest(b, StarCentre(k));
    ASSERT_TRUE(c && m) << "star " << k;
    ASSERT_EQ(c->point.status, PointStatus::kMeasured) << "star " << k;
    if (k == 12) {
      EXPECT_EQ(m->point.status, PointStatus::kRejected);
      EXPECT_EQ(m->point.reason, "masked_pixels");
      continue;
    }
    ASSERT_EQ(m->point.status, PointStatus::kMeasured) << "star " << k;
    EXPECT_LT(std::abs(m->point.position_px.x_px - c->point.position_px.x_px), c->point.sigma_x_px) << "star " << k;
    EXPECT_LT(std::abs(m->point.position_px.y_px - c->point.position_px.y_px), c->point.sigma_y_px) << "star " << k;
    EXPECT_NEAR(m->flux_dn, c->flux_dn, 2.0 * c->sigma_flux_dn) << "star " << k;
    if (k >= 10) {  // nothing masked in its image: only the background mesh may differ a little
      EXPECT_NEAR(m->point.position_px.x_px, c->point.position_px.x_px, 0.1 * c->point.sigma_x_px) << "star " << k;
    }
  }
}

}  // namespace
}  // namespace platemeter
