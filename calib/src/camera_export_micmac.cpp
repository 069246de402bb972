// The MicMac export: ExportAPERO / CalibrationInternConique with one
// CalibDistortion (ModPhgrStd, or ModRad for a radial camera), in pixels
// (camera_export.h has the formulas and directions).
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "platemeter/calib/camera_export.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

using camera_export_detail::CameraGeometry;
using camera_export_detail::FormatDouble;

// MicMac's displacement D(p) - p at u = p - CDist (cDistModStdPhpgr::Direct).
Eigen::Vector2d MicMacDisplacement(const MicMacCalibration& m, const Eigen::Vector2d& u) {
  const double r2 = u.squaredNorm();
  const double radial = r2 * (m.coeff_dist[0] + r2 * (m.coeff_dist[1] + r2 * m.coeff_dist[2]));
  return {u.x() * radial + m.p1 * (r2 + 2.0 * u.x() * u.x()) + 2.0 * m.p2 * u.x() * u.y() +
              m.b1 * u.x() + m.b2 * u.y(),
          u.y() * radial + 2.0 * m.p1 * u.x() * u.y() + m.p2 * (r2 + 2.0 * u.y() * u.y())};
}

// The basis of D(p) - p at u, one column per coefficient: K1, K2, K3, then
// P1, P2, then b1, b2, as many as `rows` has columns (3, 5 or 7).
void MicMacBasis(const Eigen::Vector2d& u, Eigen::Ref<Eigen::MatrixXd> rows) {
  const double x = u.x(), y = u.y(), r2 = u.squaredNorm();
  rows.col(0) << x * r2, y * r2;
  rows.col(1) << x * r2 * r2, y * r2 * r2;
  rows.col(2) << x * r2 * r2 * r2, y * r2 * r2 * r2;
  if (rows.cols() == 3) return;
  rows.col(3) << r2 + 2.0 * x * x, 2.0 * x * y;
  rows.col(4) << 2.0 * x * y, r2 + 2.0 * y * y;
  if (rows.cols() == 5) return;
  rows.col(5) << x, 0.0;
  rows.col(6) << y, 0.0;
}

}  // namespace

MicMacCalibration FitMicMacCalibration(const CameraExportSource& source,
                                       const CameraExportOptions& options,
                                       CameraExportReport* report) {
  const CameraGeometry g = camera_export_detail::DescribeCamera(source, options);
  MicMacCalibration m;
  m.convention = options.micmac_convention;
  m.radial_only = g.radial_only;
  m.image_width_px = options.image_width_px;
  m.image_height_px = options.image_height_px;
  m.pp_x_px = g.principal_point_px.x();
  m.pp_y_px = g.principal_point_px.y();
  m.cdist_x_px = g.distortion_centre_px.x();
  m.cdist_y_px = g.distortion_centre_px.y();
  const Eigen::Vector2d pp = g.principal_point_px, cdist = g.distortion_centre_px;
  const bool m2c = m.convention == MicMacConvention::kDistortionM2C;
  // One F for both axes: the row direction's scale; b1, b2 carry the rest of
  // the linear part (only in x, as MicMac's affinity is written).
  m.f_px = m2c ? g.focal_px * g.jacobian(1, 1) : g.focal_px / g.jacobian.inverse()(1, 1);

  // M2C: measured - ideal = basis(ideal - CDist) theta;
  // C2M: ideal - measured = basis(measured - CDist) theta, ideal = PP + F (x', y').
  // Fit only what the camera has: P1, P2 unless it is radial, b1, b2 only if its
  // linear part is not a plain scale (an affinity), so that no spurious affinity
  // or decentering absorbs the higher-order terms.
  const Eigen::Matrix2d& j = g.jacobian;
  const bool affinity = std::abs(j(0, 1)) > 1e-12 || std::abs(j(1, 0)) > 1e-12 ||
                        std::abs(j(0, 0) - j(1, 1)) > 1e-12;
  const int n = static_cast<int>(g.samples.size());
  const int columns = m.radial_only ? 3 : (affinity ? 7 : 5);
  Eigen::MatrixXd design(2 * n, columns);
  Eigen::VectorXd target(2 * n);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d ideal = pp + m.f_px * g.samples[k].normalized;
    const Eigen::Vector2d& measured = g.samples[k].measured_px;
    MicMacBasis((m2c ? ideal : measured) - cdist, design.middleRows(2 * k, 2));
    target.segment<2>(2 * k) = m2c ? Eigen::Vector2d(measured - ideal) : Eigen::Vector2d(ideal - measured);
  }
  const Eigen::VectorXd theta = camera_export_detail::SolveLinearLeastSquares(design, target);
  for (int k = 0; k < 3; ++k) m.coeff_dist[k] = theta(k);
  if (columns >= 5) {
    m.p1 = theta(3);
    m.p2 = theta(4);
  }
  if (columns == 7) {
    m.b1 = theta(5);
    m.b2 = theta(6);
  }

  if (report != nullptr) {
    report->format = CameraExportFormat::kMicMac;
    report->target_model = fmt::format("MicMac {}, {}", m.radial_only ? "ModRad" : "ModPhgrStd",
                                       m2c ? "eConvApero_DistM2C" : "eConvApero_DistC2M");
    report->source_model = source.lens_model;
    report->projected_with = "MicMac's formula (cDistModStdPhpgr::Direct)";
    std::vector<Eigen::Vector2d> projected;
    projected.reserve(n);
    const double step = 1e-3;  // px
    for (const auto& s : g.samples) {
      const Eigen::Vector2d ideal = pp + m.f_px * s.normalized;
      if (m2c) {
        projected.push_back(ideal + MicMacDisplacement(m, ideal - cdist));
      } else {
        Eigen::Vector2d measured;
        const bool ok = camera_export_detail::InvertCorrection(
            [&](const Eigen::Vector2d& p) { return MicMacDisplacement(m, p - cdist); }, ideal, step,
            &measured);
        projected.push_back(ok ? measured : Eigen::Vector2d::Constant(std::nan("")));
      }
    }
    camera_export_detail::FillResiduals(g, projected, options, report);
    if (!report->exact) {
      const DistortionModelId id = source.model.model();
      if (id == DistortionModelId::kSlama) {
        report->why_not_exact =
            m2c ? "Seed 001's decentering profile K4 + K5 d^2 is beyond MicMac's constant P1, P2, "
                  "so the coefficients are fitted."
                : "Seed 001's model is in distortion form (eConvApero_DistM2C is the closer "
                  "convention) with a decentering profile K4 + K5 d^2 beyond MicMac's constant "
                  "P1, P2, so the coefficients are fitted.";
      } else if (m2c) {
        report->why_not_exact =
            "The camera's model is in correction form (ideal = measured + d(measured)), "
            "eConvApero_DistM2C in distortion form (measured = ideal + d(ideal)); the inverse of "
            "the correction polynomial is not a polynomial, so the coefficients are fitted "
            "(eConvApero_DistC2M holds a Brown camera exactly).";
      } else {
        report->why_not_exact =
            "The camera's decentering profile (seed 004's J2 r^4) or its affinity in the row "
            "direction is beyond MicMac's constant P1, P2 and b1, b2 in x, so the coefficients "
            "are fitted.";
      }
    }
  }
  return m;
}

std::string FormatMicMacXml(const MicMacCalibration& m, const CameraExportReport& report) {
  const bool m2c = m.convention == MicMacConvention::kDistortionM2C;
  std::string x = "<?xml version=\"1.0\" ?>\n<ExportAPERO>\n";
  std::string summary = report.Summary();
  // "--" may not appear inside an XML comment.
  for (size_t at = summary.find("--"); at != std::string::npos; at = summary.find("--", at)) {
    summary.replace(at, 2, "- ");
  }
  x += "     <!-- platemeter camera export. Pixels: x = column, y = row, the centre of the top-left "
       "pixel at (0, 0). " +
       summary + " -->\n";
  x += "     <CalibrationInternConique>\n";
  x += fmt::format("          <KnownConv>{}</KnownConv>\n",
                   m2c ? "eConvApero_DistM2C" : "eConvApero_DistC2M");
  x += fmt::format("          <PP>{} {}</PP>\n", FormatDouble(m.pp_x_px), FormatDouble(m.pp_y_px));
  x += fmt::format("          <F>{}</F>\n", FormatDouble(m.f_px));
  x += fmt::format("          <SzIm>{} {}</SzIm>\n", m.image_width_px, m.image_height_px);
  x += "          <CalibDistortion>\n";
  auto radial_lines = [&](const std::string& indent) {
    std::string lines = fmt::format("{}<CDist>{} {}</CDist>\n", indent, FormatDouble(m.cdist_x_px),
                                    FormatDouble(m.cdist_y_px));
    for (double k : m.coeff_dist) {
      lines += fmt::format("{}<CoeffDist>{}</CoeffDist>\n", indent, FormatDouble(k));
    }
    return lines;
  };
  if (m.radial_only) {
    x += "               <ModRad>\n" + radial_lines(std::string(20, ' ')) + "               </ModRad>\n";
  } else {
    x += "               <ModPhgrStd>\n";
    x += "                    <RadialePart>\n";
    x += radial_lines(std::string(25, ' '));
    x += "                    </RadialePart>\n";
    x += fmt::format("                    <P1>{}</P1>\n", FormatDouble(m.p1));
    x += fmt::format("                    <P2>{}</P2>\n", FormatDouble(m.p2));
    x += fmt::format("                    <b1>{}</b1>\n", FormatDouble(m.b1));
    x += fmt::format("                    <b2>{}</b2>\n", FormatDouble(m.b2));
    x += "               </ModPhgrStd>\n";
  }
  x += "          </CalibDistortion>\n";
  x += "     </CalibrationInternConique>\n</ExportAPERO>\n";
  return x;
}

}  // namespace platemeter
