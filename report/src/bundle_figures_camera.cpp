// The inner cone's figures of the bundle's HTML report: the correlation heat
// map, the balanced radial and decentering profiles with one-sigma envelopes,
// and the distortion vector field over the format.
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "bundle_figures.h"
#include "platemeter/core/error.h"
#include "platemeter/report/heatmap_plot.h"
#include "platemeter/report/profile_plot.h"
#include "platemeter/report/vector_plot.h"

namespace platemeter::report {
namespace {

// The balanced correction (radial k0'..k3' and decentering lambda p1, lambda
// p2: the profiles' lens, the affinity left out) at (x, y) from the principal point, um.
PlotVector BalancedCorrection(const DistortionProfile& profile, const BundleCameraResult& camera, double x_mm,
                              double y_mm) {
  const double xb = x_mm - camera.values[1], yb = y_mm - camera.values[2];
  const double r2 = xb * xb + yb * yb;
  const auto& k = profile.radial_coefficients;
  const double radial = k[0].value + r2 * (k[1].value + r2 * (k[2].value + r2 * k[3].value));
  const double p1 = profile.scale * camera.values[6], p2 = profile.scale * camera.values[7];
  const double dx = xb * radial + p1 * (r2 + 2 * xb * xb) + 2 * p2 * xb * yb;
  const double dy = yb * radial + 2 * p1 * xb * yb + p2 * (r2 + 2 * yb * yb);
  return {x_mm, y_mm, 1e3 * dx, 1e3 * dy};
}

Figure FieldFigure(const DistortionProfile& profile, const BundleCameraResult& camera, const std::string& balance) {
  const double w = camera.format_width_mm > 0 ? camera.format_width_mm : 1.0;
  const double h = camera.format_height_mm > 0 ? camera.format_height_mm : 1.0;
  VectorPanel panel;
  panel.title = "camera " + camera.name;
  const int n = 15;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      panel.vectors.push_back(BalancedCorrection(profile, camera, -w / 2 + w * (i + 0.5) / n, -h / 2 + h * (j + 0.5) / n));
    }
  }
  VectorPlotOptions o;
  o.title = "Distortion correction over the format, camera " + camera.name;
  o.vector_words = "correction";
  o.x_mm = {-w / 2, w / 2};
  o.y_mm = {-h / 2, h / 2};
  const VectorPlot plot = DrawVectorPlot({panel}, o);
  return {"distortion-field-" + Slug(camera.name),
          fmt::format("The correction added to measured coordinates (radial {}, plus decentering), on a {} x {} grid "
                      "over the {:.1f} x {:.1f} mm format; the affinity b1, b2 (the image frame's) is left out.",
                      balance, n, n, w, h),
          plot.files};
}

std::vector<double> Radii(const BundleCameraResult& camera, int samples) {
  const double corner = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  std::vector<double> radii;
  for (int i = 0; i <= samples; ++i) radii.push_back((corner > 0 ? corner : 1.0) * i / samples);
  return radii;
}

}  // namespace

FigureSection CorrelationFigures(const BundleResult& result) {
  FigureSection section{"correlations", "Correlations of the inner cone", {}, {}};
  for (const BundleCameraResult& camera : result.cameras) {
    std::vector<std::string> names;
    const std::vector<int> adjusted = AdjustedCameraParameters(camera, &names);
    if (adjusted.empty()) continue;
    const Eigen::MatrixXd r = result.adjustment.Correlation(adjusted);
    std::vector<std::vector<double>> matrix(r.rows(), std::vector<double>(r.cols()));
    for (int i = 0; i < r.rows(); ++i) {
      for (int k = 0; k < r.cols(); ++k) matrix[i][k] = r(i, k);
    }
    HeatmapPlotOptions o;
    o.title = "Correlations of the adjusted inner cone, camera " + camera.name;
    const HeatmapPlot plot = DrawHeatmap(matrix, names, o);
    section.figures.push_back({"correlation-" + Slug(camera.name),
                               "The correlation matrix of the camera's adjusted parameters (the table above), "
                               "blue -1 through white 0 to red +1.",
                               plot.files});
  }
  return section;
}

FigureSection DistortionFigures(const BundleResult& result, const BundleReportOptions& report_options,
                                const BundleHtmlOptions& options) {
  FigureSection section{"distortion", "Distortion", {}, {}};
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    const BundleCameraResult& camera = result.cameras[c];
    DistortionProfile profile;
    try {
      profile = BundleDistortionProfile(result, static_cast<int>(c), report_options,
                                        Radii(camera, std::max(2, options.profile_samples)));
    } catch (const Error& e) {
      section.notes.push_back("camera " + camera.name + ": no distortion profile: " + e.reason());
      continue;
    }
    const std::string balance = BundleBalanceWords(result, static_cast<int>(c), report_options);
    ProfileSeries radial{"δ'r, " + balance, {}, {}, {}, 0x1f4e9a};
    ProfileSeries decentering{"Pr (decentering)", {}, {}, {}, 0xc0392b};
    for (const DistortionProfileRow& row : profile.rows) {
      for (const auto& [s, v, sigma] : {std::tuple{&radial, row.radial_um, row.radial_sigma_um},
                                  std::tuple{&decentering, row.decentering_um, row.decentering_sigma_um}}) {
        s->x.push_back(row.r_mm);
        s->value.push_back(v);
        s->sigma.push_back(sigma);
      }
    }
    for (const auto& [series, stem, what] : {std::tuple{&radial, "profile-radial-", "balanced symmetric radial distortion δ'r"},
                                             std::tuple{&decentering, "profile-decentering-", "decentering profile Pr"}}) {
      ProfilePlotOptions o;
      o.title = fmt::format("The {}, camera {}", what, camera.name);
      o.y_label = std::string(what).ends_with("Pr") ? "Pr (µm)" : "δ'r (µm)";
      const ProfilePlot plot = DrawProfilePlot({*series}, o);
      section.figures.push_back({stem + Slug(camera.name),
                                 fmt::format("The {} (seed 000 eqs. 14, 15) from the centre to the format's corner, "
                                             "the band one sigma propagated through the full covariance of the inner "
                                             "cone.",
                                             what),
                                 plot.files});
    }
    section.figures.push_back(FieldFigure(profile, camera, balance));
  }
  return section;
}

}  // namespace platemeter::report
