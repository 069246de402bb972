// The renderer's marks against independent truth: closed-form pixel integrals
// of axis-aligned blurred rectangles, exact coverage of unblurred bars, total
// flux equal to amplitude x area, and quadrature convergence (two node counts).
#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "platemeter/core/error.h"
#include "platemeter/samples/render_model.h"

namespace platemeter::sim {
namespace {

// Integral over [lo, hi] of Phi((t - mu) / s): s [Psi((hi - mu)/s) - Psi((lo - mu)/s)], Psi(z) = z Phi(z) + phi(z).
double IntegralOfPhi(double lo, double hi, double mu, double s) {
  auto psi = [](double z) { return z * 0.5 * std::erfc(-z / std::sqrt(2.0)) + std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI); };
  return s * (psi((hi - mu) / s) - psi((lo - mu) / s));
}
// Mean over the pixel [x-0.5, x+0.5) of the blurred indicator of [c - a, c + a].
double BlurredIntervalPixel(long x, double c, double a, double s) {
  // indicator blurred = Phi((t - c + a)/s) - Phi((t - c - a)/s)
  return IntegralOfPhi(x - 0.5, x + 0.5, c - a, s) - IntegralOfPhi(x - 0.5, x + 0.5, c + a, s);
}
double IntervalOverlap(double lo1, double hi1, double lo2, double hi2) {
  return std::max(0.0, std::min(hi1, hi2) - std::max(lo1, lo2));
}

SceneMark Cross(double cx, double cy, double angle_rad = 0.0, double scale = 0.2) {
  SceneMark mark;
  mark.id = "X1Y1";
  mark.shape = MarkShapeKind::kCross;
  mark.centre_px = {cx, cy};
  mark.size_um = 200.0;
  mark.line_width_um = 20.0;
  mark.amplitude_dn = -1000.0;
  // u right, v up on the plate; rows grow downwards: a mirrored rotation.
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  mark.px_from_um[0] = scale * c;
  mark.px_from_um[1] = -scale * s;
  mark.px_from_um[2] = -scale * s;
  mark.px_from_um[3] = -scale * c;
  return mark;
}

double SumOver(const MarkModel& model) {
  const PixelRect& s = model.support();
  const auto values = MarkModelWindow(model, s);
  return std::accumulate(values.begin(), values.end(), 0.0);
}

TEST(RenderMarks, AxisAlignedBlurredCrossMatchesClosedForm) {
  for (double blur : {0.3, 0.55, 1.2}) {
    const SceneMark mark = Cross(100.37, 80.81);
    const MarkModel model(mark, blur);
    // Cross = bar_x + bar_y - square; px half sizes: 100 um * 0.2 = 20 px, 10 um * 0.2 = 2 px.
    double worst = 0.0;
    const PixelRect& s = model.support();
    for (long y = s.y0_px; y < s.y_end_px(); ++y)
      for (long x = s.x0_px; x < s.x_end_px(); ++x) {
        const double bx_long = BlurredIntervalPixel(x, 100.37, 20.0, blur);
        const double bx_thin = BlurredIntervalPixel(x, 100.37, 2.0, blur);
        const double by_long = BlurredIntervalPixel(y, 80.81, 20.0, blur);
        const double by_thin = BlurredIntervalPixel(y, 80.81, 2.0, blur);
        const double truth = -1000.0 * (bx_long * by_thin + bx_thin * by_long - bx_thin * by_thin);
        worst = std::max(worst, std::abs(model.PixelValue(x, y) - truth));
      }
    EXPECT_LT(worst, 1e-5) << "blur " << blur << " px: worst pixel error in DN (amplitude 1000)";
    // Outside the support the closed form is negligible.
    EXPECT_LT(std::abs(1000.0 * BlurredIntervalPixel(s.x0_px - 1, 100.37, 20.0, blur)), 1e-9);
  }
}

TEST(RenderMarks, UnblurredBarCoverageIsExact) {
  // A scratch along u, 30 um x 7 um at 0.1 px/um, no mirror: x in [c-1.5, c+1.5], y in [c-0.35, c+0.35].
  SceneMark mark;
  mark.kind = MarkKind::kScratch;
  mark.centre_px = {10.3, 20.62};
  mark.size_um = 30.0;
  mark.line_width_um = 7.0;
  mark.amplitude_dn = 500.0;
  mark.px_from_um[0] = 0.1, mark.px_from_um[1] = 0, mark.px_from_um[2] = 0, mark.px_from_um[3] = 0.1;
  const MarkModel model(mark, 0.0);
  for (long y = 18; y < 24; ++y)
    for (long x = 6; x < 15; ++x) {
      const double truth = 500.0 * IntervalOverlap(x - 0.5, x + 0.5, 10.3 - 1.5, 10.3 + 1.5) *
                           IntervalOverlap(y - 0.5, y + 0.5, 20.62 - 0.35, 20.62 + 0.35);
      EXPECT_NEAR(model.PixelValue(x, y), truth, 1e-9) << x << "," << y;
    }
}

TEST(RenderMarks, TotalIntegralIsAmplitudeTimesArea) {
  const double det = 0.2 * 0.2;  // px^2 per um^2 of the rotated, mirrored frame
  struct Case {
    const char* name;
    SceneMark mark;
    double area_um2;  // or 1/det for flux marks
  };
  std::vector<Case> cases;
  SceneMark cross = Cross(50.2, 60.7, 0.37);
  cases.push_back({"cross", cross, 2 * 200.0 * 20.0 - 20.0 * 20.0});
  SceneMark damaged = cross;
  damaged.damage_fraction = 0.3;
  damaged.seed = 17;
  cases.push_back({"damaged cross", damaged, 2 * 200.0 * 20.0 - 20.0 * 20.0 - 0.3 * 4 * 90.0 * 20.0});
  SceneMark dot = cross;
  dot.shape = MarkShapeKind::kDot;
  dot.size_um = 80.0;
  cases.push_back({"dot", dot, M_PI * 40.0 * 40.0});
  SceneMark ring = dot;
  ring.shape = MarkShapeKind::kRing;
  ring.size_um = 150.0;
  ring.line_width_um = 15.0;
  cases.push_back({"ring", ring, M_PI * (75.0 * 75.0 - 60.0 * 60.0)});
  SceneMark corner = cross;
  corner.shape = MarkShapeKind::kCorner;
  corner.size_um = 150.0;
  corner.corner_angle_rad = 0.8;
  cases.push_back({"corner", corner, 2 * 150.0 * 20.0});
  SceneMark dust = dot;
  dust.kind = MarkKind::kDust;
  cases.push_back({"dust", dust, M_PI * 40.0 * 40.0});
  SceneMark scratch = cross;
  scratch.kind = MarkKind::kScratch;
  scratch.size_um = 300.0;
  scratch.line_width_um = 6.0;
  scratch.corner_angle_rad = 1.1;
  cases.push_back({"scratch", scratch, 300.0 * 6.0});
  SceneMark star = cross;
  star.kind = MarkKind::kStar;
  star.shape = MarkShapeKind::kPsf;
  star.psf_fwhm_um = 12.0;
  star.amplitude_dn = 40000.0;
  cases.push_back({"star", star, 1.0 / det});
  SceneMark trail = star;
  trail.kind = MarkKind::kTrailDash;
  trail.shape = MarkShapeKind::kSegment;
  trail.segment_u_um = 120.0;
  trail.segment_v_um = -45.0;
  cases.push_back({"trail", trail, 1.0 / det});
  SceneMark skew_star = star;  // not a similarity: anisotropic PSF, quadrature path
  skew_star.px_from_um[1] += 0.03;
  skew_star.px_from_um[2] += 0.01;
  const double skew_det = std::abs(skew_star.px_from_um[0] * skew_star.px_from_um[3] -
                                   skew_star.px_from_um[1] * skew_star.px_from_um[2]);
  cases.push_back({"skewed star", skew_star, 1.0 / skew_det});

  for (double blur : {0.0, 0.45, 0.9}) {
    for (const Case& c : cases) {
      const bool needs_blur = c.mark.shape == MarkShapeKind::kPsf || c.mark.shape == MarkShapeKind::kSegment;
      if (blur == 0.0 && needs_blur && c.mark.psf_fwhm_um == 0.0) continue;
      const MarkModel model(c.mark, blur);
      const double this_det = std::string(c.name) == "skewed star" ? skew_det : det;
      const double expected = c.mark.amplitude_dn * c.area_um2 * this_det;
      EXPECT_NEAR(SumOver(model) / expected, 1.0, 2e-7) << c.name << " blur " << blur;
    }
  }
}

// The pixel integration is converged: 12 instead of 8 nodes on sub-cells three
// times smaller move no pixel by more than 1e-7 of the amplitude and the image
// centroid by far less than 0.001 px (1e-7 px).
TEST(RenderMarks, QuadratureIsConverged) {
  RenderOptions fine;
  fine.quadrature_nodes = 12;
  fine.max_cell_over_sigma = 0.7;
  for (double blur : {0.12, 0.3, 0.6}) {
    for (MarkShapeKind shape : {MarkShapeKind::kCross, MarkShapeKind::kRing, MarkShapeKind::kPsf}) {
      SceneMark mark = Cross(40.31, 41.77, 0.23);
      mark.shape = shape;
      if (shape == MarkShapeKind::kRing) mark.size_um = 120.0;
      if (shape == MarkShapeKind::kPsf) {
        mark.psf_fwhm_um = 3.0;  // narrow: 0.26 px sigma on the plate
        mark.amplitude_dn = 1000.0;
        mark.px_from_um[1] += 0.02;  // anisotropic: quadrature path
      }
      const MarkModel coarse_model(mark, blur);
      const MarkModel fine_model(mark, blur, fine);
      const PixelRect& s = coarse_model.support();
      double worst = 0.0, sx_c = 0, sy_c = 0, s_c = 0, sx_f = 0, sy_f = 0, s_f = 0;
      for (long y = s.y0_px; y < s.y_end_px(); ++y)
        for (long x = s.x0_px; x < s.x_end_px(); ++x) {
          const double a = coarse_model.PixelValue(x, y), b = fine_model.PixelValue(x, y);
          worst = std::max(worst, std::abs(a - b));
          sx_c += a * x, sy_c += a * y, s_c += a;
          sx_f += b * x, sy_f += b * y, s_f += b;
        }
      EXPECT_LT(worst, 1e-4) << "shape " << static_cast<int>(shape) << " blur " << blur;  // DN of 1000
      EXPECT_LT(std::abs(sx_c / s_c - sx_f / s_f), 1e-7);
      EXPECT_LT(std::abs(sy_c / s_c - sy_f / s_f), 1e-7);
    }
  }
}

// Along the bars the pixel mean is taken in closed form (box averages of the
// blurred edge); it must agree with brute-force quadrature at every rotation,
// including nearly axis-aligned ones where the closed form switches to its
// small-width expansion.
TEST(RenderMarks, ClosedFormEdgesAgreeWithQuadrature) {
  RenderOptions quadrature;
  quadrature.closed_form = false;
  quadrature.quadrature_nodes = 12;
  quadrature.max_cell_over_sigma = 0.7;
  for (double angle : {0.0, 1e-5, 3e-4, 0.0015, 0.02, 0.4, M_PI / 4}) {
    for (double blur : {0.15, 0.6, 2.0}) {
      const SceneMark mark = Cross(40.31, 41.77, angle);
      const MarkModel closed(mark, blur), brute(mark, blur, quadrature);
      const PixelRect& s = closed.support();
      double worst = 0.0;
      for (long y = s.y0_px; y < s.y_end_px(); ++y)
        for (long x = s.x0_px; x < s.x_end_px(); ++x)
          worst = std::max(worst, std::abs(closed.PixelValue(x, y) - brute.PixelValue(x, y)));
      EXPECT_LT(worst, 1e-6) << "angle " << angle << " blur " << blur;  // DN of 1000
      // A trail dash: isotropic PSF swept along a segment at the same angle.
      SceneMark dash = Cross(40.31, 41.77, angle);
      dash.kind = MarkKind::kTrailDash;
      dash.shape = MarkShapeKind::kSegment;
      dash.psf_fwhm_um = 8.0;
      dash.segment_u_um = 150.0;
      dash.amplitude_dn = 1e5;
      const MarkModel dash_closed(dash, blur), dash_brute(dash, blur, quadrature);
      const PixelRect& d = dash_closed.support();
      double dash_worst = 0.0;
      for (long y = d.y0_px; y < d.y_end_px(); ++y)
        for (long x = d.x0_px; x < d.x_end_px(); ++x)
          dash_worst = std::max(dash_worst, std::abs(dash_closed.PixelValue(x, y) - dash_brute.PixelValue(x, y)));
      EXPECT_LT(dash_worst, 1e-7) << "dash angle " << angle << " blur " << blur;  // DN of a 1e5 flux
    }
  }
}

TEST(RenderMarks, DamageIsDeterministicAndRemovesTheArms) {
  SceneMark mark = Cross(50.0, 50.0);
  mark.damage_fraction = 0.5;
  mark.seed = 99;
  const MarkModel a(mark, 0.5), b(mark, 0.5);
  const auto va = MarkModelWindow(a, a.support()), vb = MarkModelWindow(b, b.support());
  EXPECT_EQ(va, vb);
  mark.seed = 100;
  const MarkModel c(mark, 0.5);
  EXPECT_NE(va, MarkModelWindow(c, a.support()));
}

TEST(RenderMarks, BadMarksThrow) {
  SceneMark mark = Cross(0, 0);
  mark.line_width_um = 0.0;
  EXPECT_THROW(MarkModel(mark, 0.5), Error);
  mark = Cross(0, 0);
  mark.px_from_um[0] = mark.px_from_um[3] = 0.0;
  mark.px_from_um[1] = mark.px_from_um[2] = 0.0;
  EXPECT_THROW(MarkModel(mark, 0.5), Error);
  mark = Cross(0, 0);
  mark.shape = MarkShapeKind::kPsf;
  mark.psf_fwhm_um = 0.0;
  EXPECT_THROW(MarkModel(mark, 0.0), Error);
  RenderOptions bad;
  bad.quadrature_nodes = 1;
  EXPECT_THROW(MarkModel(Cross(0, 0), 0.5, bad), Error);
}

}  // namespace
}  // namespace platemeter::sim
