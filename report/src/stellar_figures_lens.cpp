// The lens figures of the stellar calibration's HTML report (seed 001 Table 4,
// Figs. 6-9): the distortion fields (total, radial symmetric, decentering) with
// the axis of maximum tangential distortion through the point of symmetry, and
// the profile curves with their one-sigma envelopes, for every plate and
// every combination.
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "platemeter/calib/distortion_profile.h"
#include "platemeter/calib/stellar_distortion.h"
#include "platemeter/report/profile_plot.h"
#include "stellar_figures.h"

namespace platemeter::report {
namespace {

constexpr unsigned kPlatePalette[] = {0x1f4e9a, 0xc0392b, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0x17becf, 0x7f7f7f};

// A solution whose lens is plotted: a plate's or a combination's.
struct Solution {
  std::string who;    // "plate 1320", "combination f/3.5"
  std::string stem;   // file-name part
  int camera = 0;
  StellarLensEstimate lens;
};

std::vector<Solution> Solutions(const StellarReportContext& c) {
  std::vector<Solution> out;
  const DistortionModelId model = c.job.options.lens_model;
  for (size_t i = 0; i < c.result.singles.size(); ++i) {
    const StellarPlateResult& s = c.result.singles[i];
    out.push_back({"plate " + s.plate_id, "plate-" + Slug(s.plate_id),
                   i < c.job.plates.size() ? c.job.plates[i].camera : 0, PlateLensEstimate(s, model)});
  }
  for (size_t k = 0; k < c.result.combinations.size(); ++k) {
    const StellarCombination& combination = c.result.combinations[k];
    out.push_back({"combination " + combination.name, "combination-" + Slug(combination.name),
                   k < c.result.combination_camera.size() ? c.result.combination_camera[k] : 0,
                   CombinationLensEstimate(combination, model)});
  }
  return out;
}

// The axis through the point of symmetry, across the whole area shown.
PlotLine AxisLine(const StellarSymmetry& s, const AxisRange& x, const AxisRange& y) {
  const double reach = std::hypot(x.max - x.min, y.max - y.min);
  const double ux = std::cos(s.axis_rad), uy = std::sin(s.axis_rad);
  return {s.x_mm - reach * ux, s.y_mm - reach * uy, s.x_mm + reach * ux, s.y_mm + reach * uy, true, 0x000000};
}

Figure FieldFigure(const StellarReportContext& c, const Solution& solution) {
  const AxisRange& x = c.x_mm[solution.camera];
  const AxisRange& y = c.y_mm[solution.camera];
  const StellarSymmetry symmetry = StellarSymmetryOf(solution.lens);
  std::vector<VectorPanel> panels;
  const int n = c.options.field_grid;
  for (StellarLensPart part : {StellarLensPart::kTotal, StellarLensPart::kRadial, StellarLensPart::kDecentering}) {
    VectorPanel& panel = panels.emplace_back();
    panel.title = StellarLensPartName(part);
    panel.labels = c.corner_labels[solution.camera];
    panel.markers.push_back({symmetry.x_mm, symmetry.y_mm, 0x000000});
    if (symmetry.has_decentering) panel.lines.push_back(AxisLine(symmetry, x, y));
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double px = x.min + (x.max - x.min) * (i + 0.5) / n, py = y.min + (y.max - y.min) * (j + 0.5) / n;
        const Eigen::Vector2d d = StellarDistortion_um(solution.lens, part, px, py);
        panel.vectors.push_back({px, py, d.x(), d.y()});
      }
    }
  }
  VectorPlotOptions o;
  o.title = "Systematic lens distortion, " + solution.who;
  o.vector_words = "distortion";
  o.x_mm = x;
  o.y_mm = y;
  o.columns = 3;
  o.panel_px = 380;
  const VectorPlot plot = DrawVectorPlot(panels, o);
  return {"distortion-" + solution.stem,
          fmt::format("The math model of the total systematic distortion of {} and its radial symmetric and "
                      "decentering components on a {} x {} grid (the displacement of the measured image from the "
                      "true one, one scale: {:g} µm bar). The dot is the point of symmetry ({:.3f}, {:.3f}) mm; the "
                      "dashed line the axis of maximum tangential distortion through it, at {:.1f} deg from +x{}.",
                      solution.who, n, n, plot.scale_bar_um, symmetry.x_mm, symmetry.y_mm,
                      symmetry.axis_rad * 180 / M_PI,
                      c.job.options.lens_model == DistortionModelId::kSlama
                          ? " (Phi_T + 90 deg in the plate frame: the model's tangential component is largest there)"
                          : ""),
          plot.files};
}

double MaxDistance(const StellarReportContext& c, int camera) {
  const CameraDefinition& d = c.job.cameras[camera];
  const double corner = FormatHalfDiagonal_mm(d.format_width_mm, d.format_height_mm);
  return corner > 0 ? corner : std::hypot(c.x_mm[camera].max, c.y_mm[camera].max);
}

}  // namespace

FigureSection StellarDistortionFigures(const StellarReportContext& c) {
  FigureSection section{"distortion", "Systematic lens distortion", {}, {}};
  for (const Solution& s : Solutions(c)) section.figures.push_back(FieldFigure(c, s));
  return section;
}

FigureSection StellarProfileFigures(const StellarReportContext& c) {
  FigureSection section{"profiles", "Distortion profiles", {}, {}};
  const std::vector<Solution> solutions = Solutions(c);
  // One plot per kind and per set (the plates; the combinations), each solution a curve with its envelope.
  for (bool combinations : {false, true}) {
    std::vector<ProfileSeries> radial, transformed, decentering;
    std::string focal_lengths;
    for (const Solution& s : solutions) {
      if (s.who.starts_with("combination") != combinations) continue;
      const unsigned rgb = kPlatePalette[radial.size() % std::size(kPlatePalette)];
      const StellarProfile p = ComputeStellarProfile(s.lens, MaxDistance(c, s.camera), c.options.profile_samples);
      for (auto* series : {&radial, &transformed, &decentering}) series->push_back({s.who, {}, {}, {}, rgb});
      for (const StellarProfileRow& row : p.rows) {
        for (const auto& [series, v, sigma] : {std::tuple{&radial.back(), row.radial_um, row.radial_sigma_um},
                                               std::tuple{&transformed.back(), row.transformed_um, row.transformed_sigma_um},
                                               std::tuple{&decentering.back(), row.decentering_um, row.decentering_sigma_um}}) {
          series->x.push_back(row.d_mm);
          series->value.push_back(v);
          series->sigma.push_back(sigma);
        }
      }
      focal_lengths += fmt::format("{}{}: C = {:.4f} mm, C' = {:.4f} +- {:.4f} mm", focal_lengths.empty() ? "" : "; ",
                                   s.who, s.lens.values[0], p.transformed_focal_length_mm,
                                   p.transformed_focal_length_sigma_mm);
    }
    if (radial.empty()) continue;
    const std::string set = combinations ? "combinations" : "plates";
    const auto add = [&](const std::vector<ProfileSeries>& series, const std::string& kind, const std::string& what,
                         const std::string& words) {
      ProfilePlotOptions o;
      o.title = fmt::format("{}, {}", what, set);
      o.x_label = "d, distance from the point of symmetry (mm)";
      o.y_label = what + " (µm)";
      const ProfilePlot plot = DrawProfilePlot(series, o);
      section.figures.push_back({"profile-" + kind + "-" + set, words, plot.files});
    };
    add(radial, "radial", "Radial symmetric distortion",
        "The radial symmetric distortion at the primary calibrated focal length C (seed 001 Fig. 7), out to the "
        "format's corner, each curve with its one-sigma envelope from the full covariance of the camera.");
    add(transformed, "transformed", "Transformed radial distortion",
        "The radial distortion transformed to the focal length C' at which the positive and negative lobes of the "
        "area under the curve are equal over the plotted extent (seed 001 Fig. 8), with its one-sigma envelope. " +
            focal_lengths + ".");
    add(decentering, "decentering", "Decentering distortion",
        "The profile of the lens decentering distortion, the largest tangential component at each distance (seed "
        "001 Fig. 9), with its one-sigma envelope.");
  }
  return section;
}

}  // namespace platemeter::report
