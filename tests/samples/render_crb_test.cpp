// The Cramer-Rao bound against independent truth: the Fisher information of a
// pixel-integrated Gaussian star written here from its analytic derivatives,
// the continuous large-sample formula, and a Monte Carlo of least-squares fits
// to noisy renders of a cross.
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "platemeter/samples/render.h"
#include "platemeter/samples/render_crb.h"

namespace platemeter::sim {
namespace {

double Phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
double phi(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2.0 * M_PI); }

TEST(RenderCrb, GaussianStarMatchesAnalyticFisherAndLargeSampleFormula) {
  const double sigma = 2.0;         // px, PSF on the scan (no scanner blur)
  const double flux = 100000.0;     // DN px^2
  const double noise_sigma = 5.0;   // DN
  Scene scene;
  scene.width_px = 100;
  scene.height_px = 100;
  scene.noise.sensor_sigma_dn = noise_sigma;
  scene.noise.quantize = false;
  SceneMark star;
  star.kind = MarkKind::kStar;
  star.shape = MarkShapeKind::kPsf;
  star.centre_px = {50.3, 49.8};
  star.psf_fwhm_um = sigma / 0.2 * 2.0 * std::sqrt(2.0 * std::log(2.0));  // 0.2 px/um
  star.amplitude_dn = flux;
  scene.marks.push_back(star);
  const MarkCramerRao crb = CramerRaoBound(scene, star);
  ASSERT_TRUE(crb.valid);

  // Independent Fisher matrix: m = b + F Ix(cx) Iy(cy), derivatives in closed form.
  Eigen::Matrix4d fisher = Eigen::Matrix4d::Zero();
  const double cx = star.centre_px.x_px, cy = star.centre_px.y_px;
  for (long y = 25; y <= 75; ++y)
    for (long x = 25; x <= 75; ++x) {
      const double ix = Phi((x + 0.5 - cx) / sigma) - Phi((x - 0.5 - cx) / sigma);
      const double iy = Phi((y + 0.5 - cy) / sigma) - Phi((y - 0.5 - cy) / sigma);
      const double dix = -(phi((x + 0.5 - cx) / sigma) - phi((x - 0.5 - cx) / sigma)) / sigma;
      const double diy = -(phi((y + 0.5 - cy) / sigma) - phi((y - 0.5 - cy) / sigma)) / sigma;
      const Eigen::Vector4d j(flux * dix * iy, flux * ix * diy, ix * iy, 1.0);
      fisher += j * j.transpose() / (noise_sigma * noise_sigma);
    }
  const Eigen::Matrix4d covariance = fisher.inverse();
  EXPECT_NEAR(crb.sigma_x_px / std::sqrt(covariance(0, 0)), 1.0, 0.003);
  EXPECT_NEAR(crb.sigma_y_px / std::sqrt(covariance(1, 1)), 1.0, 0.003);
  EXPECT_NEAR(crb.sigma_amplitude_dn / std::sqrt(covariance(2, 2)), 1.0, 0.003);
  EXPECT_NEAR(crb.correlation_xy, 0.0, 0.01);

  // Large-sample limit: F_xx = flux^2 / noise^2 * int (dG/dx)^2 = flux^2 / (8 pi s^4 noise^2) for a unit
  // Gaussian of sigma s; a pixel's box adds 1/12 px^2 of variance: s^2 = sigma^2 + 1/12.
  const double s2 = sigma * sigma + 1.0 / 12.0;
  const double analytic = std::sqrt(8.0 * M_PI) * s2 * noise_sigma / flux;
  EXPECT_NEAR(crb.sigma_x_px / analytic, 1.0, 0.02);
  EXPECT_NEAR(crb.sigma_y_px / analytic, 1.0, 0.02);
}

// An axis-aligned blurred cross has a closed-form pixel model (products of
// integrals of Phi); its Fisher matrix from analytic derivatives must give the
// renderer's bound.
TEST(RenderCrb, AxisAlignedCrossMatchesAnalyticFisher) {
  const double blur = 0.7, half_long = 20.0, half_thin = 2.0;  // px
  auto f = [&](double t, double a) { return Phi((t + a) / blur) - Phi((t - a) / blur); };
  auto psi = [](double z) { return z * Phi(z) + phi(z); };
  // Mean over pixel x of f(t - c; a) and its derivative in c.
  auto box = [&](long x, double c, double a) {
    return blur * (psi((x + 0.5 - c + a) / blur) - psi((x - 0.5 - c + a) / blur) -
                   psi((x + 0.5 - c - a) / blur) + psi((x - 0.5 - c - a) / blur));
  };
  auto dbox = [&](long x, double c, double a) { return -(f(x + 0.5 - c, a) - f(x - 0.5 - c, a)); };
  Scene scene;
  scene.width_px = 80;
  scene.height_px = 80;
  scene.noise.scanner_blur_sigma_px = blur;
  scene.noise.sensor_sigma_dn = 10.0;
  scene.noise.quantize = true;
  SceneMark cross;
  cross.centre_px = {40.3, 39.6};
  cross.size_um = 200.0;  // 40 px at 0.2 px/um
  cross.line_width_um = 20.0;
  cross.amplitude_dn = -500.0;
  scene.marks.push_back(cross);
  const MarkCramerRao crb = CramerRaoBound(scene, cross);
  ASSERT_TRUE(crb.valid);
  const double cx = cross.centre_px.x_px, cy = cross.centre_px.y_px, amp = cross.amplitude_dn;
  Eigen::Matrix4d fisher = Eigen::Matrix4d::Zero();
  for (long y = 0; y < 80; ++y)
    for (long x = 0; x < 80; ++x) {
      const double xl = box(x, cx, half_long), xt = box(x, cx, half_thin);
      const double yl = box(y, cy, half_long), yt = box(y, cy, half_thin);
      const double dxl = dbox(x, cx, half_long), dxt = dbox(x, cx, half_thin);
      const double dyl = dbox(y, cy, half_long), dyt = dbox(y, cy, half_thin);
      const double g = xl * yt + xt * yl - xt * yt;
      const Eigen::Vector4d j(amp * (dxl * yt + dxt * yl - dxt * yt), amp * (xl * dyt + xt * dyl - xt * dyt), g, 1.0);
      fisher += j * j.transpose() / (100.0 + 1.0 / 12.0);
    }
  const Eigen::Matrix4d covariance = fisher.inverse();
  EXPECT_NEAR(crb.sigma_x_px / std::sqrt(covariance(0, 0)), 1.0, 0.005);
  EXPECT_NEAR(crb.sigma_y_px / std::sqrt(covariance(1, 1)), 1.0, 0.005);
  EXPECT_NEAR(crb.correlation_xy, covariance(0, 1) / std::sqrt(covariance(0, 0) * covariance(1, 1)), 0.01);
}

TEST(RenderCrb, MonteCarloFitsOfNoisyCrossesScatterAsTheBoundSays) {
  Scene scene;
  scene.width_px = 64;
  scene.height_px = 64;
  scene.background.level_dn = 3000.0;
  scene.noise.scanner_blur_sigma_px = 0.7;
  scene.noise.sensor_sigma_dn = 6.0;
  scene.noise.grain_sigma_dn = 4.0;
  scene.noise.quantize = true;
  SceneMark cross;
  cross.id = "X2Y3";
  cross.centre_px = {31.3, 32.6};
  cross.size_um = 100.0;
  cross.line_width_um = 20.0;
  cross.amplitude_dn = -400.0;
  const double a = 0.05;  // a slightly rotated scanner
  cross.px_from_um[0] = 0.2 * std::cos(a), cross.px_from_um[1] = 0.2 * std::sin(a);
  cross.px_from_um[2] = 0.2 * std::sin(a), cross.px_from_um[3] = -0.2 * std::cos(a);
  scene.marks.push_back(cross);
  const MarkCramerRao crb = CramerRaoBound(scene, cross);
  ASSERT_TRUE(crb.valid);

  const MarkModel model(cross, scene.noise.scanner_blur_sigma_px);
  const PixelRect w = {model.support().x0_px - 4, model.support().y0_px - 4,
                       model.support().width_px + 8, model.support().height_px + 8};
  ASSERT_GE(w.x0_px, 0);
  ASSERT_LE(w.x_end_px(), scene.width_px);
  // Parameters (x, y, amplitude, background); model b + amplitude / a0 * g(centre).
  auto evaluate = [&](const Eigen::Vector4d& p) {
    Eigen::VectorXd m(w.width_px * w.height_px);
    const auto g = MarkModelWindow(model, w, {p[0], p[1]});
    for (long i = 0; i < m.size(); ++i) m[i] = p[3] + p[2] / cross.amplitude_dn * g[i];
    return m;
  };
  const Eigen::Vector4d truth(cross.centre_px.x_px, cross.centre_px.y_px, cross.amplitude_dn, 3000.0);
  // Jacobian at the truth by central differences (Gauss-Newton with it is the
  // linearised least-squares estimator, efficient to first order).
  Eigen::MatrixXd jac(w.width_px * w.height_px, 4);
  const double steps[4] = {0.01, 0.01, 1.0, 1.0};
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector4d hi = truth, lo = truth;
    hi[k] += steps[k], lo[k] -= steps[k];
    jac.col(k) = (evaluate(hi) - evaluate(lo)) / (2 * steps[k]);
  }
  const Eigen::MatrixXd solve = (jac.transpose() * jac).ldlt().solve(jac.transpose());

  constexpr int kTrials = 200;
  std::vector<double> xs, ys;
  std::vector<float> image(scene.width_px * scene.height_px);
  for (int trial = 0; trial < kTrials; ++trial) {
    Scene noisy = scene;
    noisy.noise.seed = 1000 + trial;
    RenderBand(noisy, 0, scene.height_px, image.data());
    Eigen::VectorXd data(w.width_px * w.height_px);
    for (long r = 0; r < w.height_px; ++r)
      for (long c = 0; c < w.width_px; ++c)
        data[r * w.width_px + c] = image[(w.y0_px + r) * scene.width_px + w.x0_px + c];
    Eigen::Vector4d p = truth + Eigen::Vector4d(0.05, -0.04, 10.0, 2.0);  // start off the truth
    for (int iteration = 0; iteration < 4; ++iteration) p += solve * (data - evaluate(p));
    xs.push_back(p[0] - truth[0]);
    ys.push_back(p[1] - truth[1]);
  }
  auto stats = [](const std::vector<double>& v, double* mean, double* sd) {
    double s = 0, s2 = 0;
    for (double x : v) s += x, s2 += x * x;
    *mean = s / v.size();
    *sd = std::sqrt((s2 - s * s / v.size()) / (v.size() - 1));
  };
  double mean_x, sd_x, mean_y, sd_y;
  stats(xs, &mean_x, &sd_x);
  stats(ys, &mean_y, &sd_y);
  RecordProperty("crb_sigma_x_px", std::to_string(crb.sigma_x_px));
  RecordProperty("mc_sd_x_px", std::to_string(sd_x));
  EXPECT_NEAR(sd_x / crb.sigma_x_px, 1.0, 0.15) << sd_x << " vs " << crb.sigma_x_px;
  EXPECT_NEAR(sd_y / crb.sigma_y_px, 1.0, 0.15) << sd_y << " vs " << crb.sigma_y_px;
  // Unbiased: the mean error is within 4 standard errors.
  EXPECT_LT(std::abs(mean_x), 4 * crb.sigma_x_px / std::sqrt(kTrials));
  EXPECT_LT(std::abs(mean_y), 4 * crb.sigma_y_px / std::sqrt(kTrials));
}

TEST(RenderCrb, NoInformationGivesInvalid) {
  Scene scene;
  scene.width_px = 64;
  scene.height_px = 64;
  scene.noise.sensor_sigma_dn = 3.0;
  SceneMark cross;
  cross.centre_px = {30, 30};
  cross.size_um = 100;
  cross.amplitude_dn = 0.0;
  EXPECT_FALSE(CramerRaoBound(scene, cross).valid);
  cross.amplitude_dn = -500;
  cross.centre_px = {-500, -500};  // outside the image
  EXPECT_FALSE(CramerRaoBound(scene, cross).valid);
  cross.centre_px = {30, 30};
  const auto all = CramerRaoBounds(Scene{64, 64, {}, scene.noise, {cross, cross}});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_TRUE(all[0].valid);
  EXPECT_EQ(all[0].sigma_x_px, all[1].sigma_x_px);
  // Twice the noise, twice the bound.
  Scene louder = scene;
  louder.noise.sensor_sigma_dn = 6.0;
  louder.noise.quantize = false;
  scene.noise.quantize = false;
  EXPECT_NEAR(CramerRaoBound(louder, cross).sigma_x_px / CramerRaoBound(scene, cross).sigma_x_px, 2.0, 1e-9);
}

}  // namespace
}  // namespace platemeter::sim
