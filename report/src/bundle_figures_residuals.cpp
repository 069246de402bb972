// The residual figures of the bundle's HTML report: vectors per frame (one
// plot each, or grids of small multiples) and the normalized residuals' histograms.
#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "bundle_figures.h"
#include "platemeter/report/histogram_plot.h"
#include "platemeter/report/vector_plot.h"

namespace platemeter::report {
namespace {

// The used image residuals of each frame, at their measured positions.
std::map<std::string, VectorPanel> PanelsByFrame(const BundleResult& result, const BundleInput& input) {
  std::map<std::pair<std::string, std::string>, const ImageObservation*> measured;
  for (const ImageObservation& o : input.observations) measured[{o.frame, o.point_id}] = &o;
  std::map<std::string, VectorPanel> panels;
  for (const ObservationResidual& r : result.adjustment.residuals) {
    if (r.status != ObservationStatus::kUsed || r.residual.size() != 2) continue;
    const auto it = measured.find({r.group, r.item});
    if (it == measured.end()) continue;
    panels[r.group].vectors.push_back({it->second->x_mm, it->second->y_mm, 1e3 * r.residual[0], 1e3 * r.residual[1]});
  }
  return panels;
}

// The format of a frame's camera, centred on the plate origin (none: the points' extent).
void FormatRange(const BundleResult& result, const std::string& camera, AxisRange* x, AxisRange* y) {
  for (const BundleCameraResult& c : result.cameras) {
    if (c.name != camera || !(c.format_width_mm > 0 && c.format_height_mm > 0)) continue;
    *x = {-c.format_width_mm / 2, c.format_width_mm / 2};
    *y = {-c.format_height_mm / 2, c.format_height_mm / 2};
  }
}

}  // namespace

FigureSection ResidualVectorFigures(const BundleResult& result, const BundleInput& input,
                                    const BundleHtmlOptions& options) {
  FigureSection section{"residuals", "Residual vectors per frame", {}, {}};
  std::map<std::string, VectorPanel> by_frame = PanelsByFrame(result, input);
  std::vector<VectorPanel> panels;
  std::vector<std::string> cameras;
  for (const BundleFrameResult& f : result.frames) {
    VectorPanel panel = std::move(by_frame[f.id]);
    panel.title = fmt::format("{}: {} obs., RMS {:.2f} / {:.2f} µm", f.id, panel.vectors.size(), f.rms_x_um,
                              f.rms_y_um);
    panels.push_back(std::move(panel));
    cameras.push_back(f.camera);
  }
  if (panels.empty()) return section;
  const bool grid = static_cast<int>(panels.size()) > options.max_frame_plots;
  VectorPlotOptions plot_options;
  plot_options.max_vectors = options.max_vectors_per_panel;
  FormatRange(result, cameras.front(), &plot_options.x_mm, &plot_options.y_mm);
  // One scale for every frame, so that their vectors compare.
  plot_options.px_per_um = AutoVectorScale(panels, plot_options, 560.0);
  const std::string words = "Residuals of the used observations (measured minus adjusted, in the measured plane), "
                            "drawn from the measured points; one scale for every frame (the bar).";
  if (!grid) {
    for (size_t i = 0; i < panels.size(); ++i) {
      FormatRange(result, cameras[i], &plot_options.x_mm, &plot_options.y_mm);
      plot_options.title = fmt::format("Residual vectors, frame {} of {}", i + 1, panels.size());
      const VectorPlot plot = DrawVectorPlot({panels[i]}, plot_options);
      section.figures.push_back({fmt::format("residuals-{:03d}-{}", i + 1, Slug(result.frames[i].id)),
                                 words + (plot.panels[0].aggregated ? " " + plot.panels[0].legend + "." : ""),
                                 plot.files});
    }
    return section;
  }
  // Many frames: grids of small multiples, the panel scale kept.
  plot_options.px_per_um *= 240.0 / 560.0;
  const int per_grid = std::max(1, options.frames_per_grid);
  for (size_t first = 0; first < panels.size(); first += per_grid) {
    const size_t last = std::min(panels.size(), first + per_grid);
    std::vector<VectorPanel> part(panels.begin() + first, panels.begin() + last);
    plot_options.title = fmt::format("Residual vectors, frames {} to {} of {}", first + 1, last, panels.size());
    const VectorPlot plot = DrawVectorPlot(part, plot_options);
    const auto aggregated = std::count_if(plot.panels.begin(), plot.panels.end(),
                                          [](const VectorPanelDrawn& p) { return p.aggregated; });
    section.figures.push_back(
        {fmt::format("residuals-grid-{:03d}", first / per_grid + 1),
         words + fmt::format(" {} of these {} frames have more than {} residuals: each of their arrows is the mean of "
                             "a cell (the panel's legend).",
                             aggregated, part.size(), options.max_vectors_per_panel),
         plot.files});
  }
  return section;
}

FigureSection ResidualHistogramFigures(const BundleResult& result) {
  FigureSection section{"histograms", "Normalized residuals", {}, {}};
  std::vector<double> x, y;
  for (const ObservationResidual& r : result.adjustment.residuals) {
    if (r.status != ObservationStatus::kUsed || r.normalized.size() != 2 || r.group == "distance") continue;
    x.push_back(r.normalized[0]);
    y.push_back(r.normalized[1]);
  }
  if (x.empty()) return section;
  const double sigma0 = result.adjustment.sigma0 > 0 ? result.adjustment.sigma0 : 1.0;
  for (const auto& [axis, values] : {std::pair{"x", &x}, std::pair{"y", &y}}) {
    HistogramPlotOptions o;
    o.title = fmt::format("Normalized residuals in {} (used observations)", axis);
    o.x_label = fmt::format("{} residual / a-priori sigma (-)", axis);
    // A gross error would squeeze the rest into one bar: the range is +-6 sigma0, the rest counted outside.
    o.range = AxisRange{-6.0 * sigma0, 6.0 * sigma0};
    o.bins = std::clamp(static_cast<int>(std::sqrt(double(values->size()))), 12, 72);
    o.normal_curve = true;
    o.normal_mean = 0.0;
    o.normal_sigma = sigma0;
    o.normal_words = fmt::format("expected: N(0, sigma0 = {:.3f})", sigma0);
    const HistogramPlot plot = DrawHistogram(*values, o);
    section.figures.push_back(
        {fmt::format("residual-histogram-{}", axis),
         fmt::format("{} normalized {} residuals over the normal curve N(0, sigma0^2) scaled to their count; {} beyond "
                     "±6 sigma0 not shown.",
                     values->size(), axis, plot.outside),
         plot.files});
  }
  return section;
}

}  // namespace platemeter::report
