// The reseau residual vector plot (residual_plot.h).
#include "platemeter/measure/residual_plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "platemeter/core/atomic_file.h"
#include "platemeter/core/error.h"

namespace platemeter {

bool ResidualPlotOptions::Check(std::string* why) const {
  if (size_px < 200 || size_px > 8000) {
    if (why) *why = "residual plot size_px must lie in 200..8000";
    return false;
  }
  if (!(scale_bar_um >= 0.0) || !(tolerance_um > 0.0)) {
    if (why) *why = "residual plot scale_bar_um must be >= 0 and tolerance_um > 0";
    return false;
  }
  return true;
}

void WriteResidualPlotPng(const std::string& path, const std::vector<ReseauObservation>& observations,
                          const ReseauFit& fit, const ResidualPlotOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error(path, why);
  if (observations.empty() || fit.residual_x_mm.size() != observations.size()) throw Error(path, "no residuals to plot");
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300, max_r_um = 0.0;
  for (size_t i = 0; i < observations.size(); ++i) {
    min_x = std::min(min_x, observations[i].grid_x_mm);
    max_x = std::max(max_x, observations[i].grid_x_mm);
    min_y = std::min(min_y, observations[i].grid_y_mm);
    max_y = std::max(max_y, observations[i].grid_y_mm);
    if (!fit.is_rejected[i]) max_r_um = std::max(max_r_um, 1e3 * std::hypot(fit.residual_x_mm[i], fit.residual_y_mm[i]));
  }
  double bar_um = options.scale_bar_um;
  if (bar_um <= 0.0) {
    // 1, 2 or 5 times a power of ten, near twice the largest residual.
    const double target = std::max(2.0 * max_r_um, 0.1);
    const double p10 = std::pow(10.0, std::floor(std::log10(target)));
    bar_um = target / p10 < 2 ? 2 * p10 : target / p10 < 5 ? 5 * p10 : 10 * p10;
  }
  const int size = options.size_px;
  const double margin = 0.12 * size;
  const double span_mm = std::max({max_x - min_x, max_y - min_y, 1e-6});
  const double px_per_mm = (size - 2 * margin) / span_mm;
  const double bar_px = 0.1 * size;              // the scale bar's length on the image
  const double px_per_um_residual = bar_px / bar_um;
  auto to_px = [&](double x_mm, double y_mm, double* u, double* v) {
    *u = margin + (x_mm - min_x) * px_per_mm;
    *v = size - margin - (y_mm - min_y) * px_per_mm;  // y up
  };

  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, size, size);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_line_width(cr, std::max(1.0, size / 500.0));
  auto arrow = [&](double u0, double v0, double du, double dv) {
    cairo_move_to(cr, u0, v0);
    cairo_line_to(cr, u0 + du, v0 + dv);
    cairo_stroke(cr);
    const double len = std::hypot(du, dv);
    if (len < 1.0) return;
    const double head = std::min(0.3 * len, size / 80.0), ux = du / len, uy = dv / len;
    cairo_move_to(cr, u0 + du, v0 + dv);
    cairo_line_to(cr, u0 + du - head * (ux - 0.5 * uy), v0 + dv - head * (uy + 0.5 * ux));
    cairo_line_to(cr, u0 + du - head * (ux + 0.5 * uy), v0 + dv - head * (uy - 0.5 * ux));
    cairo_close_path(cr);
    cairo_fill(cr);
  };
  for (size_t i = 0; i < observations.size(); ++i) {
    double u, v;
    to_px(observations[i].grid_x_mm, observations[i].grid_y_mm, &u, &v);
    const double rx_um = 1e3 * fit.residual_x_mm[i], ry_um = 1e3 * fit.residual_y_mm[i];
    if (fit.is_rejected[i]) cairo_set_source_rgb(cr, 0.85, 0.1, 0.1);
    else if (std::hypot(rx_um, ry_um) > options.tolerance_um) cairo_set_source_rgb(cr, 0.95, 0.55, 0.0);
    else cairo_set_source_rgb(cr, 0.1, 0.2, 0.7);
    cairo_arc(cr, u, v, std::max(1.5, size / 400.0), 0, 2 * M_PI);
    cairo_fill(cr);
    arrow(u, v, rx_um * px_per_um_residual, -ry_um * px_per_um_residual);
  }
  // Scale bar and title.
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size / 45.0);
  arrow(margin, size - 0.4 * margin, bar_px, 0.0);
  const std::string bar = fmt::format("{:g} um", bar_um);
  cairo_move_to(cr, margin + bar_px + size / 80.0, size - 0.4 * margin + size / 120.0);
  cairo_show_text(cr, bar.c_str());
  const std::string title = options.title.empty() ? fmt::format("reseau residuals ({}): rms {:.2f} um, {} used, {} rejected",
                                                                ReseauFitModelName(fit.model), fit.rms_mm * 1e3, fit.used, fit.rejected)
                                                  : options.title;
  cairo_move_to(cr, margin, 0.5 * margin);
  cairo_show_text(cr, title.c_str());
  cairo_destroy(cr);
  // Encoded in memory, then written atomically (no half-written PNG under the final name).
  std::string png;
  const cairo_status_t status = cairo_surface_write_to_png_stream(
      surface,
      [](void* closure, const unsigned char* data, unsigned int length) {
        static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
        return CAIRO_STATUS_SUCCESS;
      },
      &png);
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) throw Error(path, std::string("cannot encode the PNG: ") + cairo_status_to_string(status));
  WriteFileAtomically(path, png);
}

}  // namespace platemeter
