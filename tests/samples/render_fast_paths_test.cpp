// The renderer's fast paths against the plain formulas they replace: the
// tabulated normal CDF against erfc, the split (factored) quadrature of swept
// and anisotropic Gaussians against a brute-force pixel integral of the swept
// density written here from its definition, the five shifted values of
// PixelValuesShifted against five PixelValueWithCentre calls, and the
// Cramer-Rao bound against its Fisher sum written out pixel by pixel.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "../../samples/src/render_geometry.h"
#include "platemeter/samples/render_crb.h"
#include "platemeter/samples/render_model.h"

namespace platemeter::sim {
namespace {

double PhiNormal(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

TEST(RenderFastPaths, TabulatedNormalCdfMatchesErfc) {
  const render_detail::NormalCdfTable& table = render_detail::TheNormalCdfTable();
  double worst = 0.0;
  for (long k = -2000000; k <= 2000000; ++k) {
    const double z = k * 1e-5 * 1.00000017;  // off the table's grid
    worst = std::max(worst, std::abs(render_detail::FastNormalCdf(table, z) - PhiNormal(z)));
  }
  EXPECT_LT(worst, 1e-15);
  EXPECT_EQ(render_detail::FastNormalCdf(table, 8.5), 1.0);
  EXPECT_EQ(render_detail::FastNormalCdf(table, 40.0), 1.0);
  EXPECT_LT(render_detail::FastNormalCdf(table, -40.0), 1e-16);
  EXPECT_EQ(render_detail::FastNormalCdf(table, std::nan("")), render_detail::FastNormalCdf(table, -40.0));
  // Each interval's polynomial holds to twice its half width (the shifted
  // Cramer-Rao values share one interval).
  using Table = render_detail::NormalCdfTable;
  double worst_far = 0.0;
  for (int i = 0; i < Table::kIntervals; ++i) {
    const double centre = (i + 0.5) / Table::kPerUnit - Table::kLimit;
    for (double t : {-1.0 / Table::kPerUnit, 1.0 / Table::kPerUnit}) {
      const double* c = table.coefficients[i];
      double value = c[7];
      for (int k = 6; k >= 0; --k) value = c[k] + t * value;
      worst_far = std::max(worst_far, std::abs(value - PhiNormal(centre + t)));
    }
  }
  EXPECT_LT(worst_far, 1e-15);
}

// A trail dash (or a point image when the segment is 0) mapped by an affine,
// slightly or strongly non-orthogonal px_from_um.
SceneMark Trail(double skew, double segment_u_um, double fwhm_um) {
  SceneMark mark;
  mark.id = "KS1-T1-L1";
  mark.kind = segment_u_um > 0.0 ? MarkKind::kTrailDash : MarkKind::kStar;
  mark.shape = segment_u_um > 0.0 ? MarkShapeKind::kSegment : MarkShapeKind::kPsf;
  mark.centre_px = {40.31, 41.77};
  mark.psf_fwhm_um = fwhm_um;
  mark.segment_u_um = segment_u_um;
  mark.segment_v_um = 0.27 * segment_u_um;
  mark.amplitude_dn = 1e5;
  const double a = 0.23, s = 0.2;
  mark.px_from_um[0] = s * std::cos(a), mark.px_from_um[1] = -s * std::sin(a) + skew;
  mark.px_from_um[2] = -s * std::sin(a), mark.px_from_um[3] = -s * std::cos(a);
  return mark;
}

// The swept density at offset (x, y) px from the centre, from its definition:
// a Gaussian of covariance C moved uniformly along the segment +-half (px).
double SweptDensity(const double c[3], const double half[2], double x, double y) {
  const double det = c[0] * c[2] - c[1] * c[1];
  const double p0 = c[2] / det, p1 = -c[1] / det, p2 = c[0] / det;
  const double norm = 1.0 / (2.0 * M_PI * std::sqrt(det));
  const double q = p0 * x * x + 2 * p1 * x * y + p2 * y * y;
  const double length = 2.0 * std::hypot(half[0], half[1]);
  if (length == 0.0) return norm * std::exp(-0.5 * q);
  const double e0 = 2.0 * half[0] / length, e1 = 2.0 * half[1] / length;
  const double a = e0 * (p0 * e0 + p1 * e1) + e1 * (p1 * e0 + p2 * e1);
  const double b = e0 * (p0 * x + p1 * y) + e1 * (p1 * x + p2 * y);
  // int over t in [-L/2, L/2] of exp(-(a t^2 - 2 b t + q) / 2) dt / L.
  const double sa = std::sqrt(a), t0 = b / a;
  return norm * std::exp(-0.5 * (q - b * b / a)) * std::sqrt(2.0 * M_PI / a) / length *
         (PhiNormal(sa * (0.5 * length - t0)) - PhiNormal(sa * (-0.5 * length - t0)));
}

// Pixel mean of the mark (DN) by a fine Gauss-Legendre rule (cells of 0.7 sigma, 12 nodes).
double BruteForcePixel(const SceneMark& mark, double blur_px, long x_px, long y_px) {
  const double s_um = mark.psf_fwhm_um / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  const double* j = mark.px_from_um;
  const double c[3] = {s_um * s_um * (j[0] * j[0] + j[1] * j[1]) + blur_px * blur_px,
                       s_um * s_um * (j[0] * j[2] + j[1] * j[3]),
                       s_um * s_um * (j[2] * j[2] + j[3] * j[3]) + blur_px * blur_px};
  const double half[2] = {0.5 * (j[0] * mark.segment_u_um + j[1] * mark.segment_v_um),
                          0.5 * (j[2] * mark.segment_u_um + j[3] * mark.segment_v_um)};
  const double lambda_min = 0.5 * (c[0] + c[2]) - std::hypot(0.5 * (c[0] - c[2]), c[1]);
  const int cells = static_cast<int>(std::ceil(1.0 / (0.7 * std::sqrt(lambda_min))));
  const auto& rule = render_detail::GaussLegendre(12);
  std::vector<double> offsets, weights;
  for (int cell = 0; cell < cells; ++cell)
    for (size_t k = 0; k < rule.nodes.size(); ++k) {
      offsets.push_back(-0.5 + (cell + 0.5 + 0.5 * rule.nodes[k]) / cells);
      weights.push_back(0.5 * rule.weights[k] / cells);
    }
  const double dx = x_px - mark.centre_px.x_px, dy = y_px - mark.centre_px.y_px;
  double sum = 0.0;
  for (size_t b = 0; b < offsets.size(); ++b)
    for (size_t a = 0; a < offsets.size(); ++a)
      sum += weights[a] * weights[b] * SweptDensity(c, half, dx + offsets[a], dy + offsets[b]);
  return mark.amplitude_dn * sum;
}

// Swept and anisotropic point images through the split form, including a
// Gaussian so narrow that the split factors would overflow far from it (the
// node-by-node fallback): within 1e-7 DN of a 1e5 flux of the brute force.
TEST(RenderFastPaths, SplitQuadratureMatchesTheSweptDensity) {
  struct Case {
    double skew, segment_u_um, fwhm_um, blur_px;
  };
  const Case cases[] = {{4e-6, 150.0, 8.0, 0.15}, {4e-6, 150.0, 8.0, 0.6},  {0.02, 150.0, 8.0, 2.0},
                        {0.02, 20.0, 8.0, 0.3},   {0.02, 0.0, 8.0, 0.3},    {4e-6, 30.0, 0.5, 0.02}};
  for (const Case& k : cases) {
    const SceneMark mark = Trail(k.skew, k.segment_u_um, k.fwhm_um);
    const MarkModel model(mark, k.blur_px);
    const PixelRect& s = model.support();
    double worst = 0.0, total = 0.0;
    for (long y = s.y0_px; y < s.y_end_px(); ++y)
      for (long x = s.x0_px; x < s.x_end_px(); ++x) {
        const double value = model.PixelValue(x, y);
        worst = std::max(worst, std::abs(value - BruteForcePixel(mark, k.blur_px, x, y)));
        total += value;
      }
    EXPECT_LT(worst, 1e-7) << "skew " << k.skew << " segment " << k.segment_u_um << " blur " << k.blur_px;
    EXPECT_NEAR(total / mark.amplitude_dn, 1.0, 1e-9);
  }
}

// PixelValuesShifted gives the five PixelValueWithCentre numbers for every
// kind of part, with shifts small enough to share the CDF table and large
// enough not to.
TEST(RenderFastPaths, ShiftedValuesEqualFiveSingleCalls) {
  std::vector<SceneMark> marks = {Trail(4e-6, 150.0, 8.0), Trail(0.02, 20.0, 8.0), Trail(0.02, 0.0, 8.0),
                                  Trail(4e-6, 30.0, 0.5)};
  SceneMark cross = Trail(1e-4, 0.0, 8.0);
  cross.kind = MarkKind::kReseauCross, cross.shape = MarkShapeKind::kCross;
  cross.size_um = 200.0, cross.line_width_um = 20.0, cross.amplitude_dn = -1000.0;
  marks.push_back(cross);
  SceneMark ring = cross;
  ring.kind = MarkKind::kFiducial, ring.shape = MarkShapeKind::kRing, ring.size_um = 120.0;
  marks.push_back(ring);
  for (const SceneMark& mark : marks)
    for (double blur : {0.05, 0.6})
      for (double step : {0.005, 0.3}) {
        const MarkModel model(mark, blur);
        const PixelPoint c = mark.centre_px;
        const PixelPoint centres[5] = {c, {c.x_px + step, c.y_px}, {c.x_px - step, c.y_px},
                                       {c.x_px, c.y_px + step}, {c.x_px, c.y_px - step}};
        const PixelRect& s = model.support();
        double worst = 0.0;
        for (long y = s.y0_px - 1; y <= s.y_end_px(); ++y)
          for (long x = s.x0_px - 1; x <= s.x_end_px(); ++x) {
            double values[5];
            model.PixelValuesShifted(step, x, y, values);
            for (int k = 0; k < 5; ++k)
              worst = std::max(worst, std::abs(values[k] - model.PixelValueWithCentre(centres[k], x, y)));
          }
        EXPECT_LT(worst, 1e-12 * std::abs(mark.amplitude_dn))
            << mark.id << " shape " << static_cast<int>(mark.shape) << " blur " << blur << " step " << step;
      }
}

// The bound from the Fisher sum over the whole window, every pixel evaluated
// at the five centres (what CramerRaoBound did before it skipped the pixels
// outside the support and shared the five evaluations).
TEST(RenderFastPaths, CramerRaoBoundEqualsTheFullFisherSum) {
  SceneNoise noise;
  noise.sensor_sigma_dn = 100.0;
  noise.grain_sigma_dn = 300.0;
  const CramerRaoOptions options;
  for (const SceneMark& mark : {Trail(4e-6, 150.0, 30.0), Trail(0.02, 20.0, 8.0), Trail(1e-4, 0.0, 8.0)}) {
    const double blur = 0.2;
    const MarkModel model(mark, blur);
    const PixelRect& s = model.support();
    const PixelRect window{s.x0_px - 4, s.y0_px - 4, s.width_px + 8, s.height_px + 8};
    const double h = options.step_px;
    const PixelPoint c = mark.centre_px;
    Eigen::Matrix4d fisher = Eigen::Matrix4d::Zero();
    for (long y = window.y0_px; y < window.y_end_px(); ++y)
      for (long x = window.x0_px; x < window.x_end_px(); ++x) {
        Eigen::Vector4d j;
        j[0] = (model.PixelValueWithCentre({c.x_px + h, c.y_px}, x, y) -
                model.PixelValueWithCentre({c.x_px - h, c.y_px}, x, y)) / (2 * h);
        j[1] = (model.PixelValueWithCentre({c.x_px, c.y_px + h}, x, y) -
                model.PixelValueWithCentre({c.x_px, c.y_px - h}, x, y)) / (2 * h);
        j[2] = model.PixelValue(x, y) / mark.amplitude_dn;
        j[3] = 1.0;
        fisher += j * j.transpose();
      }
    const Eigen::Matrix4d covariance = (fisher / PixelNoiseVariance(noise)).inverse();
    const MarkCramerRao crb = CramerRaoBound(model, noise, window, options);
    ASSERT_TRUE(crb.valid);
    EXPECT_NEAR(crb.sigma_x_px / std::sqrt(covariance(0, 0)), 1.0, 1e-9);
    EXPECT_NEAR(crb.sigma_y_px / std::sqrt(covariance(1, 1)), 1.0, 1e-9);
    EXPECT_NEAR(crb.correlation_xy,
                covariance(0, 1) / std::sqrt(covariance(0, 0) * covariance(1, 1)), 1e-9);
    EXPECT_EQ(crb.window_pixels, window.width_px * window.height_px);
  }
}

}  // namespace
}  // namespace platemeter::sim
