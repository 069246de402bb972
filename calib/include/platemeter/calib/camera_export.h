#pragma once
// Exports of a calibrated camera to the camera formats of other tools
// (docs/camera-exports.md). The camera is a CameraDefinition with its lens
// calibration, read through CameraModel (camera_model.h): any lens model
// CameraModel supports (brown-affine, brown-balanced, smac-radial-decentering,
// orbigon-11, none) goes through CameraModel::IdealFromMeasured /
// MeasuredFromIdeal, so the exports never depend on how a model was published.
//
// The scan. Pixels follow platemeter's convention (core/pixel.h): x = column,
// y = row, the CENTRE of the top-left pixel is (0, 0) (OpenCV, MicMac and ASP
// count pixels the same way). A plate point p (mm, camera frame: x right, y up,
// origin where the principal point xp, yp is measured from) is at
//   pixel = origin_px + axes p / pixel_mm
// where the rows of `axes` are the camera-frame unit vectors along which the
// column and the row grow (CameraExportOptions::column_axis, row_axis; default
// +x and -y: rows downward) and origin_px is where the frame origin lies
// (default: the image centre, ((width - 1) / 2, (height - 1) / 2)).
// The other tools' camera frame is x along the columns, y along the rows, z
// toward the object; a ray whose ideal image (distortion-free, relative to the
// principal point) is ideal_mm has the normalized coordinates
//   (x', y') = axes ideal_mm / c.
//
// The formats:
//   kOpenCv   K = [fx 0 cx; 0 fy cy; 0 0 1] (px) and distCoeffs (k1, k2, p1, p2, k3):
//               x'' = x'(1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x'y' + p2 (r^2 + 2 x'^2)
//               y'' = y'(1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y'^2) + 2 p2 x'y'
//               column = fx x'' + cx,  row = fy y'' + cy          (r^2 = x'^2 + y'^2)
//             DISTORTION form (measured from ideal), as cv::FileStorage YAML.
//   kMicMac   ExportAPERO / CalibrationInternConique: F, PP (px), SzIm and one
//             CalibDistortion, ModPhgrStd (radial CoeffDist about CDist, P1 P2,
//             b1 b2) or ModRad (radial only), all in pixels, u = p - CDist:
//               D(p) = p + u (K1 r^2 + K2 r^4 + K3 r^6)
//                        + (P1 (r^2 + 2 ux^2) + 2 P2 ux uy + b1 ux + b2 uy,
//                           2 P1 ux uy + P2 (r^2 + 2 uy^2))
//             eConvApero_DistM2C (default): measured = D(ideal), ideal = PP + F (x', y');
//             eConvApero_DistC2M:           ideal = D(measured).
//   kAspTsai  Ames Stereo Pipeline .tsai, VERSION_4 PINHOLE: fu, fv, cu, cv and
//             pitch in metres (column = (fu x'' + cu) / pitch), u/v/w directions,
//             C = 0 and R = I (the export is the interior orientation; the pose is
//             per image), and a distortion block:
//               Photometrix: undistorted = s + u (K1 r^2 + K2 r^4 + K3 r^6)
//                            + (P1 (r^2 + 2 ux^2) + 2 P2 ux uy, 2 P1 ux uy + P2 (r^2 + 2 uy^2)),
//                            u = s - (cu + xp, cv + yp), s the measured point in metres
//                            (CORRECTION form, seed 000's);
//               TSAI: OpenCV's model on (x', y') (the kOpenCv coefficients).
//
// Exact or fitted. Each target's linear part (focal lengths, principal point,
// distortion centre) comes from the camera's: fx = c / pixel times the
// Jacobian d(measured)/d(ideal) at the centre of distortion (so OpenCV's fx is
// the Gaussian focal length: c' / (1 + k0') for brown-balanced, c / (1 + b1) in x
// for brown-affine). The distortion coefficients are then FITTED by linear least
// squares on a grid of ideal <-> measured correspondences over the camera's
// format (every target model is linear in its coefficients once the ideal, or
// for correction forms the measured, points are given), and the residual of
// the target's own projection against CameraModel's is measured on that grid
// (in px and um) and returned. Where the target can represent the camera (a
// correction-form target, MicMac's eConvApero_DistC2M or ASP's Photometrix, for
// a seed 000 / 004 camera) the fit reproduces the exact conversion and the
// residual is at the rounding level (report.exact). Where it cannot (OpenCV's distortion form for
// seed 000's correction form: the inverse of a polynomial map is not a
// polynomial; an affinity b2 that a pinhole without skew cannot hold), the
// residual says how far the exported camera is from the calibrated one.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/camera_model.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

enum class CameraExportFormat { kOpenCv, kMicMac, kAspTsai };
const char* CameraExportFormatName(CameraExportFormat format);  // "opencv", "micmac", "asp-tsai"
bool ParseCameraExportFormat(const std::string& name, CameraExportFormat* format);

// A camera-frame direction (plate frame: x right, y up).
enum class PlateAxis { kPlusX, kMinusX, kPlusY, kMinusY };
const char* PlateAxisName(PlateAxis axis);  // "+x", "-x", "+y", "-y"

// MicMac's direction of the distortion function (KnownConv).
enum class MicMacConvention {
  kDistortionM2C,  // eConvApero_DistM2C: measured = D(ideal); what MicMac tools write and read
  kCorrectionC2M,  // eConvApero_DistC2M: ideal = D(measured); seed 000's direction (exact for Brown cameras)
};

// The .tsai distortion block.
enum class AspDistortion {
  kAuto,         // the one with the smaller maximum residual (Photometrix on a tie)
  kPhotometrix,  // correction form: exact for brown-conrady, brown-balanced, smac (J2 = 0);
                 // brown-affine up to b1, b2 (ASP does not use its b1, b2)
  kTsai,         // OpenCV's distortion form (fitted); ASP's fastest to project with
};

struct CameraExportOptions {
  // The scan.
  double pixel_size_um = 0.0;  // um; side of the scan's (square) pixels; required, > 0
  int image_width_px = 0;      // px; scan width; required, > 0
  int image_height_px = 0;     // px; scan height; required, > 0
  // Where the camera frame lies in the pixel grid (see the header comment).
  std::optional<double> origin_x_px;     // px; column of the frame origin; default (width - 1) / 2
  std::optional<double> origin_y_px;     // px; row of the frame origin; default (height - 1) / 2
  PlateAxis column_axis = PlateAxis::kPlusX;  // camera-frame direction in which the column grows
  PlateAxis row_axis = PlateAxis::kMinusY;    // camera-frame direction in which the row grows (down)
  // The fit.
  int fit_grid_points_per_side = 41;  // grid of n x n measured points over the format (>= 5)
  double exact_tolerance_px = 1e-6;   // px; a max residual below this is reported as exact
  // Per format.
  MicMacConvention micmac_convention = MicMacConvention::kDistortionM2C;
  AspDistortion asp_distortion = AspDistortion::kAuto;

  bool Check(std::string* why) const;
};

// What was exported and how close it is to the calibrated camera. Residuals are
// the length of (target's projection - CameraModel's projection) of the same
// ray, over the fit grid (the camera's format).
struct CameraExportReport {
  CameraExportFormat format = CameraExportFormat::kOpenCv;
  std::string target_model;   // e.g. "OpenCV (k1, k2, p1, p2, k3)", "MicMac ModPhgrStd, eConvApero_DistM2C"
  std::string source_model;   // the lens model, e.g. "brown-affine"
  bool exact = false;         // max residual below CameraExportOptions::exact_tolerance_px
  int samples = 0;            // rays compared (the fit grid)
  double region_width_mm = 0.0, region_height_mm = 0.0;  // mm; the fit region (the format)
  double rms_residual_px = 0.0;  // px; RMS of the residual length
  double max_residual_px = 0.0;  // px
  double rms_residual_um = 0.0;  // um; the same in the plate (pixel_size_um per px)
  double max_residual_um = 0.0;  // um
  std::string why_not_exact;     // one sentence: why the target cannot hold the camera exactly (empty if exact)
  std::string projected_with;    // how the residual was measured: "cv::projectPoints" or the target's formula
  std::string note;              // anything else the user should know (e.g. the block AspDistortion::kAuto passed over)

  // One paragraph a user can act on: what was written, exact or fitted, the residual.
  std::string Summary() const;
};

// The camera to export: its model and the region (format) the fit covers.
struct CameraExportSource {
  std::string name;              // for messages and file headers
  CameraModel model;
  std::string lens_model;        // the published model name (LensCalibration::model)
  double format_width_mm = 0.0;  // mm; fit region, centred on the frame origin; 0: the image
  double format_height_mm = 0.0;
};

// Throws platemeter::Error(camera name, reason) if the camera has no lens
// calibration or the lens cannot be read. A lens whose model is "none" (no
// coefficients) is the distortion-free camera c, xp, yp.
CameraExportSource CameraExportSourceFromDefinition(const CameraDefinition& camera);

// ---------------------------------------------------------------------------
// The single entry point: the file text of `format` for `camera`. Throws
// platemeter::Error(camera name, one-line reason) on bad input (no lens,
// options failing Check, e.g. a non-positive pixel size). `report`, if given,
// receives the residuals.
std::string ExportCamera(const CameraDefinition& camera, CameraExportFormat format,
                         const CameraExportOptions& options, CameraExportReport* report = nullptr);
std::string ExportCamera(const CameraExportSource& source, CameraExportFormat format,
                         const CameraExportOptions& options, CameraExportReport* report = nullptr);

// ---------------------------------------------------------------------------
// The exported cameras as values.

struct OpenCvCamera {
  double fx_px = 0.0, fy_px = 0.0;  // px; focal lengths
  double cx_px = 0.0, cy_px = 0.0;  // px; where the optical axis meets the (measured) image
  double k1 = 0.0, k2 = 0.0, k3 = 0.0, p1 = 0.0, p2 = 0.0;  // OpenCV's, on normalized coordinates
  int image_width_px = 0, image_height_px = 0;
  std::vector<double> CameraMatrix() const;     // 9 values, row-major
  std::vector<double> DistCoeffs() const;       // {k1, k2, p1, p2, k3}, OpenCV's order
};

struct MicMacCalibration {
  MicMacConvention convention = MicMacConvention::kDistortionM2C;
  bool radial_only = false;            // ModRad (no decentering, no affinity) instead of ModPhgrStd
  double f_px = 0.0;                   // px; F
  double pp_x_px = 0.0, pp_y_px = 0.0;  // px; PP
  double cdist_x_px = 0.0, cdist_y_px = 0.0;  // px; CDist
  double coeff_dist[3] = {0.0, 0.0, 0.0};     // K1 [1/px^2], K2 [1/px^4], K3 [1/px^6]
  double p1 = 0.0, p2 = 0.0;           // 1/px
  double b1 = 0.0, b2 = 0.0;           // -
  int image_width_px = 0, image_height_px = 0;
};

struct AspPinhole {
  AspDistortion distortion = AspDistortion::kPhotometrix;  // kPhotometrix or kTsai (never kAuto)
  double fu_m = 0.0, fv_m = 0.0;  // m
  double cu_m = 0.0, cv_m = 0.0;  // m; the principal point, from the centre of the top-left pixel
  double pitch_m = 0.0;           // m; pixel size
  // Photometrix: xp, yp [m] (distortion centre from cu, cv), k1 [1/m^2], k2 [1/m^4],
  // k3 [1/m^6], p1, p2 [1/m]; b1 = b2 = 0 (ASP does not use them).
  // TSAI: k1, k2, k3, p1, p2 dimensionless (OpenCV's); xp = yp = 0.
  double xp_m = 0.0, yp_m = 0.0;
  double k1 = 0.0, k2 = 0.0, k3 = 0.0, p1 = 0.0, p2 = 0.0;
};

// Each throws like ExportCamera; `report` (if given) receives the residuals.
OpenCvCamera FitOpenCvCamera(const CameraExportSource& source, const CameraExportOptions& options,
                             CameraExportReport* report = nullptr);
MicMacCalibration FitMicMacCalibration(const CameraExportSource& source,
                                       const CameraExportOptions& options,
                                       CameraExportReport* report = nullptr);
AspPinhole FitAspPinhole(const CameraExportSource& source, const CameraExportOptions& options,
                         CameraExportReport* report = nullptr);

// The file texts (the report's numbers go into comments where the format allows them).
std::string FormatOpenCvYaml(const OpenCvCamera& camera, const CameraExportReport& report);
std::string FormatMicMacXml(const MicMacCalibration& calibration, const CameraExportReport& report);
std::string FormatAspTsai(const AspPinhole& camera);

// Pixel positions of points given in the OpenCV camera frame (x along the
// columns, y along the rows, z forward; rvec = tvec = 0) through `camera`:
// OpenCV's own cv::projectPoints where the library was built with OpenCV's
// calib3d (OpenCvProjectionAvailable()), else the formula in the header comment.
std::vector<Eigen::Vector2d> ProjectWithOpenCv(const OpenCvCamera& camera,
                                               const std::vector<Eigen::Vector3d>& points_in_camera);
bool OpenCvProjectionAvailable();

// ---------------------------------------------------------------------------
// Shared by the exports (declared here so that each format's file can use them).
namespace camera_export_detail {

// pixel = origin_px + axes p_mm / pixel_mm.
struct PixelFrame {
  Eigen::Vector2d origin_px = Eigen::Vector2d::Zero();
  Eigen::Matrix2d axes = Eigen::Matrix2d::Identity();  // rows: camera-frame directions of column, row
  double pixel_mm = 0.0;
  Eigen::Vector2d PixelFromPlate(const Eigen::Vector2d& point_mm) const;
  Eigen::Vector2d PlateFromPixel(const Eigen::Vector2d& point_px) const;
};

// A ray of the camera on the fit grid.
struct RaySample {
  Eigen::Vector2d measured_px;  // px; where CameraModel images it in the scan
  Eigen::Vector2d normalized;   // (x', y') = axes ideal_mm / c: the target camera frame's X/Z, Y/Z
};

// The camera's linear part in the scan's pixels, and the fit grid.
struct CameraGeometry {
  PixelFrame frame;
  double focal_px = 0.0;                   // px; c / pixel
  Eigen::Vector2d principal_point_px;      // px; (xp, yp)
  Eigen::Vector2d axis_px;                 // px; measured image of the optical axis (ideal 0)
  Eigen::Vector2d distortion_centre_px;    // px; ideal image of the centre of distortion
                                           // (the principal point; seed 001's point of symmetry)
  Eigen::Matrix2d jacobian;                // d(measured px) / d(ideal px) at the centre of distortion
  bool radial_only = false;                // no decentering and no affinity in the camera's model
  double region_width_mm = 0.0, region_height_mm = 0.0;
  std::vector<RaySample> samples;
};

// Throws Error(source.name, reason) for options failing Check or a grid point
// whose ideal image cannot be computed.
CameraGeometry DescribeCamera(const CameraExportSource& source, const CameraExportOptions& options);

// Least squares min |design * x - target| with the columns scaled to unit
// length first (the basis functions differ by many orders of magnitude).
Eigen::VectorXd SolveLinearLeastSquares(const Eigen::MatrixXd& design, const Eigen::VectorXd& target);

// Solves p + correction(p) = target by Newton's method (central-difference
// Jacobian with `step`), starting at target. False if it does not converge.
bool InvertCorrection(const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& correction,
                      const Eigen::Vector2d& target, double step, Eigen::Vector2d* solution);

// Fills the report's residual fields from the target's projected pixels (one per sample).
void FillResiduals(const CameraGeometry& geometry, const std::vector<Eigen::Vector2d>& projected_px,
                   const CameraExportOptions& options, CameraExportReport* report);

// The shortest text that reads back to the same double, always with a '.' or an
// exponent ("1.0", "0.1", "1e-05").
std::string FormatDouble(double value);

}  // namespace camera_export_detail

}  // namespace platemeter
