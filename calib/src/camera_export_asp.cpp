// The Ames Stereo Pipeline export: a VERSION_4 PINHOLE .tsai in metres with a
// Photometrix (correction form) or TSAI (OpenCV's distortion form) block
// (camera_export.h has the formulas).
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "platemeter/calib/camera_export.h"

namespace platemeter {
namespace {

using camera_export_detail::CameraGeometry;
using camera_export_detail::FormatDouble;

// Photometrix's correction (undistorted - measured) at u = s - (cu + xp, cv + yp), metres.
Eigen::Vector2d PhotometrixCorrection(const AspPinhole& a, const Eigen::Vector2d& u) {
  const double r2 = u.squaredNorm();
  const double drr = r2 * (a.k1 + r2 * (a.k2 + r2 * a.k3));
  return {u.x() * drr + a.p1 * (r2 + 2.0 * u.x() * u.x()) + 2.0 * a.p2 * u.x() * u.y(),
          u.y() * drr + a.p2 * (r2 + 2.0 * u.y() * u.y()) + 2.0 * a.p1 * u.x() * u.y()};
}

struct Candidate {
  AspPinhole camera;
  CameraExportReport report;
};

Candidate FitPhotometrix(const CameraExportSource& source, const CameraExportOptions& options,
                         const CameraGeometry& g) {
  Candidate out;
  AspPinhole& a = out.camera;
  a.distortion = AspDistortion::kPhotometrix;
  a.pitch_m = options.pixel_size_um / 1e6;
  // The ideal principal point at (cu, cv); the distortion centre at (cu + xp, cv + yp).
  a.cu_m = g.principal_point_px.x() * a.pitch_m;
  a.cv_m = g.principal_point_px.y() * a.pitch_m;
  a.xp_m = (g.distortion_centre_px.x() - g.principal_point_px.x()) * a.pitch_m;
  a.yp_m = (g.distortion_centre_px.y() - g.principal_point_px.y()) * a.pitch_m;
  // Correction form: d(ideal)/d(measured) at the centre must be the identity in
  // the distortion terms, so fu, fv take its diagonal.
  const Eigen::Matrix2d ideal_from_measured = g.jacobian.inverse();
  a.fu_m = g.focal_px / ideal_from_measured(0, 0) * a.pitch_m;
  a.fv_m = g.focal_px / ideal_from_measured(1, 1) * a.pitch_m;

  const Eigen::Vector2d cu(a.cu_m, a.cv_m), centre(a.cu_m + a.xp_m, a.cv_m + a.yp_m);
  const Eigen::Vector2d f(a.fu_m, a.fv_m);
  const int n = static_cast<int>(g.samples.size());
  Eigen::MatrixXd design(2 * n, 5);
  Eigen::VectorXd target(2 * n);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d s = g.samples[k].measured_px * a.pitch_m;
    const Eigen::Vector2d undistorted = cu + f.cwiseProduct(g.samples[k].normalized);
    const Eigen::Vector2d u = s - centre;
    const double x = u.x(), y = u.y(), r2 = u.squaredNorm();
    design.row(2 * k) << x * r2, x * r2 * r2, x * r2 * r2 * r2, r2 + 2.0 * x * x, 2.0 * x * y;
    design.row(2 * k + 1) << y * r2, y * r2 * r2, y * r2 * r2 * r2, 2.0 * x * y, r2 + 2.0 * y * y;
    target.segment<2>(2 * k) = undistorted - s;
  }
  const Eigen::VectorXd theta = camera_export_detail::SolveLinearLeastSquares(design, target);
  a.k1 = theta(0);
  a.k2 = theta(1);
  a.k3 = theta(2);
  a.p1 = theta(3);
  a.p2 = theta(4);

  std::vector<Eigen::Vector2d> projected;
  projected.reserve(n);
  for (const auto& sample : g.samples) {
    const Eigen::Vector2d undistorted = cu + f.cwiseProduct(sample.normalized);
    Eigen::Vector2d s;
    const bool ok = camera_export_detail::InvertCorrection(
        [&](const Eigen::Vector2d& p) { return PhotometrixCorrection(a, p - centre); }, undistorted,
        1e-3 * a.pitch_m, &s);
    projected.push_back(ok ? Eigen::Vector2d(s / a.pitch_m) : Eigen::Vector2d::Constant(std::nan("")));
  }
  CameraExportReport& r = out.report;
  r.target_model = "ASP .tsai PINHOLE with Photometrix distortion (correction form)";
  r.projected_with = "ASP's Photometrix formula, inverted by Newton's method";
  camera_export_detail::FillResiduals(g, projected, options, &r);
  if (!r.exact) {
    const DistortionModelId id = source.model.model();
    if (id == DistortionModelId::kBrownAffine) {
      r.why_not_exact =
          "ASP's Photometrix model does not use b1, b2: the affinity goes into fu / fv "
          "(b1, up to its product with the distortion) and the non-orthogonality b2 stays in "
          "the residual.";
    } else if (id == DistortionModelId::kSlama) {
      r.why_not_exact =
          "Seed 001's model is in distortion form about its point of symmetry, with a decentering "
          "profile K4 + K5 d^2; Photometrix is in correction form with a constant P1, P2, so the "
          "coefficients are fitted.";
    } else {
      r.why_not_exact =
          "The camera's decentering profile (J2 r^4 of seed 004) is beyond Photometrix's constant "
          "P1, P2, so the coefficients are fitted.";
    }
  }
  return out;
}

Candidate FitTsai(const CameraExportSource& source, const CameraExportOptions& options) {
  Candidate out;
  const OpenCvCamera cv = FitOpenCvCamera(source, options, &out.report);
  AspPinhole& a = out.camera;
  a.distortion = AspDistortion::kTsai;
  a.pitch_m = options.pixel_size_um / 1e6;
  a.fu_m = cv.fx_px * a.pitch_m;
  a.fv_m = cv.fy_px * a.pitch_m;
  a.cu_m = cv.cx_px * a.pitch_m;
  a.cv_m = cv.cy_px * a.pitch_m;
  a.k1 = cv.k1;
  a.k2 = cv.k2;
  a.k3 = cv.k3;
  a.p1 = cv.p1;
  a.p2 = cv.p2;
  out.report.target_model = "ASP .tsai PINHOLE with TSAI distortion (OpenCV's model)";
  return out;
}

}  // namespace

AspPinhole FitAspPinhole(const CameraExportSource& source, const CameraExportOptions& options,
                         CameraExportReport* report) {
  Candidate chosen;
  switch (options.asp_distortion) {
    case AspDistortion::kPhotometrix:
      chosen = FitPhotometrix(source, options, camera_export_detail::DescribeCamera(source, options));
      break;
    case AspDistortion::kTsai:
      chosen = FitTsai(source, options);
      break;
    case AspDistortion::kAuto: {
      Candidate photometrix =
          FitPhotometrix(source, options, camera_export_detail::DescribeCamera(source, options));
      Candidate tsai = FitTsai(source, options);
      const bool photometrix_wins = photometrix.report.exact ||
                                    photometrix.report.max_residual_px <= tsai.report.max_residual_px;
      const Candidate& other = photometrix_wins ? tsai : photometrix;
      const std::string note =
          fmt::format("Chosen over the {} block, whose max residual is {:.3g} px.",
                      photometrix_wins ? "TSAI" : "Photometrix", other.report.max_residual_px);
      chosen = photometrix_wins ? std::move(photometrix) : std::move(tsai);
      chosen.report.note = note;
      break;
    }
  }
  if (report != nullptr) {
    *report = chosen.report;
    report->format = CameraExportFormat::kAspTsai;
    report->source_model = source.lens_model;
  }
  return chosen.camera;
}

std::string FormatAspTsai(const AspPinhole& a) {
  // As ASP writes it (VisionWorkbench PinholeModel::write): no comments, one
  // "name = value" per line; the pose is the identity at the origin.
  std::string t = "VERSION_4\nPINHOLE\n";
  t += fmt::format("fu = {}\nfv = {}\ncu = {}\ncv = {}\n", FormatDouble(a.fu_m), FormatDouble(a.fv_m),
                   FormatDouble(a.cu_m), FormatDouble(a.cv_m));
  t += "u_direction = 1 0 0\nv_direction = 0 1 0\nw_direction = 0 0 1\n";
  t += "C = 0 0 0\nR = 1 0 0 0 1 0 0 0 1\n";
  t += fmt::format("pitch = {}\n", FormatDouble(a.pitch_m));
  if (a.distortion == AspDistortion::kTsai) {
    t += fmt::format("TSAI\nk1 = {}\nk2 = {}\np1 = {}\np2 = {}\nk3 = {}\n", FormatDouble(a.k1),
                     FormatDouble(a.k2), FormatDouble(a.p1), FormatDouble(a.p2), FormatDouble(a.k3));
  } else {
    t += fmt::format("Photometrix\nxp = {}\nyp = {}\nk1 = {}\nk2 = {}\nk3 = {}\np1 = {}\np2 = {}\n"
                     "b1 = 0.0\nb2 = 0.0\n",
                     FormatDouble(a.xp_m), FormatDouble(a.yp_m), FormatDouble(a.k1),
                     FormatDouble(a.k2), FormatDouble(a.k3), FormatDouble(a.p1), FormatDouble(a.p2));
  }
  return t;
}

}  // namespace platemeter
