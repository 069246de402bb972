// Camera exports (calib/camera_export.h): OpenCV (against cv::projectPoints),
// MicMac (well-formed XML, hand-checked values, MicMac's own formula
// re-evaluated here), ASP .tsai (against a hand-computed example), the bad
// inputs, and every built-in camera's lens model.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platemeter/calib/camera_export.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "support/test_support.h"

#include <opencv2/calib3d.hpp>

namespace platemeter {
namespace {

// A mapping camera of seed 000's form: c = 153.26 mm, a 114.3 mm format,
// distortion of some 20 um at the corners.
CameraDefinition BrownAffineCamera(double p1, double p2, double b1, double b2) {
  CameraDefinition camera;
  camera.name = "test-brown-affine";
  camera.format_width_mm = 114.3;
  camera.format_height_mm = 114.3;
  LensCalibration lens;
  lens.model = "brown-affine";
  lens.principal_distance_mm = 153.26;
  lens.principal_point_x_mm = 0.012;
  lens.principal_point_y_mm = -0.021;
  lens.coefficients = {{"k1_per_mm2", 4.0e-8}, {"k2_per_mm4", -2.0e-12}, {"k3_per_mm6", 1.0e-17},
                       {"p1_per_mm", p1},      {"p2_per_mm", p2},       {"b1", b1},
                       {"b2", b2}};
  camera.lens = lens;
  return camera;
}

CameraExportOptions ScanOptions() {
  CameraExportOptions options;
  options.pixel_size_um = 10.0;
  options.image_width_px = 12000;
  options.image_height_px = 12000;
  return options;
}

// Rays over 95 % of the format, as OpenCV camera-frame points (z = 1) and the
// pixels where the platemeter camera images them.
struct Rays {
  std::vector<Eigen::Vector3d> in_opencv_frame;
  std::vector<Eigen::Vector2d> platemeter_px;
};

Rays RaysOverFormat(const CameraExportSource& source, const CameraExportOptions& options) {
  const camera_export_detail::CameraGeometry g = camera_export_detail::DescribeCamera(source, options);
  const double c = source.model.interior().principal_distance_mm;
  Rays rays;
  for (double u = -0.95; u <= 0.951; u += 0.19 / 2) {
    for (double v = -0.95; v <= 0.951; v += 0.19 / 2) {
      const Eigen::Vector2d ideal_mm(u * 0.5 * source.format_width_mm, v * 0.5 * source.format_height_mm);
      // The platemeter direction (image frame: x right, y up, w toward the object).
      const Eigen::Vector3d direction(ideal_mm.x(), ideal_mm.y(), c);
      const std::optional<Eigen::Vector2d> measured =
          source.model.ProjectDirection(Eigen::Matrix3d::Identity(), direction);
      EXPECT_TRUE(measured.has_value());
      rays.platemeter_px.push_back(g.frame.PixelFromPlate(*measured));
      const Eigen::Vector2d normalized = g.frame.axes * ideal_mm / c;  // OpenCV's X/Z, Y/Z
      rays.in_opencv_frame.emplace_back(normalized.x() * 1000.0, normalized.y() * 1000.0, 1000.0);
    }
  }
  return rays;
}

double MaxDistance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  double max = 0.0;
  for (size_t k = 0; k < a.size(); ++k) max = std::max(max, (a[k] - b[k]).norm());
  return max;
}

std::vector<Eigen::Vector2d> CvProjectPoints(const OpenCvCamera& camera, const std::vector<Eigen::Vector3d>& points) {
  std::vector<cv::Point3d> object;
  for (const auto& p : points) object.emplace_back(p.x(), p.y(), p.z());
  std::vector<double> k = camera.CameraMatrix(), d = camera.DistCoeffs();
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F),
                    cv::Mat(3, 3, CV_64F, k.data()), cv::Mat(1, 5, CV_64F, d.data()), image);
  std::vector<Eigen::Vector2d> out;
  for (const auto& q : image) out.emplace_back(q.x, q.y);
  return out;
}

// The value of "<tag>...</tag>" (first occurrence) in an XML text.
std::string XmlValue(const std::string& xml, const std::string& tag, size_t from = 0) {
  const size_t begin = xml.find("<" + tag + ">", from);
  if (begin == std::string::npos) return "";
  const size_t start = begin + tag.size() + 2;
  return xml.substr(start, xml.find("</" + tag + ">", start) - start);
}

std::vector<double> Numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

// ---------------------------------------------------------------------------
// OpenCV

TEST(CameraExportOpenCv, PureBrownRadialDecenteringFitIsSmallAndAgreesWithProjectPoints) {
  const CameraDefinition camera = BrownAffineCamera(3.0e-7, -2.0e-7, 0.0, 0.0);
  const CameraExportOptions options = ScanOptions();
  const CameraExportSource source = CameraExportSourceFromDefinition(camera);
  CameraExportReport report;
  const OpenCvCamera cv = FitOpenCvCamera(source, options, &report);

  // The linear part is the camera's: fx = fy = c / pixel, (cx, cy) the principal
  // point with rows downward from the image centre (5999.5, 5999.5).
  EXPECT_NEAR(cv.fx_px, 15326.0, 1e-6);
  EXPECT_NEAR(cv.fy_px, 15326.0, 1e-6);
  EXPECT_NEAR(cv.cx_px, 5999.5 + 1.2, 1e-9);
  EXPECT_NEAR(cv.cy_px, 5999.5 + 2.1, 1e-9);
  // First order, the distortion form is minus the correction; on normalized
  // coordinates with rows downward (y' = -y / c): k1 = -k1 c^2, OpenCV's
  // p1 = Brown's p2 c and OpenCV's p2 = -Brown's p1 c.
  EXPECT_NEAR(cv.k1, -4.0e-8 * 153.26 * 153.26, 2e-5);
  EXPECT_NEAR(cv.p2, -3.0e-7 * 153.26, 2e-6);
  EXPECT_NEAR(cv.p1, -2.0e-7 * 153.26, 2e-6);

  // Not exact: correction form (platemeter) against distortion form (OpenCV).
  EXPECT_FALSE(report.exact);
  // Measured: RMS 3.3e-5 px (0.3 nm), max 2.1e-4 px at 10 um pixels.
  EXPECT_LT(report.rms_residual_px, 2e-4);
  EXPECT_LT(report.max_residual_px, 1e-3);
  EXPECT_EQ(report.samples, 41 * 41);
  std::cout << "[ OpenCV, pure Brown ] " << report.Summary() << "\n";

  const Rays rays = RaysOverFormat(source, options);
  const double stated = report.max_residual_px * 1.05 + 1e-9;
  EXPECT_LE(MaxDistance(ProjectWithOpenCv(cv, rays.in_opencv_frame), rays.platemeter_px), stated);
  EXPECT_LE(MaxDistance(CvProjectPoints(cv, rays.in_opencv_frame), rays.platemeter_px), stated);
  if (OpenCvProjectionAvailable()) {
    EXPECT_EQ(report.projected_with, "cv::projectPoints");
  }
}

TEST(CameraExportOpenCv, AffinityGoesIntoFocalLengthsAndSkewIntoTheResidual) {
  const double b1 = 1.0e-4, b2 = -5.0e-5;
  const CameraExportSource source =
      CameraExportSourceFromDefinition(BrownAffineCamera(3.0e-7, -2.0e-7, b1, b2));
  const CameraExportOptions options = ScanOptions();
  CameraExportReport report;
  const OpenCvCamera cv = FitOpenCvCamera(source, options, &report);
  // ideal x = (1 + b1) measured x + ...: the measured scale in x is 1 / (1 + b1).
  EXPECT_NEAR(cv.fx_px, 15326.0 / (1.0 + b1), 1e-6);
  EXPECT_NEAR(cv.fy_px, 15326.0, 1e-6);
  // The non-orthogonality b2 y (up to 2.9 um at the format's edge) cannot be held
  // by OpenCV's skew-free projection: it is in the stated residual.
  EXPECT_GT(report.max_residual_um, 1.0);
  EXPECT_LT(report.max_residual_um, std::abs(b2) * 57.15e3 * 1.01);
  EXPECT_NE(report.why_not_exact.find("skew"), std::string::npos);
  std::cout << "[ OpenCV, b1 b2 ] " << report.Summary() << "\n";

  const Rays rays = RaysOverFormat(source, options);
  EXPECT_LE(MaxDistance(ProjectWithOpenCv(cv, rays.in_opencv_frame), rays.platemeter_px),
            report.max_residual_px * 1.05 + 1e-9);
}

TEST(CameraExportOpenCv, DistortionFreeCameraIsExact) {
  CameraDefinition camera = BrownAffineCamera(0, 0, 0, 0);
  camera.lens->model = "none";
  camera.lens->coefficients.clear();
  CameraExportReport report;
  const std::string yaml = ExportCamera(camera, CameraExportFormat::kOpenCv, ScanOptions(), &report);
  EXPECT_TRUE(report.exact) << report.Summary();
  EXPECT_LT(report.max_residual_px, 1e-8);
  EXPECT_EQ(yaml.rfind("%YAML:1.0\n---\n", 0), 0u);
  // The matrices as cv::FileStorage writes them, with K by hand: c / pixel =
  // 15326 px, (cx, cy) = image centre 5999.5 + (xp, -yp) / pixel.
  auto data = [&](const std::string& name) {
    const size_t at = yaml.find(name + ": !!opencv-matrix\n");
    EXPECT_NE(at, std::string::npos) << yaml;
    const size_t open = yaml.find("data: [ ", at), close = yaml.find(" ]", open);
    std::string values = yaml.substr(open + 8, close - open - 8);
    for (char& ch : values) ch = ch == ',' ? ' ' : ch;
    return Numbers(values);
  };
  const std::vector<double> k = data("camera_matrix");
  const std::vector<double> expected = {15326.0, 0.0, 6000.7, 0.0, 15326.0, 6001.6, 0.0, 0.0, 1.0};
  ASSERT_EQ(k.size(), 9u);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(k[i], expected[i], 1e-9) << i;
  const std::vector<double> d = data("distortion_coefficients");
  ASSERT_EQ(d.size(), 5u);
  for (double v : d) EXPECT_NEAR(v, 0.0, 1e-10);  // zero up to the fit's rounding
  EXPECT_NE(yaml.find("   rows: 1\n   cols: 5\n   dt: d\n"), std::string::npos);
  cv::FileStorage storage(yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  ASSERT_TRUE(storage.isOpened());
  cv::Mat camera_matrix, dist_coeffs;
  storage["camera_matrix"] >> camera_matrix;
  storage["distortion_coefficients"] >> dist_coeffs;
  ASSERT_EQ(camera_matrix.rows, 3);
  EXPECT_NEAR(camera_matrix.at<double>(1, 2), 6001.6, 1e-9);
  EXPECT_EQ(dist_coeffs.cols, 5);
  EXPECT_EQ(static_cast<int>(storage["image_width"]), 12000);
}

TEST(CameraExportOpenCv, PixelConventionIsExplicit) {
  // A mirrored scan (rows along +y) with the frame origin at a given pixel.
  const CameraExportSource source =
      CameraExportSourceFromDefinition(BrownAffineCamera(3.0e-7, -2.0e-7, 0.0, 0.0));
  CameraExportOptions options = ScanOptions();
  options.origin_x_px = 6100.25;
  options.origin_y_px = 5900.75;
  options.row_axis = PlateAxis::kPlusY;
  CameraExportReport report;
  const OpenCvCamera cv = FitOpenCvCamera(source, options, &report);
  EXPECT_NEAR(cv.cx_px, 6100.25 + 1.2, 1e-9);
  EXPECT_NEAR(cv.cy_px, 5900.75 - 2.1, 1e-9);  // yp = -0.021 mm, rows along +y
  const Rays rays = RaysOverFormat(source, options);
  EXPECT_LE(MaxDistance(ProjectWithOpenCv(cv, rays.in_opencv_frame), rays.platemeter_px),
            report.max_residual_px * 1.05 + 1e-9);
  // The same residual as the default frame: the convention only relabels pixels.
  CameraExportReport default_report;
  FitOpenCvCamera(source, ScanOptions(), &default_report);
  EXPECT_NEAR(report.rms_residual_px, default_report.rms_residual_px, 1e-9);
  // Without a format in the definition the fit covers the image: 12000 px of 10 um.
  CameraExportSource no_format = source;
  no_format.format_width_mm = no_format.format_height_mm = 0.0;
  CameraExportReport image_report;
  FitOpenCvCamera(no_format, ScanOptions(), &image_report);
  EXPECT_NEAR(image_report.region_width_mm, 120.0, 1e-9);
  EXPECT_NEAR(image_report.region_height_mm, 120.0, 1e-9);
}

// ---------------------------------------------------------------------------
// MicMac

TEST(CameraExportMicMac, XmlIsWellFormedWithTheRequiredElementsAndHandCheckedValues) {
  const CameraDefinition camera = BrownAffineCamera(3.0e-7, -2.0e-7, 1.0e-4, -5.0e-5);
  CameraExportReport report;
  const std::string xml = ExportCamera(camera, CameraExportFormat::kMicMac, ScanOptions(), &report);
  testing::TempDir dir;
  const std::string path = dir.file("AutoCal_test.xml");
  std::ofstream(path) << xml;
  EXPECT_EQ(std::system(("xmllint --noout '" + path + "'").c_str()), 0) << xml;

  for (const char* tag : {"ExportAPERO", "CalibrationInternConique", "KnownConv", "PP", "F", "SzIm",
                          "CalibDistortion", "ModPhgrStd", "RadialePart", "CDist", "CoeffDist", "P1",
                          "P2", "b1", "b2"}) {
    EXPECT_NE(xml.find(std::string("<") + tag + ">"), std::string::npos) << tag;
  }
  EXPECT_EQ(XmlValue(xml, "KnownConv"), "eConvApero_DistM2C");
  // F = c / pixel = 153.26 mm / 0.010 mm; PP = image centre + (xp, -yp) / pixel.
  EXPECT_NEAR(std::stod(XmlValue(xml, "F")), 15326.0, 1e-6);
  const std::vector<double> pp = Numbers(XmlValue(xml, "PP"));
  ASSERT_EQ(pp.size(), 2u);
  EXPECT_NEAR(pp[0], 6000.7, 1e-9);
  EXPECT_NEAR(pp[1], 6001.6, 1e-9);
  EXPECT_EQ(XmlValue(xml, "SzIm"), "12000 12000");
  EXPECT_EQ(Numbers(XmlValue(xml, "CDist")), pp);
  // Three radial coefficients, in 1/px^2, 1/px^4, 1/px^6: k1 pixel^2 to first order, sign flipped.
  size_t at = 0;
  std::vector<double> coeff;
  while ((at = xml.find("<CoeffDist>", at)) != std::string::npos) coeff.push_back(std::stod(XmlValue(xml, "CoeffDist", at++)));
  ASSERT_EQ(coeff.size(), 3u);
  EXPECT_NEAR(coeff[0], -4.0e-8 * 1e-4, 2e-13);
  // The affinity in the distortion direction: measured x scale 1 / (1 + b1) - 1
  // at the centre (the fit trades a little of it against the radial terms).
  EXPECT_NEAR(std::stod(XmlValue(xml, "b1")), 1.0 / (1.0 + 1.0e-4) - 1.0, 1e-7);
  EXPECT_FALSE(report.exact);
  std::cout << "[ MicMac M2C ] " << report.Summary() << "\n";
}

TEST(CameraExportMicMac, M2CAgreesWithMicMacsFormulaWithinTheStatedResidual) {
  const CameraExportSource source =
      CameraExportSourceFromDefinition(BrownAffineCamera(3.0e-7, -2.0e-7, 1.0e-4, -5.0e-5));
  const CameraExportOptions options = ScanOptions();
  CameraExportReport report;
  const std::string xml = ExportCamera(source, CameraExportFormat::kMicMac, options, &report);
  // cDistModStdPhpgr::Direct, written out from the XML's numbers.
  const double f = std::stod(XmlValue(xml, "F"));
  const std::vector<double> pp = Numbers(XmlValue(xml, "PP")), c = Numbers(XmlValue(xml, "CDist"));
  std::vector<double> k;
  for (size_t at = 0; (at = xml.find("<CoeffDist>", at)) != std::string::npos; ++at) k.push_back(std::stod(XmlValue(xml, "CoeffDist", at)));
  const double p1 = std::stod(XmlValue(xml, "P1")), p2 = std::stod(XmlValue(xml, "P2"));
  const double b1 = std::stod(XmlValue(xml, "b1")), b2 = std::stod(XmlValue(xml, "b2"));
  const Rays rays = RaysOverFormat(source, options);
  double max = 0.0;
  for (size_t n = 0; n < rays.in_opencv_frame.size(); ++n) {
    const Eigen::Vector3d& p = rays.in_opencv_frame[n];
    const double ix = pp[0] + f * p.x() / p.z(), iy = pp[1] + f * p.y() / p.z();
    const double dx = ix - c[0], dy = iy - c[1], r2 = dx * dx + dy * dy;
    const double radial = k[0] * r2 + k[1] * r2 * r2 + k[2] * r2 * r2 * r2;
    const double mx = ix + dx * radial + (2 * dx * dx + r2) * p1 + 2 * dx * dy * p2 + b1 * dx + b2 * dy;
    const double my = iy + dy * radial + (2 * dy * dy + r2) * p2 + 2 * dx * dy * p1;
    max = std::max(max, (Eigen::Vector2d(mx, my) - rays.platemeter_px[n]).norm());
  }
  EXPECT_LE(max, report.max_residual_px * 1.05 + 1e-9);
  // The affinity is held (b1, b2 in MicMac's model), so the fit is close: the
  // rest is the inverse of the correction polynomial.
  EXPECT_LT(report.max_residual_px, 1e-2);
}

TEST(CameraExportMicMac, C2MHoldsTheBrownCameraExactly) {
  CameraExportOptions options = ScanOptions();
  options.micmac_convention = MicMacConvention::kCorrectionC2M;
  CameraExportReport report;
  const std::string xml = ExportCamera(BrownAffineCamera(3.0e-7, -2.0e-7, 1.0e-4, -5.0e-5),
                                       CameraExportFormat::kMicMac, options, &report);
  EXPECT_EQ(XmlValue(xml, "KnownConv"), "eConvApero_DistC2M");
  EXPECT_TRUE(report.exact) << report.Summary();
  // Hand conversion to pixels (pixel 0.01 mm, rows downward: y_px = -y_mm / pixel):
  // K1 = k1 pixel^2, P1 = p1 pixel, P2 = -p2 pixel, b1 = b1, b2 = -b2.
  std::vector<double> k;
  for (size_t at = 0; (at = xml.find("<CoeffDist>", at)) != std::string::npos; ++at) k.push_back(std::stod(XmlValue(xml, "CoeffDist", at)));
  ASSERT_EQ(k.size(), 3u);
  EXPECT_NEAR(k[0] / (4.0e-8 * 1e-4), 1.0, 1e-8);
  EXPECT_NEAR(k[1] / (-2.0e-12 * 1e-8), 1.0, 1e-7);
  EXPECT_NEAR(std::stod(XmlValue(xml, "P1")) / (3.0e-7 * 0.01), 1.0, 1e-8);
  EXPECT_NEAR(std::stod(XmlValue(xml, "P2")) / (2.0e-7 * 0.01), 1.0, 1e-8);
  EXPECT_NEAR(std::stod(XmlValue(xml, "b1")), 1.0e-4, 1e-12);
  EXPECT_NEAR(std::stod(XmlValue(xml, "b2")), 5.0e-5, 1e-12);
  EXPECT_NEAR(std::stod(XmlValue(xml, "F")), 15326.0, 1e-6);
}

TEST(CameraExportMicMac, RadialCameraUsesModRad) {
  CameraExportOptions options = ScanOptions();
  options.micmac_convention = MicMacConvention::kCorrectionC2M;
  CameraExportReport report;
  const std::string xml =
      ExportCamera(BrownAffineCamera(0, 0, 0, 0), CameraExportFormat::kMicMac, options, &report);
  EXPECT_NE(xml.find("<ModRad>"), std::string::npos);
  EXPECT_EQ(xml.find("<ModPhgrStd>"), std::string::npos);
  EXPECT_TRUE(report.exact) << report.Summary();
  testing::TempDir dir;
  std::ofstream(dir.file("radial.xml")) << xml;
  EXPECT_EQ(std::system(("xmllint --noout '" + dir.file("radial.xml") + "'").c_str()), 0);
}

// ---------------------------------------------------------------------------
// ASP .tsai

// "name = value" lines of a .tsai as numbers (the header lines as given).
std::map<std::string, std::vector<double>> TsaiValues(const std::string& text) {
  std::map<std::string, std::vector<double>> values;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const size_t eq = line.find(" = ");
    if (eq != std::string::npos) values[line.substr(0, eq)] = Numbers(line.substr(eq + 3));
  }
  return values;
}

TEST(CameraExportAsp, TsaiTextMatchesAHandComputedExample) {
  // c = 100 mm, (xp, yp) = (0.1, -0.2) mm, 10 um pixels, 8001 x 6001 px: the
  // frame origin at pixel (4000, 3000), rows downward.
  CameraDefinition camera;
  camera.name = "hand";
  camera.format_width_mm = 80.0;
  camera.format_height_mm = 60.0;
  LensCalibration lens;
  lens.model = "brown-affine";
  lens.principal_distance_mm = 100.0;
  lens.principal_point_x_mm = 0.1;
  lens.principal_point_y_mm = -0.2;
  lens.coefficients = {{"k1_per_mm2", 1e-6}, {"k2_per_mm4", 1e-10}, {"k3_per_mm6", 0.0},
                       {"p1_per_mm", 2e-6},  {"p2_per_mm", 1e-6},   {"b1", 0.0}, {"b2", 0.0}};
  camera.lens = lens;
  CameraExportOptions options;
  options.pixel_size_um = 10.0;
  options.image_width_px = 8001;
  options.image_height_px = 6001;
  CameraExportReport report;
  const std::string tsai = ExportCamera(camera, CameraExportFormat::kAspTsai, options, &report);

  // By hand, in metres (pitch 1e-5 m):
  //   fu = fv = c = 0.1;  cu = (4000 + 0.1 / 0.01) * 1e-5 = 0.0401;
  //   cv = (3000 + 0.2 / 0.01) * 1e-5 = 0.0302;
  //   Photometrix is the same correction form: K1 = k1 * 1e6 = 1 /m^2,
  //   K2 = k2 * 1e12 = 100 /m^4, P1 = p1 * 1e3 = 2e-3 /m, P2 = -p2 * 1e3 = -1e-3 /m
  //   (rows downward flip y), xp = yp = 0 (distortion about the principal point).
  // Fixed lines exactly; numbers to the tolerance given. The coefficients come
  // from the least-squares fit, which reproduces the exact conversion to ~1e-8
  // relative (the conditioning of r^2, r^4, r^6 over the format times the
  // rounding of the displacements); the projection to 1e-8 px.
  struct Line {
    std::string text;  // the whole line, or "name = " for a number
    double value = 0.0, tolerance = 0.0;
  };
  const std::vector<Line> expected = {
      {"VERSION_4"}, {"PINHOLE"}, {"fu = ", 0.1, 1e-13}, {"fv = ", 0.1, 1e-13},
      {"cu = ", 0.0401, 1e-15}, {"cv = ", 0.0302, 1e-15}, {"u_direction = 1 0 0"},
      {"v_direction = 0 1 0"}, {"w_direction = 0 0 1"}, {"C = 0 0 0"},
      {"R = 1 0 0 0 1 0 0 0 1"}, {"pitch = 1e-05"}, {"Photometrix"}, {"xp = ", 0.0, 1e-15},
      {"yp = ", 0.0, 1e-15}, {"k1 = ", 1.0, 1e-7}, {"k2 = ", 100.0, 1e-4},
      {"k3 = ", 0.0, 1e-2},  // 1e-2 /m^6 moves the format's corner by 1e-11 m
      {"p1 = ", 0.002, 1e-12}, {"p2 = ", -0.001, 1e-12}, {"b1 = 0.0"}, {"b2 = 0.0"}};
  std::istringstream got(tsai);
  std::string line;
  for (const Line& want : expected) {
    ASSERT_TRUE(std::getline(got, line)) << tsai;
    if (want.text.back() != ' ') {
      EXPECT_EQ(line, want.text);
      continue;
    }
    ASSERT_EQ(line.substr(0, want.text.size()), want.text) << tsai;
    const double value = std::stod(line.substr(want.text.size()));
    EXPECT_NEAR(value, want.value, want.tolerance) << line;
  }
  EXPECT_FALSE(std::getline(got, line)) << "extra line: " << line;
  EXPECT_TRUE(report.exact) << report.Summary();
  EXPECT_NE(report.target_model.find("Photometrix"), std::string::npos);
}

TEST(CameraExportAsp, TsaiBlockCarriesTheOpenCvCoefficients) {
  const CameraExportSource source =
      CameraExportSourceFromDefinition(BrownAffineCamera(3.0e-7, -2.0e-7, 0.0, 0.0));
  CameraExportOptions options = ScanOptions();
  options.asp_distortion = AspDistortion::kTsai;
  CameraExportReport asp_report, cv_report;
  const std::string tsai = ExportCamera(source, CameraExportFormat::kAspTsai, options, &asp_report);
  const OpenCvCamera cv = FitOpenCvCamera(source, options, &cv_report);
  const auto values = TsaiValues(tsai);
  EXPECT_NE(tsai.find("\nTSAI\nk1 = "), std::string::npos);
  EXPECT_NEAR(values.at("fu")[0], cv.fx_px * 1e-5, 1e-15);
  EXPECT_NEAR(values.at("cv")[0], cv.cy_px * 1e-5, 1e-15);
  EXPECT_EQ(values.at("k1")[0], cv.k1);
  EXPECT_EQ(values.at("p1")[0], cv.p1);
  EXPECT_EQ(values.at("p2")[0], cv.p2);
  EXPECT_EQ(values.at("k3")[0], cv.k3);
  EXPECT_EQ(asp_report.max_residual_px, cv_report.max_residual_px);
  // Auto prefers the exact Photometrix block for a Brown camera.
  options.asp_distortion = AspDistortion::kAuto;
  CameraExportReport auto_report;
  const AspPinhole chosen = FitAspPinhole(source, options, &auto_report);
  EXPECT_EQ(chosen.distortion, AspDistortion::kPhotometrix);
  EXPECT_TRUE(auto_report.exact) << auto_report.Summary();
}

// ---------------------------------------------------------------------------
// Bad input and every lens model

TEST(CameraExport, BadInputThrowsWithAOneLineReason) {
  CameraDefinition camera = BrownAffineCamera(0, 0, 0, 0);
  auto expect_error = [](const std::function<void()>& call, const std::string& words) {
    try {
      call();
      ADD_FAILURE() << "no error; expected: " << words;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
      EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos) << error.what();
    }
  };
  CameraExportOptions options = ScanOptions();
  options.pixel_size_um = 0.0;
  expect_error([&] { ExportCamera(camera, CameraExportFormat::kOpenCv, options); }, "pixel size");
  options.pixel_size_um = -5.0;
  expect_error([&] { ExportCamera(camera, CameraExportFormat::kMicMac, options); }, "pixel size");
  options = ScanOptions();
  options.image_height_px = 0;
  expect_error([&] { ExportCamera(camera, CameraExportFormat::kAspTsai, options); }, "image size");
  options = ScanOptions();
  options.row_axis = PlateAxis::kMinusX;
  expect_error([&] { ExportCamera(camera, CameraExportFormat::kOpenCv, options); }, "perpendicular");
  CameraDefinition no_lens = camera;
  no_lens.lens.reset();
  expect_error([&] { ExportCamera(no_lens, CameraExportFormat::kOpenCv, ScanOptions()); },
               "test-brown-affine: has no lens calibration");
  CameraDefinition bad_lens = camera;
  bad_lens.lens->model = "polynomial-7";
  expect_error([&] { ExportCamera(bad_lens, CameraExportFormat::kOpenCv, ScanOptions()); },
               "unknown lens model");
  std::string why;
  EXPECT_TRUE(ScanOptions().Check(&why)) << why;
}

TEST(CameraExport, EveryBuiltInLensModelExportsToEveryFormat) {
  const DefinitionRegistry registry;
  for (const std::string& name : registry.CameraNames()) {
    const CameraDefinition& camera = registry.Camera(name);
    if (!camera.lens) continue;
    CameraExportOptions options;
    options.pixel_size_um = 12.5;
    options.image_width_px = static_cast<int>(camera.format_width_mm / 0.0125) + 400;
    options.image_height_px = static_cast<int>(camera.format_height_mm / 0.0125) + 400;
    options.fit_grid_points_per_side = 21;
    for (CameraExportFormat format :
         {CameraExportFormat::kOpenCv, CameraExportFormat::kMicMac, CameraExportFormat::kAspTsai}) {
      CameraExportReport report;
      const std::string text = ExportCamera(camera, format, options, &report);
      EXPECT_FALSE(text.empty());
      EXPECT_TRUE(std::isfinite(report.max_residual_px)) << name << ": " << report.Summary();
      EXPECT_EQ(report.source_model, camera.lens->model);
      std::cout << "[ " << name << " ] " << report.Summary() << "\n";
    }
    // The OpenCV camera projects the camera's rays within the stated residual.
    const CameraExportSource source = CameraExportSourceFromDefinition(camera);
    CameraExportReport report;
    const OpenCvCamera cv = FitOpenCvCamera(source, options, &report);
    const Rays rays = RaysOverFormat(source, options);
    EXPECT_LE(MaxDistance(ProjectWithOpenCv(cv, rays.in_opencv_frame), rays.platemeter_px),
              report.max_residual_px * 1.05 + 1e-9)
        << name;
  }
}

}  // namespace
}  // namespace platemeter
