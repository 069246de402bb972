// The OpenCV export: camera matrix and distCoeffs (k1, k2, p1, p2, k3) fitted
// to the camera (camera_export.h), written as cv::FileStorage YAML, and the
// projection through OpenCV's own cv::projectPoints for the residual.
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "platemeter/calib/camera_export.h"

#if __has_include(<opencv2/calib3d.hpp>)
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#define PLATEMETER_EXPORT_HAVE_CALIB3D 1
#else
#define PLATEMETER_EXPORT_HAVE_CALIB3D 0
#endif

namespace platemeter {

using camera_export_detail::CameraGeometry;
using camera_export_detail::FormatDouble;

std::vector<double> OpenCvCamera::CameraMatrix() const {
  return {fx_px, 0.0, cx_px, 0.0, fy_px, cy_px, 0.0, 0.0, 1.0};
}

std::vector<double> OpenCvCamera::DistCoeffs() const { return {k1, k2, p1, p2, k3}; }

bool OpenCvProjectionAvailable() { return PLATEMETER_EXPORT_HAVE_CALIB3D != 0; }

std::vector<Eigen::Vector2d> ProjectWithOpenCv(const OpenCvCamera& camera,
                                               const std::vector<Eigen::Vector3d>& points_in_camera) {
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(points_in_camera.size());
  if (points_in_camera.empty()) return pixels;
#if PLATEMETER_EXPORT_HAVE_CALIB3D
  std::vector<cv::Point3d> object;
  object.reserve(points_in_camera.size());
  for (const Eigen::Vector3d& p : points_in_camera) object.emplace_back(p.x(), p.y(), p.z());
  const std::vector<double> k = camera.CameraMatrix();
  const cv::Mat camera_matrix = cv::Mat(3, 3, CV_64F, const_cast<double*>(k.data())).clone();
  const std::vector<double> d = camera.DistCoeffs();
  const cv::Mat dist_coeffs = cv::Mat(1, 5, CV_64F, const_cast<double*>(d.data())).clone();
  const cv::Mat zero = cv::Mat::zeros(3, 1, CV_64F);
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, zero, zero, camera_matrix, dist_coeffs, image);
  for (const cv::Point2d& q : image) pixels.emplace_back(q.x, q.y);
#else
  for (const Eigen::Vector3d& p : points_in_camera) {
    const double x = p.x() / p.z(), y = p.y() / p.z();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (camera.k1 + r2 * (camera.k2 + r2 * camera.k3));
    const double xd = x * radial + 2.0 * camera.p1 * x * y + camera.p2 * (r2 + 2.0 * x * x);
    const double yd = y * radial + camera.p1 * (r2 + 2.0 * y * y) + 2.0 * camera.p2 * x * y;
    pixels.emplace_back(camera.fx_px * xd + camera.cx_px, camera.fy_px * yd + camera.cy_px);
  }
#endif
  return pixels;
}

OpenCvCamera FitOpenCvCamera(const CameraExportSource& source, const CameraExportOptions& options,
                             CameraExportReport* report) {
  const CameraGeometry g = camera_export_detail::DescribeCamera(source, options);
  OpenCvCamera camera;
  camera.image_width_px = options.image_width_px;
  camera.image_height_px = options.image_height_px;
  camera.fx_px = g.focal_px * g.jacobian(0, 0);
  camera.fy_px = g.focal_px * g.jacobian(1, 1);
  camera.cx_px = g.axis_px.x();
  camera.cy_px = g.axis_px.y();

  // measured - K(ideal) = K-scaled basis * (k1, k2, k3, p1, p2), linear given the ideal points.
  const int n = static_cast<int>(g.samples.size());
  Eigen::MatrixXd design(2 * n, 5);
  Eigen::VectorXd target(2 * n);
  for (int k = 0; k < n; ++k) {
    const double x = g.samples[k].normalized.x(), y = g.samples[k].normalized.y();
    const double r2 = x * x + y * y;
    const double fx = camera.fx_px, fy = camera.fy_px;
    design.row(2 * k) << fx * x * r2, fx * x * r2 * r2, fx * x * r2 * r2 * r2, fx * 2.0 * x * y,
        fx * (r2 + 2.0 * x * x);
    design.row(2 * k + 1) << fy * y * r2, fy * y * r2 * r2, fy * y * r2 * r2 * r2,
        fy * (r2 + 2.0 * y * y), fy * 2.0 * x * y;
    target(2 * k) = g.samples[k].measured_px.x() - camera.cx_px - fx * x;
    target(2 * k + 1) = g.samples[k].measured_px.y() - camera.cy_px - fy * y;
  }
  const Eigen::VectorXd theta = camera_export_detail::SolveLinearLeastSquares(design, target);
  camera.k1 = theta(0);
  camera.k2 = theta(1);
  camera.k3 = theta(2);
  camera.p1 = theta(3);
  camera.p2 = theta(4);

  if (report != nullptr) {
    report->format = CameraExportFormat::kOpenCv;
    report->target_model = "OpenCV camera matrix and distCoeffs (k1, k2, p1, p2, k3)";
    report->source_model = source.lens_model;
    report->projected_with =
        OpenCvProjectionAvailable() ? "cv::projectPoints" : "OpenCV's distortion formula";
    std::vector<Eigen::Vector3d> rays;
    rays.reserve(n);
    for (const auto& s : g.samples) rays.emplace_back(s.normalized.x(), s.normalized.y(), 1.0);
    camera_export_detail::FillResiduals(g, ProjectWithOpenCv(camera, rays), options, report);
    if (!report->exact) {
      const DistortionModelId id = source.model.model();
      if (id == DistortionModelId::kSlama) {
        report->why_not_exact =
            "Seed 001's distortion is about its own point of symmetry, with a decentering profile "
            "K4 + K5 d^2; OpenCV's is about the principal point with a constant decentering, so "
            "k1, k2, k3, p1, p2 are fitted.";
      } else {
        report->why_not_exact =
            "The camera's model is in correction form (ideal = measured + d(measured)), OpenCV's "
            "in distortion form (measured = ideal + d(ideal)); the inverse of the correction "
            "polynomial is not a polynomial of the ideal point, so k1, k2, k3, p1, p2 are fitted.";
      }
      if (std::abs(g.jacobian(0, 1)) > 1e-12 || std::abs(g.jacobian(1, 0)) > 1e-12) {
        report->why_not_exact +=
            " OpenCV's projection has no skew: the non-orthogonality of the image axes (b2) "
            "stays in the residual.";
      }
    }
  }
  return camera;
}

std::string FormatOpenCvYaml(const OpenCvCamera& camera, const CameraExportReport& report) {
  std::string text = "%YAML:1.0\n---\n";
  text += "# platemeter camera export for OpenCV (cv::FileStorage; cv::projectPoints,\n";
  text += "# cv::undistort). Pixels: x = column, y = row, the centre of the top-left pixel\n";
  text += "# at (0, 0). distortion_coefficients are (k1, k2, p1, p2, k3), OpenCV's order.\n";
  text += "# " + report.Summary() + "\n";
  text += fmt::format("image_width: {}\nimage_height: {}\n", camera.image_width_px,
                      camera.image_height_px);
  auto matrix = [&](const char* name, int rows, int cols, const std::vector<double>& data) {
    std::string values;
    for (size_t k = 0; k < data.size(); ++k) {
      if (k > 0) values += ", ";
      values += FormatDouble(data[k]);
    }
    text += fmt::format("{}: !!opencv-matrix\n   rows: {}\n   cols: {}\n   dt: d\n   data: [ {} ]\n",
                        name, rows, cols, values);
  };
  matrix("camera_matrix", 3, 3, camera.CameraMatrix());
  matrix("distortion_coefficients", 1, 5, camera.DistCoeffs());
  text += fmt::format("fit_rms_residual_px: {}\n", FormatDouble(report.rms_residual_px));
  text += fmt::format("fit_max_residual_px: {}\n", FormatDouble(report.max_residual_px));
  return text;
}

}  // namespace platemeter
