// Rendered marks land where the scene says, to a small fraction of a pixel:
// noise-free crosses and stars at a 7 x 7 grid of sub-pixel offsets (with and
// without scanner rotation) are re-measured by independent symmetric methods
// written here, which rely only on the DESIGN.md pixel convention:
// - cross: first-moment centroids of 1D profiles across each arm (columns across
//   the horizontal arm, rows across the vertical one), a straight line fitted
//   through each arm's centroids, the centre = the lines' intersection;
// - star / trail: the 2D first moment over a large window, background known.
// With a blur of >= 0.8 px the sampling (aliasing) error of a first moment is
// below 1e-5 px, so any error found is the renderer's.
#include <array>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "platemeter/samples/render.h"

namespace platemeter::sim {
namespace {

constexpr long kSize = 128;
constexpr double kLevel = 5000.0;

void SetFrame(SceneMark* mark, double angle_rad, double scale, bool mirror) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad), m = mirror ? -1.0 : 1.0;
  // Rotation by angle_rad then (optionally) the plate's v-up to rows-down mirror.
  mark->px_from_um[0] = scale * c;
  mark->px_from_um[1] = -scale * s;
  mark->px_from_um[2] = m * scale * s;
  mark->px_from_um[3] = m * scale * c;
}

Scene OneMarkScene(const SceneMark& mark, double blur_px) {
  Scene scene;
  scene.width_px = kSize;
  scene.height_px = kSize;
  scene.background.level_dn = kLevel;
  scene.noise.scanner_blur_sigma_px = blur_px;
  scene.noise.quantize = false;
  scene.marks.push_back(mark);
  return scene;
}

// Image minus the known background, as double.
std::vector<double> RenderContrast(const Scene& scene) {
  std::vector<float> image(kSize * kSize);
  RenderBand(scene, 0, kSize, image.data());
  std::vector<double> contrast(image.size());
  for (size_t i = 0; i < image.size(); ++i) contrast[i] = image[i] - kLevel;
  return contrast;
}

// Least-squares line b = p + q a through points (a, b).
void FitLine(const std::vector<double>& a, const std::vector<double>& b, double* p, double* q) {
  double n = a.size(), sa = 0, sb = 0, saa = 0, sab = 0;
  for (size_t i = 0; i < a.size(); ++i) sa += a[i], sb += b[i], saa += a[i] * a[i], sab += a[i] * b[i];
  *q = (n * sab - sa * sb) / (n * saa - sa * sa);
  *p = (sb - *q * sa) / n;
}

// Measures a cross's centre from arm profiles. The arms' slopes (from the
// mark's frame) only place the profile windows; inner/outer_px bound the
// distance of the profiles from the centre (clear of the other arm and the tips).
PixelPoint MeasureCross(const std::vector<double>& image, const SceneMark& mark, double half_width_px,
                        double blur_px, double inner_px, double outer_px) {
  const PixelPoint guess = mark.centre_px;
  const double slope_h = mark.px_from_um[2] / mark.px_from_um[0];  // dy/dx along the u arm
  const double slope_v = mark.px_from_um[1] / mark.px_from_um[3];  // dx/dy along the v arm
  const double window_h = half_width_px * std::sqrt(1 + slope_h * slope_h) + 9.0 * blur_px + 2.0;
  const double window_v = half_width_px * std::sqrt(1 + slope_v * slope_v) + 9.0 * blur_px + 2.0;
  std::vector<double> xs, ys;
  for (long x = 0; x < kSize; ++x) {
    const double d = std::abs(x - guess.x_px);
    if (d < inner_px || d > outer_px) continue;
    const double line_y = guess.y_px + slope_h * (x - guess.x_px);
    double s0 = 0, s1 = 0;
    for (long y = std::lround(line_y - window_h); y <= std::lround(line_y + window_h); ++y) {
      s0 += image[y * kSize + x];
      s1 += image[y * kSize + x] * y;
    }
    xs.push_back(x);
    ys.push_back(s1 / s0);
  }
  std::vector<double> rows, cols;
  for (long y = 0; y < kSize; ++y) {
    const double d = std::abs(y - guess.y_px);
    if (d < inner_px || d > outer_px) continue;
    const double line_x = guess.x_px + slope_v * (y - guess.y_px);
    double s0 = 0, s1 = 0;
    for (long x = std::lround(line_x - window_v); x <= std::lround(line_x + window_v); ++x) {
      s0 += image[y * kSize + x];
      s1 += image[y * kSize + x] * x;
    }
    rows.push_back(y);
    cols.push_back(s1 / s0);
  }
  EXPECT_GE(xs.size(), 20u);
  EXPECT_GE(rows.size(), 20u);
  double a, b, c, d;
  FitLine(xs, ys, &a, &b);      // y = a + b x
  FitLine(rows, cols, &c, &d);  // x = c + d y
  const double x = (c + d * a) / (1.0 - d * b);
  return {x, a + b * x};
}

TEST(RenderCentre, CrossLandsWhereTheSceneSaysAtEverySubPixelOffset) {
  for (double angle : {0.0, 0.04, 0.2}) {
    double sum_dx = 0, sum_dy = 0, worst = 0;
    int count = 0;
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j) {
        SceneMark mark;
        mark.id = "X1Y1";
        mark.centre_px = {63.0 - 0.5 + i / 7.0, 64.0 - 0.5 + j / 7.0};
        mark.size_um = 400.0;  // 80 px tip to tip at 0.2 px/um
        mark.line_width_um = 20.0;
        mark.amplitude_dn = -1000.0;
        SetFrame(&mark, -angle, 0.2, true);
        const double blur = 0.8;
        const auto image = RenderContrast(OneMarkScene(mark, blur));
        // Profiles from 9 px (clear of the other arm: centre square + blur + tilt) to 30 px (clear of the tips at 40).
        const PixelPoint measured = MeasureCross(image, mark, 2.0, blur, 9.0, 30.0);
        const double dx = measured.x_px - mark.centre_px.x_px, dy = measured.y_px - mark.centre_px.y_px;
        sum_dx += dx, sum_dy += dy, ++count;
        worst = std::max({worst, std::abs(dx), std::abs(dy)});
        EXPECT_LT(std::abs(dx), 0.002) << "angle " << angle << " offset " << i << "," << j;
        EXPECT_LT(std::abs(dy), 0.002) << "angle " << angle << " offset " << i << "," << j;
      }
    EXPECT_LT(std::abs(sum_dx / count), 0.0005) << "x bias at angle " << angle;
    EXPECT_LT(std::abs(sum_dy / count), 0.0005) << "y bias at angle " << angle;
    RecordProperty("worst_cross_error_px_angle_" + std::to_string(angle), std::to_string(worst));
  }
}

PixelPoint FirstMoment(const std::vector<double>& image, PixelPoint guess, double half_window) {
  double s0 = 0, sx = 0, sy = 0;
  for (long y = std::lround(guess.y_px - half_window); y <= std::lround(guess.y_px + half_window); ++y)
    for (long x = std::lround(guess.x_px - half_window); x <= std::lround(guess.x_px + half_window); ++x) {
      const double v = image[y * kSize + x];
      s0 += v, sx += v * x, sy += v * y;
    }
  return {sx / s0, sy / s0};
}

TEST(RenderCentre, StarsAndTrailsLandWhereTheSceneSays) {
  struct Case {
    const char* name;
    double angle, skew, segment_u, segment_v;
  };
  const Case cases[] = {{"star", 0.0, 0.0, 0, 0},
                        {"rotated star", 0.3, 0.0, 0, 0},
                        {"skewed star (anisotropic PSF)", 0.1, 0.03, 0, 0},
                        {"trail dash", 0.2, 0.0, 60.0, 25.0},
                        {"skewed trail", 0.0, 0.02, -40.0, 70.0}};
  for (const Case& c : cases) {
    double sum_dx = 0, sum_dy = 0;
    int count = 0;
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j) {
        SceneMark mark;
        mark.kind = MarkKind::kStar;
        mark.shape = c.segment_u == 0 ? MarkShapeKind::kPsf : MarkShapeKind::kSegment;
        mark.centre_px = {64.0 - 0.5 + i / 7.0, 63.0 - 0.5 + j / 7.0};
        mark.psf_fwhm_um = 15.0;  // 3 px FWHM at 0.2 px/um
        mark.segment_u_um = c.segment_u;
        mark.segment_v_um = c.segment_v;
        mark.amplitude_dn = 50000.0;  // flux, DN px^2
        SetFrame(&mark, c.angle, 0.2, true);
        mark.px_from_um[1] += c.skew;
        const auto image = RenderContrast(OneMarkScene(mark, 0.5));
        const PixelPoint m = FirstMoment(image, mark.centre_px, 30.0);
        const double dx = m.x_px - mark.centre_px.x_px, dy = m.y_px - mark.centre_px.y_px;
        sum_dx += dx, sum_dy += dy, ++count;
        EXPECT_LT(std::abs(dx), 0.002) << c.name << " offset " << i << "," << j;
        EXPECT_LT(std::abs(dy), 0.002) << c.name << " offset " << i << "," << j;
      }
    EXPECT_LT(std::abs(sum_dx / count), 0.0005) << c.name;
    EXPECT_LT(std::abs(sum_dy / count), 0.0005) << c.name;
  }
}

// The unblurred (exact coverage) cross against an independent area integral:
// for a rotated, mirrored cross, a pixel's covered area is the integral over x
// of the covered length of the vertical line at x (each bar is a convex
// parallelogram: the line meets it in one interval, found from its edges),
// summed by a fine midpoint rule (the length is piecewise linear in x).
TEST(RenderCentre, UnblurredRotatedCrossMatchesAnIndependentAreaIntegral) {
  SceneMark mark;
  mark.centre_px = {20.37, 19.71};
  mark.size_um = 60.0;
  mark.line_width_um = 12.0;
  mark.amplitude_dn = 1.0;
  SetFrame(&mark, 0.37, 0.2, true);
  const MarkModel model(mark, 0.0);
  const double* a = mark.px_from_um;
  auto corner = [&](double u, double v) {
    return std::array<double, 2>{mark.centre_px.x_px + a[0] * u + a[1] * v, mark.centre_px.y_px + a[2] * u + a[3] * v};
  };
  using Polygon = std::array<std::array<double, 2>, 4>;
  const Polygon bar_u = {corner(-30, -6), corner(30, -6), corner(30, 6), corner(-30, 6)};
  const Polygon bar_v = {corner(-6, -30), corner(6, -30), corner(6, 30), corner(-6, 30)};
  // The interval [lo, hi] where the vertical line at x meets a convex polygon (empty: lo > hi).
  auto meet = [](const Polygon& poly, double x, double* lo, double* hi) {
    *lo = 1e300, *hi = -1e300;
    for (int i = 0; i < 4; ++i) {
      const auto& p = poly[i];
      const auto& q = poly[(i + 1) % 4];
      if ((x < std::min(p[0], q[0])) || (x > std::max(p[0], q[0])) || p[0] == q[0]) continue;
      const double y = p[1] + (x - p[0]) * (q[1] - p[1]) / (q[0] - p[0]);
      *lo = std::min(*lo, y), *hi = std::max(*hi, y);
    }
  };
  auto overlap = [](double lo1, double hi1, double lo2, double hi2) {
    return std::max(0.0, std::min(hi1, hi2) - std::max(lo1, lo2));
  };
  constexpr int kColumns = 4000;
  double worst = 0.0, total = 0.0;
  for (long y = 10; y < 30; ++y)
    for (long x = 10; x < 31; ++x) {
      double area = 0.0;
      for (int k = 0; k < kColumns; ++k) {
        const double xs = x - 0.5 + (k + 0.5) / kColumns;
        double lo1, hi1, lo2, hi2;
        meet(bar_u, xs, &lo1, &hi1);
        meet(bar_v, xs, &lo2, &hi2);
        const double length = overlap(lo1, hi1, y - 0.5, y + 0.5) + overlap(lo2, hi2, y - 0.5, y + 0.5) -
                              overlap(std::max(lo1, lo2), std::min(hi1, hi2), y - 0.5, y + 0.5);
        area += length / kColumns;
      }
      total += area;
      worst = std::max(worst, std::abs(model.PixelValue(x, y) - area));
    }
  EXPECT_LT(worst, 1e-6);
  EXPECT_NEAR(total, (2 * 60.0 * 12.0 - 12.0 * 12.0) * 0.04, 1e-4);  // the whole cross is inside the loop
}

}  // namespace
}  // namespace platemeter::sim
