// The residual figures of the stellar calibration's HTML report (seed 001
// Table 4): histograms over the normal curve, the star images measured, and the
// residual vectors (total, radial, tangential) per subtrail, one colour per trail.
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include <fmt/format.h>

#include "platemeter/report/histogram_plot.h"
#include "stellar_figures.h"

namespace platemeter::report {
namespace {

// Distinct colours for up to ten trails (then they repeat).
constexpr unsigned kTrailPalette[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd,
                                 0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22, 0x7f7f7f};
constexpr unsigned kSingleImages = 0x404040;

std::string TrailWords(const std::string& trail) { return trail.empty() ? "star images" : "trail " + trail; }

// The plates of a combination (indices into result.singles).
std::vector<size_t> CombinationPlates(const StellarReportContext& c, const StellarCombination& combination) {
  std::vector<size_t> plates;
  for (size_t i = 0; i < c.result.singles.size(); ++i) {
    const auto& ids = combination.plate_ids;
    if (std::find(ids.begin(), ids.end(), c.result.singles[i].plate_id) != ids.end()) plates.push_back(i);
  }
  return plates;
}

int CameraOf(const StellarReportContext& c, size_t plate) {
  return plate < c.job.plates.size() ? c.job.plates[plate].camera : 0;
}

// x, y and x-and-y histograms of the used residuals of `plates`.
void AddHistograms(const StellarReportContext& c, const std::vector<size_t>& plates, const std::string& who,
                   const std::string& stem, FigureSection* section) {
  std::vector<double> x, y;
  long rejected = 0;
  for (size_t p : plates) {
    for (const StellarImageResidual& r : PlateResiduals(c, p)) {
      if (!r.used) {
        ++rejected;
        continue;
      }
      x.push_back(r.vx_um);
      y.push_back(r.vy_um);
    }
  }
  if (x.size() < 2) {
    section->notes.push_back(who + ": fewer than two used residuals, no histogram");
    return;
  }
  std::vector<double> xy = x;
  xy.insert(xy.end(), y.begin(), y.end());
  for (const auto& [values, what, suffix] : {std::tuple{&x, "x", "x"}, std::tuple{&y, "y", "y"},
                                             std::tuple{&xy, "x and y", "xy"}}) {
    HistogramPlotOptions o;
    o.title = fmt::format("{}: {} residuals", who, what);
    o.x_label = fmt::format("{} residual (µm)", what);
    o.normal_curve = true;
    o.normal_words = "normal curve of the residuals' mean and standard deviation";
    const HistogramPlot plot = DrawHistogram(*values, o);
    section->figures.push_back(
        {stem + "-" + suffix,
         fmt::format("{}: the {} residuals of the single-plate adjustment{} ({} values, {} rejected images left out), "
                     "binned, with the normal curve N({:.2f}, {:.2f}) µm scaled to the counts.",
                     who, what, plates.size() > 1 ? "s, pooled" : "", values->size(), rejected, plot.normal_mean,
                     plot.normal_sigma),
         plot.files});
  }
}

VectorPlotOptions PlateVectorOptions(const StellarReportContext& c, int camera, const std::string& title) {
  VectorPlotOptions o;
  o.title = title;
  o.x_mm = c.x_mm[camera];
  o.y_mm = c.y_mm[camera];
  o.max_vectors = c.options.max_vectors_per_panel;
  return o;
}

// The mean residual and position of consecutive groups of `size` used images of one star's trail.
std::vector<PlotVector> SubtrailVectors(const std::vector<StellarImageResidual>& residuals, int size,
                                        const std::map<std::string, unsigned>& colours) {
  std::map<std::pair<std::string, std::string>, std::vector<const StellarImageResidual*>> trails;
  for (const StellarImageResidual& r : residuals) {
    if (r.used) trails[{r.image->trail, r.image->star_id}].push_back(&r);
  }
  std::vector<PlotVector> out;
  for (const auto& [trail_name, name] : colours) {
    for (auto& [key, members] : trails) {
      if (key.first != trail_name) continue;
      std::stable_sort(members.begin(), members.end(), [](const auto* a, const auto* b) {
        return std::make_pair(a->image->dot, a->image->mid_time.Mjd()) <
               std::make_pair(b->image->dot, b->image->mid_time.Mjd());
      });
      for (size_t start = 0; start < members.size(); start += size) {
        const size_t end = std::min(members.size(), start + size);
        PlotVector v{0, 0, 0, 0, name};
        for (size_t k = start; k < end; ++k) {
          v.x_mm += members[k]->image->x_mm;
          v.y_mm += members[k]->image->y_mm;
          v.dx_um += members[k]->vx_um;
          v.dy_um += members[k]->vy_um;
        }
        const double n = static_cast<double>(end - start);
        out.push_back({v.x_mm / n, v.y_mm / n, v.dx_um / n, v.dy_um / n, name});
      }
    }
  }
  return out;
}

}  // namespace

std::vector<StellarImageResidual> PlateResiduals(const StellarReportContext& c, size_t plate) {
  const StellarPlate& p = c.result.plates[plate];
  std::map<std::string, const StarImageObservation*> by_id;
  for (const StarImageObservation& image : p.images) by_id[image.image_id] = &image;
  std::vector<StellarImageResidual> out;
  for (const ObservationResidual& r : c.result.singles[plate].adjustment.residuals) {
    const auto it = by_id.find(r.item.substr(0, r.item.find(' ')));
    if (it == by_id.end() || r.residual.size() < 2) continue;
    out.push_back({it->second, 1e3 * r.residual[0], 1e3 * r.residual[1], r.status == ObservationStatus::kUsed});
  }
  return out;
}

std::map<std::string, unsigned> TrailColours(const StellarReportContext& c) {
  std::map<std::string, unsigned> colours;
  for (const StellarPlate& p : c.result.plates) {
    for (const StarImageObservation& image : p.images) colours[image.trail] = 0;
  }
  size_t k = 0;
  for (auto& [trail, rgb] : colours) rgb = trail.empty() ? kSingleImages : kTrailPalette[k++ % std::size(kTrailPalette)];
  return colours;
}

std::vector<std::pair<std::string, unsigned>> TrailKey(const std::map<std::string, unsigned>& colours) {
  std::vector<std::pair<std::string, unsigned>> key;
  for (const auto& [trail, rgb] : colours) key.emplace_back(TrailWords(trail), rgb);
  return key;
}

FigureSection StellarHistogramFigures(const StellarReportContext& c) {
  FigureSection section{"histograms", "Histograms of the residuals", {}, {}};
  for (size_t i = 0; i < c.result.singles.size(); ++i) {
    const std::string& id = c.result.singles[i].plate_id;
    AddHistograms(c, {i}, "plate " + id, "histogram-plate-" + Slug(id), &section);
  }
  for (const StellarCombination& combination : c.result.combinations) {
    AddHistograms(c, CombinationPlates(c, combination), "combination " + combination.name,
                  "histogram-combination-" + Slug(combination.name), &section);
  }
  section.notes.push_back(
      "Seed 001 also draws histograms of the differences of double measurements; a scan is measured once, so there "
      "are none here.");
  return section;
}

FigureSection StellarStarImageFigures(const StellarReportContext& c) {
  FigureSection section{"star-images", "The star images measured", {}, {}};
  const std::map<std::string, unsigned> colours = TrailColours(c);
  auto panel_of = [&](const std::vector<size_t>& plates, const std::string& title) {
    VectorPanel panel{title, {}, {}, {}, c.corner_labels[CameraOf(c, plates.front())]};
    for (size_t p : plates) {
      for (const StarImageObservation& image : c.result.plates[p].images)
        panel.markers.push_back({image.x_mm, image.y_mm, colours.at(image.trail)});
    }
    return panel;
  };
  auto add = [&](const std::vector<size_t>& plates, const std::string& who, const std::string& stem) {
    VectorPlotOptions o = PlateVectorOptions(c, CameraOf(c, plates.front()), "Star images measured, " + who);
    o.colour_key = TrailKey(colours);
    const VectorPlot plot = DrawVectorPlot({panel_of(plates, who)}, o);
    size_t images = 0;
    for (size_t p : plates) images += c.result.plates[p].images.size();
    section.figures.push_back({stem,
                               fmt::format("Every star image of {} ({} images), one colour per trail; the corner "
                                           "reseau numbers key the plot to the focal plane (plate frame, x right, y "
                                           "up, mm).",
                                           who, images),
                               plot.files});
  };
  for (size_t i = 0; i < c.result.singles.size(); ++i)
    add({i}, "plate " + c.result.singles[i].plate_id, "stars-plate-" + Slug(c.result.singles[i].plate_id));
  for (const StellarCombination& combination : c.result.combinations) {
    const std::vector<size_t> plates = CombinationPlates(c, combination);
    if (plates.size() > 1)
      add(plates, "combination " + combination.name, "stars-combination-" + Slug(combination.name));
  }
  return section;
}

FigureSection StellarResidualVectorFigures(const StellarReportContext& c) {
  FigureSection section{"residual-vectors", "Residual vectors of the single-plate adjustments", {}, {}};
  const std::map<std::string, unsigned> colours = TrailColours(c);
  for (size_t i = 0; i < c.result.singles.size(); ++i) {
    const StellarPlateResult& s = c.result.singles[i];
    const int camera = CameraOf(c, i);
    const std::vector<PlotVector> total = SubtrailVectors(PlateResiduals(c, i), c.options.subtrail_images, colours);
    if (total.empty()) continue;
    VectorPanel t{"total", total, {}, {}, c.corner_labels[camera]};
    VectorPanel radial{"radial", {}, {}, {}, c.corner_labels[camera]};
    VectorPanel tangential{"tangential", {}, {}, {}, c.corner_labels[camera]};
    for (const PlotVector& v : total) {
      // Components along and across the direction from the principal point.
      const double ux = v.x_mm - s.camera[1], uy = v.y_mm - s.camera[2], n = std::hypot(ux, uy);
      const double ex = n > 0 ? ux / n : 1.0, ey = n > 0 ? uy / n : 0.0;
      const double along = v.dx_um * ex + v.dy_um * ey;
      radial.vectors.push_back({v.x_mm, v.y_mm, along * ex, along * ey, v.rgb});
      tangential.vectors.push_back({v.x_mm, v.y_mm, v.dx_um - along * ex, v.dy_um - along * ey, v.rgb});
    }
    VectorPlotOptions o = PlateVectorOptions(c, camera, "Residuals of plate " + s.plate_id);
    o.colour_key = TrailKey(colours);
    o.columns = 3;
    o.panel_px = 380;
    const VectorPlot plot = DrawVectorPlot({t, radial, tangential}, o);
    section.figures.push_back(
        {"residuals-plate-" + Slug(s.plate_id),
         fmt::format("Plate {}: each vector the mean residual of a subtrail of up to {} consecutive images of one "
                     "star ({} vectors), one colour per trail; total, and its radial and tangential components about "
                     "the principal point; one scale for the three panels ({:g} µm bar).",
                     s.plate_id, c.options.subtrail_images, total.size(), plot.scale_bar_um),
         plot.files});
  }
  return section;
}

}  // namespace platemeter::report
