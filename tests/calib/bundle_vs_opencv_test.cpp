// Platemeter's self-calibrating bundle (calib/bundle_adjustment.h) against
// OpenCV's calibrateCamera on the same planar-target observations
// (samples/bundle_block.h SimulatePlanarTarget), the issue's bar: "the same
// distortion field (compare fields, not coefficients) within 0.3 sigma, and
// sigmas equal to its stdDeviationsIntrinsics once scaled alike".
// What is compared and why: docs/bundle-vs-opencv.md.
#include <gtest/gtest.h>

#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/samples/bundle_block.h"

#include <opencv2/calib3d.hpp>

namespace platemeter {
namespace {

using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;

// The adjusted inner cone, kBundleCameraParamNames indices: c, xp, yp, k1, k2,
// p1, p2 (k3, b1, b2 held at 0, as OpenCV's CALIB_FIX_K3 and its lack of an
// affinity). theta below is this vector.
constexpr std::array<int, 7> kAdjusted = {0, 1, 2, 3, 4, 6, 7};
constexpr std::array<const char*, 7> kThetaNames = {"c_mm", "xp_mm", "yp_mm", "k1_per_mm2",
                                                    "k2_per_mm4", "p1_per_mm", "p2_per_mm"};
// OpenCV's intrinsics in the same count: f (fx = fy, CALIB_FIX_ASPECT_RATIO),
// cx, cy, k1, k2, p1, p2 (k3 fixed at 0). phi below is this vector.
constexpr std::array<const char*, 7> kPhiNames = {"f_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2"};

// The block: the simulator's default planar target (a 16 mm lens on 18 x 12 mm,
// 3000 x 2000 pixels of 6 um, k1 and k2 giving ~48 um of radial correction at
// the 10.8 mm half diagonal, p1 = 2e-5 and p2 = -1.5e-5 /mm giving ~3 um of
// decentering (profile) there; 12 x 9 points, 15 poses tilted 10..45 deg, rolled +-90
// deg; 0.6 um = 0.1 px of noise per axis), both tools starting from the true
// c, xp, yp and zero distortion. The simulator's default seed (1).
sim::PlanarTargetOptions TargetOptions() {
  sim::PlanarTargetOptions options;
  options.approximations.zero_distortion = true;
  // Other blocks (docs/bundle-vs-opencv.md lists seeds 1..8).
  if (const char* seed = std::getenv("BUNDLE_VS_OPENCV_SEED")) options.seed = std::stoull(seed);
  return options;
}

// ---------------------------------------------------------------------------
// Platemeter.

struct PlatemeterFit {
  Vec7 theta = Vec7::Zero();
  Mat7 covariance = Mat7::Zero();  // scaled by sigma0^2
  double sigma0 = 0.0;
  double dof = 0.0;
  double sum_squares_px2 = 0.0;  // sum of squared residuals, in pixels^2 (ideal-plane residuals / pixel)
  bool converged = false;
  std::string summary;
  std::vector<BundleFrameResult> frames;  // the exterior orientations, for the recomputed Jacobian
};

// c, xp, yp, k1, k2, p1, p2 free; k3, b1, b2 fixed at 0; every frame free;
// every target point fixed (sigma 0): OpenCV takes the object points as exact,
// so both tools solve for the same unknowns (the intrinsics and six exterior
// parameters per view) and the datum is the target itself.
PlatemeterFit RunPlatemeter(const sim::PlanarTargetBlock& target, bool noise_free) {
  BundleInput input = target.block.input;
  if (noise_free) {
    for (std::size_t i = 0; i < input.observations.size(); ++i) {
      input.observations[i].x_mm = target.block.truth.observations[i].x_mm;
      input.observations[i].y_mm = target.block.truth.observations[i].y_mm;
    }
  }
  for (int i : kAdjusted) input.cameras[0].states[i] = ParameterState::Free();
  for (GroundPoint& point : input.ground_points) point.sigma_m = {0.0, 0.0, 0.0};
  BundleOptions options;
  options.datum = DatumKind::kControlPoints;
  const BundleResult result = RunBundleAdjustment(input, options);
  EXPECT_EQ(result.datum, DatumKind::kControlPoints);

  PlatemeterFit fit;
  fit.converged = result.adjustment.converged;
  fit.summary = result.adjustment.summary;
  fit.sigma0 = result.adjustment.sigma0;
  fit.dof = result.adjustment.dof;
  const BundleCameraResult& camera = result.cameras.at(0);
  std::vector<int> indices;
  for (int k = 0; k < 7; ++k) {
    fit.theta[k] = camera.values[kAdjusted[k]];
    indices.push_back(camera.parameter_index[kAdjusted[k]]);
  }
  fit.covariance = result.adjustment.Covariance(indices, /*scaled=*/true);
  fit.frames = result.frames;
  const double pixel_mm = target.pixels.pixel_size_um * 1e-3;
  for (const ObservationResidual& r : result.adjustment.residuals) {
    for (double v : r.residual) fit.sum_squares_px2 += (v / pixel_mm) * (v / pixel_mm);
  }
  return fit;
}

// BrownAffine's seven from theta (k3, b1, b2 = 0).
std::array<double, 7> BrownAffineParams(const Vec7& theta) {
  return {theta[3], theta[4], 0.0, theta[5], theta[6], 0.0, 0.0};
}

// The distortion field of platemeter's model at a plate point (mm, format
// frame): measured minus ideal, both about the model's principal point,
// = -Apply(measured - principal point) (seed 000's correction form). mm.
Eigen::Vector2d PlatemeterField_mm(const Vec7& theta, const Eigen::Vector2d& plate_mm) {
  const std::array<double, 7> p = BrownAffineParams(theta);
  double dx = 0.0, dy = 0.0;
  BrownAffine::Apply(p.data(), plate_mm.x() - theta[1], plate_mm.y() - theta[2], &dx, &dy);
  return {-dx, -dy};
}

// Pixel of a normalized direction (X/Z, Y/Z in seed 000's image frame, which
// is OpenCV's camera frame) through platemeter's camera.
Eigen::Vector2d PlatemeterPixel(const Vec7& theta, const Eigen::Vector2d& direction,
                                const sim::PixelMapping& pixels) {
  const std::array<double, 7> p = BrownAffineParams(theta);
  double mx = 0.0, my = 0.0;
  const bool ok = MeasuredFromIdeal<BrownAffine>(p.data(), theta[0] * direction.x(), theta[0] * direction.y(), &mx,
                                                 &my);
  EXPECT_TRUE(ok);
  return pixels.PixelFromPlate(Eigen::Vector2d(mx + theta[1], my + theta[2]));
}

// ---------------------------------------------------------------------------
// OpenCV's model (distortion form, normalized coordinates), written out so
// that it can be inverted and mapped; checked against cv::projectPoints.

Eigen::Vector2d OpenCvDistort(const Vec7& phi, const Eigen::Vector2d& n, double k3 = 0.0) {
  const double x = n.x(), y = n.y(), r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (phi[3] + r2 * (phi[4] + r2 * k3));
  return {x * radial + 2.0 * phi[5] * x * y + phi[6] * (r2 + 2.0 * x * x),
          y * radial + phi[5] * (r2 + 2.0 * y * y) + 2.0 * phi[6] * x * y};
}

Eigen::Vector2d OpenCvPixel(const Vec7& phi, const Eigen::Vector2d& direction, double k3 = 0.0) {
  const Eigen::Vector2d d = OpenCvDistort(phi, direction, k3);
  return {phi[0] * d.x() + phi[1], phi[0] * d.y() + phi[2]};
}

// Normalized undistorted coordinates of normalized distorted ones (Newton).
Eigen::Vector2d OpenCvUndistort(const Vec7& phi, const Eigen::Vector2d& distorted, double k3 = 0.0) {
  Eigen::Vector2d n = distorted;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Vector2d hx(1e-7, 0.0), hy(0.0, 1e-7);
    Eigen::Matrix2d jacobian;
    jacobian.col(0) = (OpenCvDistort(phi, n + hx, k3) - OpenCvDistort(phi, n - hx, k3)) / (2 * hx.x());
    jacobian.col(1) = (OpenCvDistort(phi, n + hy, k3) - OpenCvDistort(phi, n - hy, k3)) / (2 * hy.y());
    const Eigen::Vector2d step = jacobian.partialPivLu().solve(OpenCvDistort(phi, n, k3) - distorted);
    n -= step;
    if (step.norm() < 1e-15) break;
  }
  return n;
}

// OpenCV's distortion field at a plate point (mm): the point's pixel, its
// normalized distorted coordinates about OpenCV's principal point, the
// undistorted ones, and measured minus ideal back in mm (times f * pixel).
Eigen::Vector2d OpenCvField_mm(const Vec7& phi, const sim::PixelMapping& pixels, const Eigen::Vector2d& plate_mm,
                               double k3 = 0.0) {
  const Eigen::Vector2d px = pixels.PixelFromPlate(plate_mm);
  const Eigen::Vector2d distorted((px.x() - phi[1]) / phi[0], (px.y() - phi[2]) / phi[0]);
  return (distorted - OpenCvUndistort(phi, distorted, k3)) * phi[0] * pixels.pixel_size_um * 1e-3;
}

// Steps for finite differences: 1 % of each parameter's sigma.
Vec7 Steps(const Mat7& covariance) { return 0.01 * covariance.diagonal().cwiseSqrt(); }

// The exact least-squares map between the models: the OpenCV intrinsics whose
// pixels best match platemeter's camera's over a grid of directions filling
// the format (Gauss-Newton), and its Jacobian d phi / d theta (the regression
// of platemeter's tangent vectors on OpenCV's: (Jphi' Jphi)^-1 Jphi' Jtheta).
struct ModelMap {
  Vec7 phi = Vec7::Zero();
  Mat7 jacobian = Mat7::Zero();
  double rms_px = 0.0;  // of the fit (the models' difference over the grid)
  double max_px = 0.0;
};

ModelMap MapToOpenCv(const Vec7& theta, const Vec7& theta_steps, const sim::PixelMapping& pixels,
                     const std::vector<Eigen::Vector2d>& directions) {
  const int n = static_cast<int>(directions.size());
  const double pixel_mm = pixels.pixel_size_um * 1e-3;
  auto platemeter_pixels = [&](const Vec7& t) {
    Eigen::VectorXd out(2 * n);
    for (int i = 0; i < n; ++i) out.segment<2>(2 * i) = PlatemeterPixel(t, directions[i], pixels);
    return out;
  };
  auto opencv_pixels = [&](const Vec7& phi) {
    Eigen::VectorXd out(2 * n);
    for (int i = 0; i < n; ++i) out.segment<2>(2 * i) = OpenCvPixel(phi, directions[i]);
    return out;
  };
  auto opencv_jacobian = [&](const Vec7& phi) {
    Eigen::MatrixXd j(2 * n, 7);
    for (int k = 0; k < 7; ++k) {
      const double h = k == 0 ? 1e-3 : (k < 3 ? 1e-3 : 1e-7);
      Vec7 plus = phi, minus = phi;
      plus[k] += h, minus[k] -= h;
      j.col(k) = (opencv_pixels(plus) - opencv_pixels(minus)) / (2 * h);
    }
    return j;
  };
  // First-order start (bundle_block.h): f = c / pixel, k1 = -k1 c^2, k2 = -k2 c^4,
  // p1_cv = -p2 c, p2_cv = -p1 c.
  ModelMap map;
  const double c = theta[0];
  map.phi << c / pixel_mm, pixels.PixelFromPlate({theta[1], theta[2]}).x(),
      pixels.PixelFromPlate({theta[1], theta[2]}).y(), -theta[3] * c * c, -theta[4] * c * c * c * c, -theta[6] * c,
      -theta[5] * c;
  const Eigen::VectorXd target = platemeter_pixels(theta);
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Eigen::MatrixXd j = opencv_jacobian(map.phi);
    const Eigen::VectorXd r = opencv_pixels(map.phi) - target;
    const Vec7 step = (j.transpose() * j).ldlt().solve(j.transpose() * r);
    map.phi -= step;
  }
  const Eigen::VectorXd r = opencv_pixels(map.phi) - target;
  map.rms_px = std::sqrt(r.squaredNorm() / n);
  map.max_px = r.cwiseAbs().maxCoeff();
  const Eigen::MatrixXd j_phi = opencv_jacobian(map.phi);
  Eigen::MatrixXd j_theta(2 * n, 7);
  for (int k = 0; k < 7; ++k) {
    Vec7 plus = theta, minus = theta;
    plus[k] += theta_steps[k], minus[k] -= theta_steps[k];
    j_theta.col(k) = (platemeter_pixels(plus) - platemeter_pixels(minus)) / (2 * theta_steps[k]);
  }
  map.jacobian = (j_phi.transpose() * j_phi).ldlt().solve(j_phi.transpose() * j_theta);
  return map;
}

// Platemeter's covariance of theta recomputed from a numerical Jacobian at its
// solution, the target points fixed, in one of two residual forms:
//   kIdeal:    seed 000 eq. (1) as the engine writes it (CollinearityResidualT:
//              the measured point corrected by the model minus the projection),
//              whitened with the observation's sigma as if it were measured;
//   kMeasured: the projection through the model (ProjectDirectionT, distortion
//              inverted) minus the measured point, OpenCV's form.
// Scaled by sum(r^2) / (2n - p) of the same residuals.
enum class ResidualForm { kIdeal, kMeasured };

// The whitened Jacobian (rows: observations x, y in input order; columns:
// theta, then X, Y, Z, phi, omega, kappa per frame) and the residuals' sum of squares.
Eigen::MatrixXd PlatemeterJacobian(const PlatemeterFit& fit, ResidualForm form, const BundleInput& input,
                                   double* sum_squares_out) {
  std::map<std::string, int> frame_index;
  for (std::size_t f = 0; f < fit.frames.size(); ++f) frame_index[fit.frames[f].id] = static_cast<int>(f);
  std::map<std::string, Eigen::Vector3d> point_position;
  for (const GroundPoint& p : input.ground_points) point_position[p.id] = p.position_m;
  const int unknowns = 7 + 6 * static_cast<int>(fit.frames.size());
  const int rows = 2 * static_cast<int>(input.observations.size());
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(rows, unknowns);
  double sum_squares = 0.0;
  const Vec7 steps = Steps(fit.covariance);
  // Residual of one observation for theta and the frame's six.
  auto residual = [&](const ImageObservation& o, const Vec7& theta, const Eigen::Matrix<double, 6, 1>& frame) {
    const std::array<double, 3> interior = {theta[0], theta[1], theta[2]};
    const std::array<double, 7> distortion = BrownAffineParams(theta);
    double rotation[9];
    TMatrixT(frame[3], frame[4], frame[5], rotation);
    const Eigen::Vector3d d = point_position.at(o.point_id) - frame.head<3>();
    Eigen::Vector2d r;
    if (form == ResidualForm::kIdeal) {
      EXPECT_TRUE(CollinearityResidualT<BrownAffine>(interior.data(), distortion.data(), rotation, d.data(), o.x_mm,
                                                     o.y_mm, r.data()));
    } else {
      double x = 0.0, y = 0.0;
      EXPECT_TRUE(ProjectDirectionT<BrownAffine>(interior.data(), distortion.data(), rotation, d.data(), &x, &y));
      r = Eigen::Vector2d(x - o.x_mm, y - o.y_mm);
    }
    return Eigen::Vector2d(r / o.sigma_x_mm);  // whitened (sigma_x = sigma_y here)
  };
  for (std::size_t i = 0; i < input.observations.size(); ++i) {
    const ImageObservation& o = input.observations[i];
    const int f = frame_index.at(o.frame);
    const BundleFrameResult& fr = fit.frames[f];
    Eigen::Matrix<double, 6, 1> frame;
    frame << fr.position_m, fr.angles.phi_rad, fr.angles.omega_rad, fr.angles.kappa_rad;
    const Eigen::Vector2d r0 = residual(o, fit.theta, frame);
    sum_squares += r0.squaredNorm();
    for (int k = 0; k < 7; ++k) {
      Vec7 plus = fit.theta, minus = fit.theta;
      plus[k] += steps[k], minus[k] -= steps[k];
      j.block<2, 1>(2 * i, k) = (residual(o, plus, frame) - residual(o, minus, frame)) / (2 * steps[k]);
    }
    for (int k = 0; k < 6; ++k) {
      const double h = k < 3 ? 1e-6 : 1e-8;  // m, rad
      Eigen::Matrix<double, 6, 1> plus = frame, minus = frame;
      plus[k] += h, minus[k] -= h;
      j.block<2, 1>(2 * i, 7 + 6 * f + k) = (residual(o, fit.theta, plus) - residual(o, fit.theta, minus)) / (2 * h);
    }
  }
  *sum_squares_out = sum_squares;
  return j;
}

Mat7 RecomputedCovariance(const PlatemeterFit& fit, ResidualForm form, const BundleInput& input) {
  double sum_squares = 0.0;
  const Eigen::MatrixXd j = PlatemeterJacobian(fit, form, input, &sum_squares);
  const Eigen::MatrixXd normal = j.transpose() * j;
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(j.cols(), j.cols());
  const Mat7 cofactor = normal.ldlt().solve(identity).topLeftCorner<7, 7>();
  return cofactor * sum_squares / (j.rows() - j.cols());
}

// Plate points (mm) on a grid over the format, inset by the simulator's margin
// (where target points can fall), columns x rows.
std::vector<Eigen::Vector2d> FormatGrid(const sim::PlanarTargetOptions& options, int columns, int rows) {
  const double half_w = 0.5 * options.camera.format_width_mm - options.format_margin_mm;
  const double half_h = 0.5 * options.camera.format_height_mm - options.format_margin_mm;
  std::vector<Eigen::Vector2d> grid;
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < columns; ++i) {
      grid.emplace_back(-half_w + 2.0 * half_w * i / (columns - 1), -half_h + 2.0 * half_h * j / (rows - 1));
    }
  }
  return grid;
}

Vec7 TrueTheta(const sim::BundleCameraTruth& camera) {
  Vec7 t;
  t << camera.c_mm, camera.xp_mm, camera.yp_mm, camera.k1_per_mm2, camera.k2_per_mm4, camera.p1_per_mm,
      camera.p2_per_mm;
  return t;
}

TEST(BundleVsOpenCv, PlatemeterRecoversTheTrueFieldOfThePlanarTarget) {
  const sim::PlanarTargetOptions options = TargetOptions();
  const sim::PlanarTargetBlock target = sim::SimulatePlanarTarget(options);
  const PlatemeterFit fit = RunPlatemeter(target, /*noise_free=*/false);
  SCOPED_TRACE(fit.summary);
  ASSERT_TRUE(fit.converged);
  EXPECT_NEAR(fit.sigma0, 1.0, 0.1);
  const Vec7 truth = TrueTheta(options.camera);
  const Vec7 steps = Steps(fit.covariance);
  double worst = 0.0;
  for (const Eigen::Vector2d& p : FormatGrid(options, 13, 9)) {
    Eigen::Matrix<double, 2, 7> j;
    for (int k = 0; k < 7; ++k) {
      Vec7 plus = fit.theta, minus = fit.theta;
      plus[k] += steps[k], minus[k] -= steps[k];
      j.col(k) = (PlatemeterField_mm(plus, p) - PlatemeterField_mm(minus, p)) / (2 * steps[k]);
    }
    const Eigen::Matrix2d field_covariance = j * fit.covariance * j.transpose();
    const Eigen::Vector2d error = PlatemeterField_mm(fit.theta, p) - PlatemeterField_mm(truth, p);
    for (int a = 0; a < 2; ++a) worst = std::max(worst, std::abs(error[a]) / std::sqrt(field_covariance(a, a)));
  }
  EXPECT_LT(worst, 4.0) << "platemeter's field against the truth, in its own sigmas";
}


struct OpenCvFit {
  Vec7 phi = Vec7::Zero();      // f (= fy = fx), cx, cy, k1, k2, p1, p2
  double k3 = 0.0;
  Vec7 std_dev = Vec7::Zero();  // stdDeviationsIntrinsics as returned; fy's for f
  double std_dev_fx = 0.0;      // fx is tied to fy (CALIB_FIX_ASPECT_RATIO): OpenCV reports 0
  double rms_px = 0.0;          // calibrateCamera's return value
  double sum_squares_px2 = 0.0; // sum of squared residuals (x and y) at its solution
  int points = 0;
  int unknowns = 0;             // 7 intrinsics + 6 per view
  Eigen::MatrixXd jacobian;     // OpenCV's Jacobian at its solution (cv::projectPoints): pixels per
                                // f, cx, cy, k1, k2, p1, p2, then rvec, tvec per view
  Mat7 cofactor = Mat7::Zero(); // intrinsic block of (J'J)^-1, px^-2 (sigma0 = 1 px)
};

// calibrateCamera on the block's views (the noisy pixels, or the noise-free
// ones), flags as close to platemeter's model as OpenCV allows: one focal
// length (CALIB_FIX_ASPECT_RATIO with fx = fy given), k3 fixed at 0 (unless
// fix_k3 is false), p1 and p2 free (no CALIB_ZERO_TANGENT_DIST), started from
// the true fx, cx, cy and zero distortion (CALIB_USE_INTRINSIC_GUESS).
OpenCvFit RunOpenCv(const sim::PlanarTargetBlock& target, bool noise_free, bool fix_k3 = true) {
  std::vector<std::vector<cv::Point3f>> object(target.views.size());
  std::vector<std::vector<cv::Point2f>> image(target.views.size());
  for (std::size_t v = 0; v < target.views.size(); ++v) {
    const sim::PlanarTargetView& view = target.views[v];
    for (std::size_t i = 0; i < view.object_points_m.size(); ++i) {
      const Eigen::Vector3d& o = view.object_points_m[i];
      const Eigen::Vector2d& m = noise_free ? view.true_image_points_px[i] : view.image_points_px[i];
      // calibrateCamera takes float points (OpenCV 4.6 converts to CV_32F anyway):
      // 2e-4 px of rounding against 0.1 px of noise.
      object[v].emplace_back(static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z()));
      image[v].emplace_back(static_cast<float>(m.x()), static_cast<float>(m.y()));
    }
  }
  const sim::OpenCvIntrinsics& k = target.intrinsics;
  cv::Mat camera_matrix = (cv::Mat_<double>(3, 3) << k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0);
  cv::Mat distortion = cv::Mat::zeros(1, 5, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics, std_extrinsics, per_view;
  const int flags = cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_ASPECT_RATIO | (fix_k3 ? cv::CALIB_FIX_K3 : 0);
  OpenCvFit fit;
  fit.rms_px = cv::calibrateCamera(object, image, cv::Size(target.pixels.width_px, target.pixels.height_px),
                                   camera_matrix, distortion, rvecs, tvecs, std_intrinsics, std_extrinsics, per_view,
                                   flags,
                                   cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 500, DBL_EPSILON));
  EXPECT_NEAR(camera_matrix.at<double>(0, 0), camera_matrix.at<double>(1, 1), 1e-9);
  const double* d = distortion.ptr<double>();
  fit.phi << camera_matrix.at<double>(1, 1), camera_matrix.at<double>(0, 2), camera_matrix.at<double>(1, 2), d[0],
      d[1], d[2], d[3];
  fit.k3 = d[4];
  const double* s = std_intrinsics.ptr<double>();
  fit.std_dev << s[1], s[2], s[3], s[4], s[5], s[6], s[7];
  fit.std_dev_fx = s[0];
  if (!fix_k3) return fit;

  const int views = static_cast<int>(target.views.size());
  int rows = 0;
  for (const auto& o : object) rows += 2 * static_cast<int>(o.size());
  fit.points = rows / 2;
  fit.unknowns = 7 + 6 * views;
  fit.jacobian = Eigen::MatrixXd::Zero(rows, fit.unknowns);
  int row = 0;
  for (int v = 0; v < views; ++v) {
    std::vector<cv::Point2d> projected;
    cv::Mat jacobian;  // 2n x 15: rvec, tvec, fx, fy, cx, cy, k1, k2, p1, p2, k3
    const std::vector<cv::Point3d> object_d(object[v].begin(), object[v].end());
    cv::projectPoints(object_d, rvecs[v], tvecs[v], camera_matrix, distortion, projected, jacobian);
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const double rx = projected[i].x - image[v][i].x, ry = projected[i].y - image[v][i].y;
      fit.sum_squares_px2 += rx * rx + ry * ry;
      for (int a = 0; a < 2; ++a, ++row) {
        const double* jr = jacobian.ptr<double>(static_cast<int>(2 * i + a));
        fit.jacobian(row, 0) = jr[6] + jr[7];  // fx = fy = f
        for (int c = 0; c < 2; ++c) fit.jacobian(row, 1 + c) = jr[8 + c];
        for (int c = 0; c < 4; ++c) fit.jacobian(row, 3 + c) = jr[10 + c];
        for (int c = 0; c < 6; ++c) fit.jacobian(row, 7 + 6 * v + c) = jr[c];
      }
    }
  }
  const Eigen::MatrixXd normal = fit.jacobian.transpose() * fit.jacobian;
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(fit.unknowns, fit.unknowns);
  fit.cofactor = normal.ldlt().solve(identity).topLeftCorner<7, 7>();
  return fit;
}

// Both tools once per process (the tests below share them).
struct Comparison {
  sim::PlanarTargetOptions options;
  sim::PlanarTargetBlock target;
  PlatemeterFit platemeter;        // the noisy observations
  PlatemeterFit platemeter_exact;  // the noise-free ones (its model's floor: none)
  OpenCvFit opencv;                // the noisy observations
  OpenCvFit opencv_exact;          // the noise-free ones: OpenCV's model floor, k3 fixed
  OpenCvFit opencv_exact_k3;       // the same with k3 free
  // Platemeter's estimate mapped to OpenCV's parameters: over a grid of
  // directions filling the format (no poses), and through the observations
  // with the poses free (d phi / d theta).
  ModelMap format_map;
  Mat7 data_map = Mat7::Zero();
};

const Comparison& Compare() {
  static const Comparison comparison = [] {
    Comparison c;
    c.options = TargetOptions();
    c.target = sim::SimulatePlanarTarget(c.options);
    c.platemeter = RunPlatemeter(c.target, false);
    c.platemeter_exact = RunPlatemeter(c.target, true);
    c.opencv = RunOpenCv(c.target, false);
    c.opencv_exact = RunOpenCv(c.target, true);
    c.opencv_exact_k3 = RunOpenCv(c.target, true, /*fix_k3=*/false);

    // Directions whose true images fill the format (25 x 17 plate points).
    std::vector<Eigen::Vector2d> directions;
    const Vec7 truth = TrueTheta(c.options.camera);
    const std::array<double, 7> params = BrownAffineParams(truth);
    for (const Eigen::Vector2d& p : FormatGrid(c.options, 25, 17)) {
      const Eigen::Vector2d m = p - Eigen::Vector2d(truth[1], truth[2]);
      double dx = 0.0, dy = 0.0;
      BrownAffine::Apply(params.data(), m.x(), m.y(), &dx, &dy);
      directions.push_back((m + Eigen::Vector2d(dx, dy)) / truth[0]);
    }
    c.format_map = MapToOpenCv(c.platemeter.theta, Steps(c.platemeter.covariance), c.target.pixels, directions);

    // The map on the observations, poses free: the OpenCV change (intrinsics and
    // poses, least squares) that best reproduces the pixel change a change of
    // theta makes at every observed point (platemeter's poses held: a change of
    // pose is a change of pose in either tool). Same order of observations
    // (frame-major, points in order) in both.
    double unused = 0.0;
    const Eigen::MatrixXd j_theta_px =
        PlatemeterJacobian(c.platemeter, ResidualForm::kMeasured, c.target.block.input, &unused).leftCols(7) *
        (c.options.sigma_um / c.options.pixel_size_um);
    const Eigen::MatrixXd& j_cv = c.opencv.jacobian;
    c.data_map = (j_cv.transpose() * j_cv).ldlt().solve(j_cv.transpose() * j_theta_px).topRows(7);
    return c;
  }();
  return comparison;
}

TEST(BundleVsOpenCv, OurOpenCvModelIsOpenCvs) {
  // The distortion written out above against cv::projectPoints (identity pose).
  Vec7 phi;
  phi << 2666.7, 1504.5, 996.2, -0.0128, 0.007, 2.4e-4, -3.2e-4;
  const double k3 = 0.02;
  cv::Mat camera_matrix = (cv::Mat_<double>(3, 3) << phi[0], 0.0, phi[1], 0.0, phi[0], phi[2], 0.0, 0.0, 1.0);
  cv::Mat distortion = (cv::Mat_<double>(1, 5) << phi[3], phi[4], phi[5], phi[6], k3);
  const std::vector<cv::Point3d> points = {{0.3, -0.2, 1.0}, {-0.31, 0.22, 1.0}, {0.05, 0.18, 1.0}};
  std::vector<cv::Point2d> projected;
  cv::projectPoints(points, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), camera_matrix, distortion,
                    projected);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d n(points[i].x, points[i].y);
    const Eigen::Vector2d ours = OpenCvPixel(phi, n, k3);
    EXPECT_NEAR(ours.x(), projected[i].x, 1e-9);
    EXPECT_NEAR(ours.y(), projected[i].y, 1e-9);
    const Eigen::Vector2d back = OpenCvUndistort(phi, OpenCvDistort(phi, n, k3), k3);
    EXPECT_NEAR(back.x(), n.x(), 1e-13);
    EXPECT_NEAR(back.y(), n.y(), 1e-13);
  }
}

// The fields: measured minus ideal, um, at 13 x 9 plate points over the format,
// each tool's lens about its own principal point (docs/bundle-vs-opencv.md).
// The difference OpenCV - platemeter holds OpenCV's model floor: its
// distortion form with k1, k2 cannot take seed 000's correction form (the
// simulator's and platemeter's) exactly; OpenCV on the noise-free points shows
// it. It is held to the 0.3 sigma where platemeter's field sigma is at
// least 1 nm: that leaves out one grid point, (0, 0), 37 um from the principal
// point, where the field is zero by construction (8e-5 um, sigma 2e-6 um) and
// the ratio compares the models' second-order terms, not the estimates. With
// the floor taken out (how the two estimates follow the same noise) every
// point is held to 0.3 sigma.
TEST(BundleVsOpenCv, DistortionFieldsAgreeWithinAThirdOfPlatemetersSigma) {
  const Comparison& c = Compare();
  SCOPED_TRACE(c.platemeter.summary);
  ASSERT_TRUE(c.platemeter.converged);
  ASSERT_TRUE(c.platemeter_exact.converged);
  EXPECT_NEAR(c.platemeter.sigma0, 1.0, 0.1);
  const Vec7 truth = TrueTheta(c.options.camera);
  const Vec7 steps = Steps(c.platemeter.covariance);
  const sim::PixelMapping& pixels = c.target.pixels;
  const double kNoSigma_um = 1e-3;  // a field component known better than this is zero by construction
  const auto um = [](const Eigen::Vector2d& v) { return Eigen::Vector2d(v * 1e3); };
  struct Worst {
    double sigmas = 0.0, um = 0.0;
    Eigen::Vector2d where = Eigen::Vector2d::Zero();
    void Add(const Eigen::Vector2d& d, const Eigen::Vector2d& sigma, const Eigen::Vector2d& p, double min_sigma = 0.0) {
      for (int a = 0; a < 2; ++a) {
        if (sigma[a] < min_sigma) continue;
        if (std::abs(d[a]) / sigma[a] > sigmas) sigmas = std::abs(d[a]) / sigma[a], where = p;
        um = std::max(um, std::abs(d[a]));
      }
    }
  };
  Worst raw, raw_everywhere, beyond_floor, platemeter_vs_truth, opencv_vs_truth, platemeter_floor, opencv_floor;
  double largest_field = 0.0, largest_sigma = 0.0;
  int left_out = 0;
  std::printf("\n  plate mm    | platemeter um   sigma um    | OpenCV-platemeter (sigmas)  "
              "| OpenCV floor | truth um\n");
  for (const Eigen::Vector2d& p : FormatGrid(c.options, 13, 9)) {
    Eigen::Matrix<double, 2, 7> j;  // d field / d theta (c's column is zero: the field does not depend on it)
    for (int k = 0; k < 7; ++k) {
      Vec7 plus = c.platemeter.theta, minus = c.platemeter.theta;
      plus[k] += steps[k], minus[k] -= steps[k];
      j.col(k) = (PlatemeterField_mm(plus, p) - PlatemeterField_mm(minus, p)) / (2 * steps[k]);
    }
    const Eigen::Vector2d sigma = um((j * c.platemeter.covariance * j.transpose()).diagonal().cwiseSqrt());
    const Eigen::Vector2d pm = um(PlatemeterField_mm(c.platemeter.theta, p));
    const Eigen::Vector2d cv = um(OpenCvField_mm(c.opencv.phi, pixels, p));
    const Eigen::Vector2d tr = um(PlatemeterField_mm(truth, p));
    const Eigen::Vector2d floor = um(OpenCvField_mm(c.opencv_exact.phi, pixels, p)) - tr;
    raw.Add(cv - pm, sigma, p, kNoSigma_um);
    raw_everywhere.Add(cv - pm, sigma, p);
    beyond_floor.Add(cv - pm - floor, sigma, p);
    platemeter_vs_truth.Add(pm - tr, sigma, p);
    opencv_vs_truth.Add(cv - tr, sigma, p);
    platemeter_floor.Add(um(PlatemeterField_mm(c.platemeter_exact.theta, p)) - tr, sigma, p);
    opencv_floor.Add(floor, sigma, p);
    largest_field = std::max(largest_field, pm.norm());
    largest_sigma = std::max({largest_sigma, sigma.x(), sigma.y()});
    if (sigma.minCoeff() < kNoSigma_um) {
      ++left_out;
      std::printf("  left out: %.1f %.1f mm, field %.1e %.1e um, sigma %.1e %.1e um, "
                  "OpenCV - platemeter %.1e %.1e um\n",
                  p.x(), p.y(), pm.x(), pm.y(), sigma.x(), sigma.y(), (cv - pm).x(), (cv - pm).y());
    }
    const bool corner_or_axis = (std::abs(std::abs(p.x()) - 8.7) < 1e-9 || std::abs(p.x()) < 1e-9) &&
                                (std::abs(std::abs(p.y()) - 5.7) < 1e-9 || std::abs(p.y()) < 1e-9);
    if (corner_or_axis && sigma.minCoeff() >= kNoSigma_um) {
      const Eigen::Vector2d d = cv - pm;
      std::printf("  %5.1f %5.1f | %7.2f %7.2f %5.2f %5.2f | %6.3f %6.3f (%5.2f %5.2f) | %6.3f %6.3f | %7.2f %7.2f\n",
                  p.x(), p.y(), pm.x(), pm.y(), sigma.x(), sigma.y(), d.x(), d.y(), d.x() / sigma.x(),
                  d.y() / sigma.y(), floor.x(), floor.y(), tr.x(), tr.y());
    }
  }
  const double pixel_um = c.options.pixel_size_um;
  std::printf("  field up to %.1f um; platemeter's field sigma up to %.2f um (noise %.2f um = %.2f px)\n",
              largest_field, largest_sigma, c.options.sigma_um, c.options.sigma_um / pixel_um);
  const auto line = [](const char* what, const Worst& w) {
    std::printf("  %-40s max %.4f um, %.3f sigma (at %5.1f %5.1f mm)\n", what, w.um, w.sigmas, w.where.x(),
                w.where.y());
  };
  line("OpenCV - platemeter (sigma >= 1 nm):", raw);
  line("OpenCV - platemeter (every point):", raw_everywhere);
  line("OpenCV's floor (noise-free) - truth:", opencv_floor);
  line("(OpenCV - platemeter) - OpenCV's floor:", beyond_floor);
  line("platemeter - truth:", platemeter_vs_truth);
  line("OpenCV - truth:", opencv_vs_truth);
  line("platemeter noise-free - truth:", platemeter_floor);
  std::printf("  noise-free rms residual: OpenCV %.4f um (k3 fixed), %.4f um (k3 free)\n",
              c.opencv_exact.rms_px * pixel_um, c.opencv_exact_k3.rms_px * pixel_um);

  // The bar.
  EXPECT_LE(left_out, 1);
  EXPECT_LT(raw.sigmas, 0.3);
  // What should agree at every point: the two estimates follow the noise alike.
  EXPECT_LT(beyond_floor.sigmas, 0.3);
  // OpenCV's floor: a model difference of second order in the distortion
  // (3 k1 r^2 = 1.8 % of the field at the corner, before k1, k2 absorb most of it).
  EXPECT_LT(opencv_floor.um, 0.01 * largest_field);
  // Platemeter's model is the simulator's: no floor.
  EXPECT_LT(platemeter_floor.um, 1e-4);
  // Sanity: both near the truth (max over 117 points, two components each).
  EXPECT_LT(platemeter_vs_truth.sigmas, 4.0);
  EXPECT_LT(opencv_vs_truth.sigmas, 4.0);
}

// Sigmas "scaled alike": OpenCV's stdDeviationsIntrinsics against platemeter's
// covariance mapped to OpenCV's parameters, both scaled by sum r^2 / (2n - p).
TEST(BundleVsOpenCv, SigmasAgreeWithStdDeviationsIntrinsicsScaledAlike) {
  const Comparison& c = Compare();
  ASSERT_TRUE(c.platemeter.converged);
  const OpenCvFit& cv = c.opencv;
  const double px_per_sigma = c.options.sigma_um / c.options.pixel_size_um;

  // OpenCV's scale: its stdDevs are sqrt(diag((J'J)^-1) * sigma2). Which sigma2?
  Vec7 implied;
  for (int k = 0; k < 7; ++k) implied[k] = cv.std_dev[k] * cv.std_dev[k] / cv.cofactor(k, k);
  const double sigma2_points = cv.sum_squares_px2 / (cv.points - cv.unknowns);            // OpenCV 4.6
  const double sigma2_residuals = cv.sum_squares_px2 / (2.0 * cv.points - cv.unknowns);  // standard; later OpenCV
  const bool per_point = std::abs(implied.mean() / sigma2_points - 1.0) < 1e-4;
  const bool per_residual = std::abs(implied.mean() / sigma2_residuals - 1.0) < 1e-4;
  EXPECT_LT((implied.array() / implied.mean() - 1.0).abs().maxCoeff(), 1e-4) << "one sigma2 for every intrinsic";
  EXPECT_TRUE(per_point || per_residual) << implied.mean();
  const double rescale = std::sqrt(sigma2_residuals / implied.mean());
  // Platemeter's scale: sigma0^2 = v'Pv / (2n - p), the same convention; in pixels
  // it is the same number as OpenCV's standard sigma2 (the same residuals up to
  // the correction form's weighting).
  const double platemeter_sigma0_px = c.platemeter.sigma0 * px_per_sigma;
  std::printf("\n  OpenCV %s: rms %.4f px over %d points, %d unknowns, sum r^2 %.4f px^2\n", CV_VERSION, cv.rms_px,
              cv.points, cv.unknowns, cv.sum_squares_px2);
  std::printf("  its stdDev^2 / diag((J'J)^-1) = %.6g px^2 = sum r^2 / (%s - p); "
              "scaled alike by sqrt(%.6g / %.6g) = %.4f\n",
              implied.mean(), per_point ? "n points" : "2 n", sigma2_residuals, implied.mean(), rescale);
  std::printf("  sigma0: OpenCV sqrt(sum r^2 / (2n - p)) = %.5f px, platemeter %.4f x %.2f px = %.5f px "
              "(dof %.0f, sum r^2 %.4f px^2 in the ideal plane)\n",
              std::sqrt(sigma2_residuals), c.platemeter.sigma0, px_per_sigma, platemeter_sigma0_px, c.platemeter.dof,
              c.platemeter.sum_squares_px2);
  EXPECT_NEAR(platemeter_sigma0_px / std::sqrt(sigma2_residuals), 1.0, 0.01);
  EXPECT_NEAR(c.platemeter.dof, 2.0 * cv.points - cv.unknowns, 0.5);

  // The engine's covariance is (J'PJ)^-1 sigma0^2 of its own equations (recomputed
  // here by finite differences): seed 000's residual (corrected measurement minus
  // projection) carried back to the measured plane by the correction's slope, so
  // that it is weighted like OpenCV's (projection minus measurement); weighting
  // the ideal-plane residual directly would differ by the slope, 1 + 3 k1 r^2 <= 1.02.
  const Mat7 recomputed = RecomputedCovariance(c.platemeter, ResidualForm::kIdeal, c.target.block.input);
  const Mat7 measured_form = RecomputedCovariance(c.platemeter, ResidualForm::kMeasured, c.target.block.input);

  const Mat7 by_data = c.data_map * c.platemeter.covariance * c.data_map.transpose();
  const Mat7 by_format = c.format_map.jacobian * c.platemeter.covariance * c.format_map.jacobian.transpose();
  std::printf("  platemeter -> OpenCV over the format: fit rms %.1e px, max %.1e px\n", c.format_map.rms_px,
              c.format_map.max_px);
  std::printf("  %-5s | %14s %11s %11s | %14s %11s %11s | %6s %6s\n", "", "platemeter", "sigma data", "sigma format",
              "OpenCV", "stdDev", "scaled", "/data", "/format");
  for (int k = 0; k < 7; ++k) {
    const double scaled = cv.std_dev[k] * rescale;
    std::printf("  %-5s | %14.7g %11.4g %11.4g | %14.7g %11.4g %11.4g | %6.4f %6.4f\n", kPhiNames[k],
                c.format_map.phi[k], std::sqrt(by_data(k, k)), std::sqrt(by_format(k, k)), cv.phi[k], cv.std_dev[k],
                scaled, scaled / std::sqrt(by_data(k, k)), scaled / std::sqrt(by_format(k, k)));
  }
  std::printf("  %-10s | %14s %11s | %10s %10s\n", "platemeter", "value", "sigma", "ideal plane", "measured");
  for (int k = 0; k < 7; ++k) {
    const double sigma = std::sqrt(c.platemeter.covariance(k, k));
    std::printf("  %-10s | %14.7g %11.4g | %10.5f %10.5f\n", kThetaNames[k], c.platemeter.theta[k], sigma,
                std::sqrt(recomputed(k, k)) / sigma, std::sqrt(measured_form(k, k)) / sigma);
    EXPECT_NEAR(std::sqrt(measured_form(k, k)) / sigma, 1.0, 1e-3) << kThetaNames[k];
  }

  for (int k = 0; k < 7; ++k) {
    const double scaled = cv.std_dev[k] * rescale;
    // Through the observations: the same residuals, weighted alike; what is
    // left is the two models' difference (OpenCV's floor, < 0.5 %).
    EXPECT_NEAR(scaled / std::sqrt(by_data(k, k)), 1.0, 0.005) << kPhiNames[k];
    // Through the format grid, the cruder map (its weighting is not the
    // observations'): the 10 %.
    EXPECT_NEAR(scaled / std::sqrt(by_format(k, k)), 1.0, 0.10) << kPhiNames[k];
  }
}


}  // namespace
}  // namespace platemeter
