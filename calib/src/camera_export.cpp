// Camera exports: options, the camera's linear part and fit grid in the scan's
// pixels, the shared least-squares and residual helpers, and the entry point.
// The formats are in camera_export_opencv.cpp, _micmac.cpp, _asp.cpp.
#include "platemeter/calib/camera_export.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

Eigen::Vector2d AxisVector(PlateAxis axis) {
  switch (axis) {
    case PlateAxis::kPlusX: return {1.0, 0.0};
    case PlateAxis::kMinusX: return {-1.0, 0.0};
    case PlateAxis::kPlusY: return {0.0, 1.0};
    case PlateAxis::kMinusY: return {0.0, -1.0};
  }
  return {1.0, 0.0};
}

bool AlongX(PlateAxis axis) { return axis == PlateAxis::kPlusX || axis == PlateAxis::kMinusX; }

// The centre of distortion in ideal coordinates relative to the principal point
// (mm): seed 001's point of symmetry (xs, ys); the principal point otherwise.
Eigen::Vector2d DistortionCentreMm(const CameraModel& model) {
  if (model.model() == DistortionModelId::kSlama) return {model.params()[0], model.params()[1]};
  return Eigen::Vector2d::Zero();
}

bool RadialOnly(const CameraModel& model) {
  const std::vector<double>& p = model.params();
  switch (model.model()) {
    case DistortionModelId::kNone: return true;
    case DistortionModelId::kSmacRadialDecentering:  // J1, J2
    case DistortionModelId::kBrownConrady:           // p1, p2
    case DistortionModelId::kBrownBalanced:          // p1, p2
      return p[3] == 0.0 && p[4] == 0.0;
    case DistortionModelId::kBrownAffine:  // p1, p2, b1, b2
      return p[3] == 0.0 && p[4] == 0.0 && p[5] == 0.0 && p[6] == 0.0;
    case DistortionModelId::kSlama:  // K4, K5
      return p[5] == 0.0 && p[6] == 0.0;
  }
  return false;
}

}  // namespace

const char* CameraExportFormatName(CameraExportFormat format) {
  switch (format) {
    case CameraExportFormat::kOpenCv: return "opencv";
    case CameraExportFormat::kMicMac: return "micmac";
    case CameraExportFormat::kAspTsai: return "asp-tsai";
  }
  return "?";
}

bool ParseCameraExportFormat(const std::string& name, CameraExportFormat* format) {
  for (CameraExportFormat candidate :
       {CameraExportFormat::kOpenCv, CameraExportFormat::kMicMac, CameraExportFormat::kAspTsai}) {
    if (name == CameraExportFormatName(candidate)) {
      *format = candidate;
      return true;
    }
  }
  return false;
}

const char* PlateAxisName(PlateAxis axis) {
  switch (axis) {
    case PlateAxis::kPlusX: return "+x";
    case PlateAxis::kMinusX: return "-x";
    case PlateAxis::kPlusY: return "+y";
    case PlateAxis::kMinusY: return "-y";
  }
  return "?";
}

bool CameraExportOptions::Check(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (!(pixel_size_um > 0.0) || !std::isfinite(pixel_size_um)) {
    return fail(fmt::format("pixel size must be positive, got {} um", pixel_size_um));
  }
  if (image_width_px <= 0 || image_height_px <= 0) {
    return fail(fmt::format("image size must be positive, got {} x {} px", image_width_px,
                            image_height_px));
  }
  if ((origin_x_px && !std::isfinite(*origin_x_px)) || (origin_y_px && !std::isfinite(*origin_y_px))) {
    return fail("the frame origin must be finite");
  }
  if (AlongX(column_axis) == AlongX(row_axis)) {
    return fail(fmt::format("column axis {} and row axis {} must be perpendicular",
                            PlateAxisName(column_axis), PlateAxisName(row_axis)));
  }
  if (fit_grid_points_per_side < 5 || fit_grid_points_per_side > 1001) {
    return fail(fmt::format("fit grid must have 5 to 1001 points per side, got {}",
                            fit_grid_points_per_side));
  }
  if (!(exact_tolerance_px > 0.0)) return fail("exact tolerance must be positive");
  return true;
}

std::string CameraExportReport::Summary() const {
  std::string text = fmt::format("{} export ({} lens) as {}: ", CameraExportFormatName(format),
                                 source_model, target_model);
  if (exact) {
    text += fmt::format("exact (residual at the rounding level, max {:.2g} px over {} rays of the "
                        "{:g} x {:g} mm format).",
                        max_residual_px, samples, region_width_mm, region_height_mm);
  } else {
    text += fmt::format("fitted over {} rays of the {:g} x {:g} mm format, residual RMS {:.3g} px "
                        "({:.3g} um), max {:.3g} px ({:.3g} um).",
                        samples, region_width_mm, region_height_mm, rms_residual_px,
                        rms_residual_um, max_residual_px, max_residual_um);
    if (!why_not_exact.empty()) text += " " + why_not_exact;
  }
  if (!projected_with.empty()) text += " Residual measured with " + projected_with + ".";
  if (!note.empty()) text += " " + note;
  return text;
}

CameraExportSource CameraExportSourceFromDefinition(const CameraDefinition& camera) {
  const std::string subject = camera.name.empty() ? std::string("camera") : camera.name;
  if (!camera.lens) throw Error(subject, "has no lens calibration to export");
  const LensCalibration& lens = *camera.lens;
  if (lens.model == "none") {
    if (!lens.coefficients.empty()) {
      throw Error(subject, "lens model none takes no coefficients");
    }
    InteriorOrientation interior;
    interior.principal_distance_mm = lens.principal_distance_mm;
    interior.principal_point_x_mm = lens.principal_point_x_mm;
    interior.principal_point_y_mm = lens.principal_point_y_mm;
    try {
      return CameraExportSource{camera.name, CameraModel(interior, DistortionModelId::kNone, {}),
                                lens.model, camera.format_width_mm, camera.format_height_mm};
    } catch (const Error& error) {
      throw Error(subject, error.reason());
    }
  }
  return CameraExportSource{camera.name, CameraModelFromLensCalibration(lens, subject), lens.model,
                            camera.format_width_mm, camera.format_height_mm};
}

std::string ExportCamera(const CameraDefinition& camera, CameraExportFormat format,
                         const CameraExportOptions& options, CameraExportReport* report) {
  return ExportCamera(CameraExportSourceFromDefinition(camera), format, options, report);
}

std::string ExportCamera(const CameraExportSource& source, CameraExportFormat format,
                         const CameraExportOptions& options, CameraExportReport* report) {
  CameraExportReport local;
  CameraExportReport& out = report != nullptr ? *report : local;
  switch (format) {
    case CameraExportFormat::kOpenCv:
      return FormatOpenCvYaml(FitOpenCvCamera(source, options, &out), out);
    case CameraExportFormat::kMicMac:
      return FormatMicMacXml(FitMicMacCalibration(source, options, &out), out);
    case CameraExportFormat::kAspTsai:
      return FormatAspTsai(FitAspPinhole(source, options, &out));
  }
  throw Error(source.name, "unknown export format");
}

namespace camera_export_detail {

Eigen::Vector2d PixelFrame::PixelFromPlate(const Eigen::Vector2d& point_mm) const {
  return origin_px + axes * point_mm / pixel_mm;
}

Eigen::Vector2d PixelFrame::PlateFromPixel(const Eigen::Vector2d& point_px) const {
  return axes.transpose() * (point_px - origin_px) * pixel_mm;  // axes is orthogonal
}

CameraGeometry DescribeCamera(const CameraExportSource& source, const CameraExportOptions& options) {
  const std::string subject = source.name.empty() ? std::string("camera") : source.name;
  std::string why;
  if (!options.Check(&why)) throw Error(subject, why);
  if (source.format_width_mm < 0.0 || source.format_height_mm < 0.0) {
    throw Error(subject, "format size must not be negative");
  }

  CameraGeometry g;
  g.frame.pixel_mm = options.pixel_size_um / 1e3;  // division: 10 / 1e3 is the double nearest 0.01
  g.frame.origin_px = {options.origin_x_px.value_or(0.5 * (options.image_width_px - 1)),
                       options.origin_y_px.value_or(0.5 * (options.image_height_px - 1))};
  g.frame.axes.row(0) = AxisVector(options.column_axis).transpose();
  g.frame.axes.row(1) = AxisVector(options.row_axis).transpose();

  const CameraModel& model = source.model;
  const InteriorOrientation& io = model.interior();
  const double c = io.principal_distance_mm;
  const Eigen::Vector2d pp_mm(io.principal_point_x_mm, io.principal_point_y_mm);
  g.focal_px = c / g.frame.pixel_mm;
  g.principal_point_px = g.frame.PixelFromPlate(pp_mm);
  g.radial_only = RadialOnly(model);

  auto measured = [&](const Eigen::Vector2d& ideal_mm) {
    const std::optional<Eigen::Vector2d> m = model.MeasuredFromIdeal(ideal_mm);
    if (!m) {
      throw Error(subject, fmt::format("the lens model has no measured image of the ideal point "
                                       "({:.3f}, {:.3f}) mm",
                                       ideal_mm.x(), ideal_mm.y()));
    }
    return *m;
  };
  g.axis_px = g.frame.PixelFromPlate(measured(Eigen::Vector2d::Zero()));
  const Eigen::Vector2d centre_mm = DistortionCentreMm(model);
  g.distortion_centre_px = g.frame.PixelFromPlate(pp_mm + centre_mm);
  // d(measured)/d(ideal) by central differences with Richardson's extrapolation
  // (the h^2 term of the truncation cancels): steps of 1 and 0.5 um keep the
  // truncation (~k1^2 h^4) and the rounding (1e-16 * |measured| / h) below 1e-13.
  const double h = 1e-3;
  Eigen::Matrix2d jacobian_mm;
  for (int k = 0; k < 2; ++k) {
    auto difference = [&](double step) {
      const Eigen::Vector2d d = Eigen::Vector2d::Unit(k) * step;
      return Eigen::Vector2d((measured(centre_mm + d) - measured(centre_mm - d)) / (2.0 * step));
    };
    jacobian_mm.col(k) = (4.0 * difference(0.5 * h) - difference(h)) / 3.0;
  }
  g.jacobian = g.frame.axes * jacobian_mm * g.frame.axes.transpose();

  // The fit region: the format centred on the frame origin, or the image.
  double x0, x1, y0, y1;
  if (source.format_width_mm > 0.0 && source.format_height_mm > 0.0) {
    x0 = -0.5 * source.format_width_mm;
    x1 = -x0;
    y0 = -0.5 * source.format_height_mm;
    y1 = -y0;
  } else {
    x0 = y0 = std::numeric_limits<double>::infinity();
    x1 = y1 = -std::numeric_limits<double>::infinity();
    for (double col : {-0.5, options.image_width_px - 0.5}) {
      for (double row : {-0.5, options.image_height_px - 0.5}) {
        const Eigen::Vector2d p = g.frame.PlateFromPixel({col, row});
        x0 = std::min(x0, p.x());
        x1 = std::max(x1, p.x());
        y0 = std::min(y0, p.y());
        y1 = std::max(y1, p.y());
      }
    }
  }
  g.region_width_mm = x1 - x0;
  g.region_height_mm = y1 - y0;
  const int n = options.fit_grid_points_per_side;
  g.samples.reserve(static_cast<size_t>(n) * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d point_mm(x0 + (x1 - x0) * i / (n - 1), y0 + (y1 - y0) * j / (n - 1));
      const std::optional<Eigen::Vector2d> ideal = model.IdealFromMeasured(point_mm);
      if (!ideal) {
        throw Error(subject, fmt::format("the lens model has no ideal image of the measured point "
                                         "({:.3f}, {:.3f}) mm",
                                         point_mm.x(), point_mm.y()));
      }
      g.samples.push_back({g.frame.PixelFromPlate(point_mm), g.frame.axes * *ideal / c});
    }
  }
  return g;
}

Eigen::VectorXd SolveLinearLeastSquares(const Eigen::MatrixXd& design, const Eigen::VectorXd& target) {
  Eigen::VectorXd scale(design.cols());
  for (int k = 0; k < design.cols(); ++k) {
    const double norm = design.col(k).norm();
    scale(k) = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  const Eigen::MatrixXd scaled = design * scale.asDiagonal();
  const Eigen::VectorXd solution = scaled.colPivHouseholderQr().solve(target);
  return scale.asDiagonal() * solution;
}

bool InvertCorrection(const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& correction,
                      const Eigen::Vector2d& target, double step, Eigen::Vector2d* solution) {
  Eigen::Vector2d p = target;
  // Stop on a step far below the Jacobian step (the units' scale), or at the rounding level.
  const double tolerance =
      std::max(1e-10 * step, 8.0 * std::numeric_limits<double>::epsilon() * target.norm());
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Vector2d f = p + correction(p) - target;
    Eigen::Matrix2d jacobian;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d d = Eigen::Vector2d::Unit(k) * step;
      jacobian.col(k) = d / step + (correction(p + d) - correction(p - d)) / (2.0 * step);
    }
    const Eigen::Vector2d delta = jacobian.partialPivLu().solve(f);
    if (!delta.allFinite()) return false;
    p -= delta;
    if (delta.norm() <= tolerance) {
      *solution = p;
      return true;
    }
  }
  return false;
}

void FillResiduals(const CameraGeometry& geometry, const std::vector<Eigen::Vector2d>& projected_px,
                   const CameraExportOptions& options, CameraExportReport* report) {
  double sum2 = 0.0, max = 0.0;
  for (size_t k = 0; k < geometry.samples.size(); ++k) {
    const double d = (projected_px[k] - geometry.samples[k].measured_px).norm();
    sum2 += d * d;
    max = std::max(max, std::isfinite(d) ? d : std::numeric_limits<double>::infinity());
  }
  const int n = static_cast<int>(geometry.samples.size());
  report->samples = n;
  report->region_width_mm = geometry.region_width_mm;
  report->region_height_mm = geometry.region_height_mm;
  report->rms_residual_px = n > 0 ? std::sqrt(sum2 / n) : 0.0;
  report->max_residual_px = max;
  report->rms_residual_um = report->rms_residual_px * options.pixel_size_um;
  report->max_residual_um = max * options.pixel_size_um;
  report->exact = max < options.exact_tolerance_px;
  if (report->exact) report->why_not_exact.clear();
}

std::string FormatDouble(double value) {
  std::string text = fmt::format("{}", value);  // the shortest text that reads back the same
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // n: nan, inf
  return text;
}

}  // namespace camera_export_detail
}  // namespace platemeter
