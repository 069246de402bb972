// The cross fit against crosses rendered independently in the test.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <vector>

#include "platemeter/detect/cross_fit.h"

namespace platemeter {
namespace {

struct TrueCross {
  double x_px, y_px, rotation_rad, width_px, length_px, blur_px, gain_dn, background_dn;
};

// Point value of the blurred cross: a blurred rectangle is the product of its
// two erf-difference profiles (in the rectangle's own axes), and the cross is
// bar + bar - centre square. The pixel average is then taken numerically with
// an 8 x 8 Gauss-Legendre rule over the pixel's own square, in pixel axes, so
// the test does not share the fit's closed-form, cross-aligned pixel average.
double ErfBar(double t, double width, double sigma) {
  const double k = std::sqrt(2.0) * sigma;
  return 0.5 * (std::erf((t + width / 2) / k) - std::erf((t - width / 2) / k));
}

// A stretch of an arm without its line: arm 0 along +u, 1 +v, 2 -u, 3 -v; from..to px from the centre.
struct ArmGap {
  int arm;
  double from_px, to_px;
};

ImageWindow RenderBruteForce(const TrueCross& cross, PixelRect rect, const std::vector<ArmGap>& gaps = {}) {
  static const double kNodes[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                   0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
  static const double kWeights[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                     0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  const double c = std::cos(cross.rotation_rad), s = std::sin(cross.rotation_rad);
  ImageWindow window;
  window.rect = rect;
  window.values_dn.resize(static_cast<size_t>(rect.width_px * rect.height_px));
  for (long row = 0; row < rect.height_px; ++row)
    for (long col = 0; col < rect.width_px; ++col) {
      double sum = 0;
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
          const double x = rect.x0_px + col + 0.5 * kNodes[i], y = rect.y0_px + row + 0.5 * kNodes[j];
          const double u = c * (x - cross.x_px) + s * (y - cross.y_px);
          const double v = -s * (x - cross.x_px) + c * (y - cross.y_px);
          const double across_u = ErfBar(v, cross.width_px, cross.blur_px), along_u = ErfBar(u, cross.length_px, cross.blur_px);
          const double across_v = ErfBar(u, cross.width_px, cross.blur_px), along_v = ErfBar(v, cross.length_px, cross.blur_px);
          double value = across_u * along_u + across_v * along_v - across_u * across_v;
          for (const ArmGap& g : gaps) {
            const double side = g.arm < 2 ? 1.0 : -1.0, middle = side * 0.5 * (g.from_px + g.to_px);
            value -= g.arm % 2 == 0 ? across_u * ErfBar(u - middle, g.to_px - g.from_px, cross.blur_px)
                                    : across_v * ErfBar(v - middle, g.to_px - g.from_px, cross.blur_px);
          }
          sum += 0.25 * kWeights[i] * kWeights[j] * value;
        }
      window.values_dn[static_cast<size_t>(row * rect.width_px + col)] =
          static_cast<float>(cross.background_dn + cross.gain_dn * sum);
    }
  return window;
}

CrossFitStart StartNear(const TrueCross& cross, double dx, double dy) {
  CrossFitStart start;
  start.centre_px = {cross.x_px + dx, cross.y_px + dy};
  start.line_width_px = cross.width_px * 1.2;
  start.arm_length_px = cross.length_px * 0.95;
  start.blur_sigma_px = 0.8;
  return start;
}

class CrossFitRotation : public ::testing::TestWithParam<double> {};

// The fit averages each pixel over a square aligned with the cross, not with the
// pixel grid; the claim is that this leaves the centre unbiased at any rotation.
TEST_P(CrossFitRotation, NoiseFreeCrossesAtSubPixelOffsets) {
  const double rotation_rad = GetParam();
  double sum_dx = 0, sum_dy = 0;
  int count = 0;
  for (double ox : {-0.4, -0.13, 0.0, 0.27, 0.5}) {
    for (double oy : {-0.31, 0.08, 0.45}) {
      const TrueCross cross{30.0 + ox, 31.0 + oy, rotation_rad, 3.0, 40.0, 0.6, -800.0, 2000.0};
      const CrossFitStart start = StartNear(cross, 0.6, -0.5);
      const ImageWindow window = RenderBruteForce(cross, CrossFitWindow(start));
      const CrossFitResult fit = FitCross(window, start);
      ASSERT_TRUE(fit.converged) << fit.summary;
      EXPECT_NEAR(fit.centre_px.x_px, cross.x_px, 0.001) << ox << "," << oy;
      EXPECT_NEAR(fit.centre_px.y_px, cross.y_px, 0.001) << ox << "," << oy;
      EXPECT_NEAR(fit.gain_dn, cross.gain_dn, 0.03 * std::abs(cross.gain_dn));
      sum_dx += fit.centre_px.x_px - cross.x_px;
      sum_dy += fit.centre_px.y_px - cross.y_px;
      ++count;
    }
  }
  EXPECT_LT(std::abs(sum_dx / count), 0.001);
  EXPECT_LT(std::abs(sum_dy / count), 0.001);
}

INSTANTIATE_TEST_SUITE_P(Rotations, CrossFitRotation, ::testing::Values(0.0, 0.004, -0.05));

TEST(CrossFit, FormalSigmaMatchesScatterUnderNoise) {
  const TrueCross cross{40.2, 39.7, -0.01, 4.0, 60.0, 0.8, 600.0, 1000.0};
  const CrossFitStart start = StartNear(cross, -0.7, 0.4);
  const ImageWindow clean = RenderBruteForce(cross, CrossFitWindow(start));
  std::mt19937 random(3);
  std::normal_distribution<float> noise(0.0f, 40.0f);
  std::vector<double> errors_x, errors_y, sigmas;
  for (int trial = 0; trial < 60; ++trial) {
    ImageWindow noisy = clean;
    for (float& v : noisy.values_dn) v += noise(random);
    const CrossFitResult fit = FitCross(noisy, start);
    ASSERT_TRUE(fit.converged) << fit.summary;
    errors_x.push_back(fit.centre_px.x_px - cross.x_px);
    errors_y.push_back(fit.centre_px.y_px - cross.y_px);
    sigmas.push_back(fit.sigma_x_px);
    EXPECT_NEAR(fit.residual_sigma_dn, 40.0, 4.0);
  }
  double rms_x = 0, rms_y = 0, mean_sigma = 0;
  for (size_t i = 0; i < errors_x.size(); ++i) {
    rms_x += errors_x[i] * errors_x[i];
    rms_y += errors_y[i] * errors_y[i];
    mean_sigma += sigmas[i];
  }
  rms_x = std::sqrt(rms_x / errors_x.size());
  rms_y = std::sqrt(rms_y / errors_y.size());
  mean_sigma /= sigmas.size();
  // 60 trials: the RMS itself scatters by about 1/sqrt(120) ~ 9 %.
  EXPECT_NEAR(rms_x / mean_sigma, 1.0, 0.3) << rms_x << " vs " << mean_sigma;
  EXPECT_NEAR(rms_y / mean_sigma, 1.0, 0.3) << rms_y << " vs " << mean_sigma;
}

// The matched-filter SNR of a rendered cross, derived here independently of the
// fit: the template's norm over the window after projecting out a plane
// background (what a least-squares gain with the place and shape known sees),
// times |gain| / noise sigma.
double TrueMatchedFilterSnr(const TrueCross& cross, PixelRect rect, double noise_sigma_dn) {
  TrueCross unit = cross;
  unit.gain_dn = 1.0;
  unit.background_dn = 0.0;
  const ImageWindow t = RenderBruteForce(unit, rect);
  const long n = rect.width_px * rect.height_px;
  Eigen::MatrixXd plane(n, 3);
  Eigen::VectorXd templ(n);
  for (long i = 0; i < n; ++i) {
    plane.row(i) << 1.0, static_cast<double>(i % rect.width_px), static_cast<double>(i / rect.width_px);
    templ[i] = t.values_dn[static_cast<size_t>(i)];
  }
  const Eigen::VectorXd residual = templ - plane * plane.colPivHouseholderQr().solve(templ);
  return std::abs(cross.gain_dn) * residual.norm() / noise_sigma_dn;
}

// Pure noise at a predicted place: the fit, free to move and reshape, finds
// some "cross" in it; its matched-filter SNR is what a missing cross looks
// like, and must stay below the reseau detector's threshold (8).
TEST(CrossFit, MatchedFilterSnrOfNoiseStaysBelowTheThreshold) {
  const TrueCross flat{40.2, 39.7, 0.006, 3.0, 50.0, 0.8, 0.0, 1000.0};
  const CrossFitStart start = StartNear(flat, -0.7, 0.4);
  const ImageWindow background = RenderBruteForce(flat, CrossFitWindow(start));
  std::mt19937 random(11);
  std::normal_distribution<float> noise(0.0f, 10.0f);
  double max_snr = 0.0;
  int fitted = 0;
  for (int trial = 0; trial < 50; ++trial) {
    ImageWindow noisy = background;
    for (float& v : noisy.values_dn) v += noise(random);
    const CrossFitResult fit = FitCross(noisy, start);
    if (!fit.converged) continue;
    ++fitted;
    max_snr = std::max(max_snr, std::abs(fit.gain_dn) / fit.gain_sigma_dn);
  }
  EXPECT_GT(fitted, 40);
  EXPECT_LT(max_snr, 8.0);
  EXPECT_GT(max_snr, 2.0);  // the fit does chase the noise: the test is not vacuous
}

// A faint cross (contrast 1.2 noise sigmas) of known matched-filter SNR: the fit
// gets that SNR back, and with the shape known (as the reseau detector holds the
// plate's for crosses below an SNR of 30) its formal sigma states the scatter of
// its centre.
TEST(CrossFit, FaintCrossSnrAndSigmaWithTheShapeKnown) {
  const TrueCross faint{40.2, 39.7, 0.006, 3.0, 50.0, 0.8, 12.0, 1000.0};
  const CrossFitStart start = StartNear(faint, -0.7, 0.4);
  const PixelRect rect = CrossFitWindow(start);
  const double noise_sigma_dn = 10.0;
  const double true_snr = TrueMatchedFilterSnr(faint, rect, noise_sigma_dn);
  EXPECT_GT(true_snr, 12.0);  // faint per pixel, above the threshold as a whole
  CrossFitStart known = start;
  known.line_width_px = faint.width_px;
  known.arm_length_px = faint.length_px;
  known.blur_sigma_px = faint.blur_px;
  known.shape_known = true;
  const ImageWindow clean = RenderBruteForce(faint, rect);
  std::mt19937 random(5);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(noise_sigma_dn));
  double snr_sum = 0.0, squared_error = 0.0, squared_sigma = 0.0;
  const int trials = 60;
  for (int trial = 0; trial < trials; ++trial) {
    ImageWindow noisy = clean;
    for (float& v : noisy.values_dn) v += noise(random);
    const CrossFitResult free_fit = FitCross(noisy, start);
    ASSERT_TRUE(free_fit.converged) << free_fit.summary;
    snr_sum += std::abs(free_fit.gain_dn) / free_fit.gain_sigma_dn;
    const CrossFitResult fit = FitCross(noisy, known);
    ASSERT_TRUE(fit.converged) << fit.summary;
    EXPECT_EQ(fit.width_h_px, faint.width_px);  // held
    squared_error += std::pow(fit.centre_px.x_px - faint.x_px, 2) + std::pow(fit.centre_px.y_px - faint.y_px, 2);
    squared_sigma += fit.sigma_x_px * fit.sigma_x_px + fit.sigma_y_px * fit.sigma_y_px;
  }
  EXPECT_NEAR(snr_sum / trials, true_snr, 0.1 * true_snr);
  // 60 trials, both axes: the RMS scatters by about 9 %.
  EXPECT_NEAR(std::sqrt(squared_error / squared_sigma), 1.0, 0.2) << std::sqrt(squared_error / squared_sigma);
}

// Star images on a cross's arms (bright, on a dark cross), drawn out along x by
// the star's motion as on a trailed plate, one of them clipped at the scan's
// full scale: they are fitted with the cross (elliptical Gaussians, which the
// drawn-out images are not exactly), the centre is measured with a sigma that
// states its scatter, and the fit keeps more of the cross's information than
// leaving the stars' pixels out does.
TEST(CrossFit, StarImagesOnTheArmsAreFittedWithTheCross) {
  const TrueCross cross{40.2, 39.7, 0.004, 3.0, 50.0, 0.8, -600.0, 1000.0};
  CrossFitStart start = StartNear(cross, 0.5, -0.6);
  start.polarity = -1;
  start.full_scale_dn = 4000.0;
  const ImageWindow clean = RenderBruteForce(cross, CrossFitWindow(start));
  struct Star {
    double x_px, y_px, peak_dn;
  };
  // Two on the +u arm (the second's core clipped), one on the -v arm, one beside the +v arm.
  const std::vector<Star> stars = {{52.0, 40.5, 2500.0}, {58.5, 39.0, 9000.0}, {40.0, 25.0, 2500.0}, {43.5, 55.0, 1500.0}};
  auto add_stars = [&](ImageWindow* w) {
    constexpr int kSteps = 11;        // a uniform sweep of 2.5 px along x, sigma 1.0 px
    for (long row = 0; row < w->rect.height_px; ++row)
      for (long col = 0; col < w->rect.width_px; ++col) {
        float& value = w->values_dn[static_cast<size_t>(row * w->rect.width_px + col)];
        for (const Star& star : stars)
          for (int k = 0; k < kSteps; ++k) {
            const double dx = w->rect.x0_px + col - (star.x_px + 2.5 * (k / (kSteps - 1.0) - 0.5));
            const double dy = w->rect.y0_px + row - star.y_px;
            value += static_cast<float>(star.peak_dn / kSteps * std::exp(-0.5 * (dx * dx + dy * dy)));
          }
      }
  };
  std::mt19937 random(17);
  std::normal_distribution<float> noise(0.0f, 40.0f);
  double squared_z = 0.0, information = 0.0, information_dropped = 0.0;
  int clipped = 0;
  const int trials = 30;
  CrossFitOptions drop_only;
  drop_only.max_foreign_images = 0;
  for (int trial = 0; trial < trials; ++trial) {
    ImageWindow noisy = clean;
    add_stars(&noisy);
    for (float& v : noisy.values_dn) {
      v += noise(random);
      clipped += v >= 4000.0f;
      v = std::min(v, 4000.0f);
    }
    const CrossFitResult fit = FitCross(noisy, start);
    ASSERT_TRUE(fit.converged) << fit.summary;
    EXPECT_GE(fit.foreign_images, 3) << fit.summary;
    squared_z += std::pow((fit.centre_px.x_px - cross.x_px) / fit.sigma_x_px, 2) +
                 std::pow((fit.centre_px.y_px - cross.y_px) / fit.sigma_y_px, 2);
    information += fit.information_kept;
    information_dropped += FitCross(noisy, start, drop_only).information_kept;
  }
  ASSERT_GT(clipped, 2 * trials);  // the bright star's core is clipped in every trial
  // 30 trials, both axes: the RMS scatters by about 9 %.
  EXPECT_NEAR(std::sqrt(squared_z / (2 * trials)), 1.0, 0.25);
  // Leaving the stars' pixels and margins out costs about half the information;
  // fitting the stars costs only what their own parameters take.
  EXPECT_LT(information_dropped / trials, 0.7);
  EXPECT_GT(information / trials, information_dropped / trials + 0.15);
}

// A damaged cross (as bench_reseau's: each arm without its line over a stretch,
// 31 % of the arms' length in all; one gap reaches the tip, one the centre) is
// measured, not called a defect, with an honest sigma (Monte Carlo over the
// noise). Here the foreign images fitted into its gaps keep enough of it; where
// they do not, the missing pieces are fitted (ReseauDetector.DamagedCrosses...).
TEST(CrossFit, ADamagedCrossIsMeasuredWithAnHonestSigma) {
  const TrueCross cross{40.2, 39.7, 0.004, 3.0, 50.0, 0.8, -600.0, 1000.0};
  const std::vector<ArmGap> gaps = {{0, 5.0, 14.0}, {1, 18.0, 25.5}, {2, 1.5, 8.5}, {3, 10.0, 16.0}};
  const CrossFitStart start = StartNear(cross, 0.5, -0.6);
  const ImageWindow clean = RenderBruteForce(cross, CrossFitWindow(start), gaps);
  std::mt19937 random(23);
  std::normal_distribution<float> noise(0.0f, 40.0f);
  double squared_z = 0.0, information = 0.0;
  const int trials = 30;
  for (int trial = 0; trial < trials; ++trial) {
    ImageWindow noisy = clean;
    for (float& v : noisy.values_dn) v += noise(random);
    const CrossFitResult fit = FitCross(noisy, start);
    ASSERT_TRUE(fit.converged) << fit.summary;
    EXPECT_GE(fit.information_kept, CrossFitOptions{}.min_information_kept) << fit.summary;
    squared_z += std::pow((fit.centre_px.x_px - cross.x_px) / fit.sigma_x_px, 2) +
                 std::pow((fit.centre_px.y_px - cross.y_px) / fit.sigma_y_px, 2);
    information += fit.information_kept;
  }
  // 30 trials, both axes: the RMS scatters by about 9 %.
  EXPECT_NEAR(std::sqrt(squared_z / (2 * trials)), 1.0, 0.25);
  std::printf("damaged cross: RMS(error / sigma) %.3f, information kept %.2f\n", std::sqrt(squared_z / (2 * trials)),
              information / trials);
}

}  // namespace
}  // namespace platemeter
