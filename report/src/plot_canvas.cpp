// RenderPlot (plot_canvas.h): cairo's SVG and image surfaces written to memory.
#include "plot_canvas.h"

#include <cairo-svg.h>

#include <memory>

#include "platemeter/core/error.h"

namespace platemeter::report {
namespace {

cairo_status_t AppendTo(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void DrawPage(cairo_surface_t* surface, const std::function<void(cairo_t*)>& draw) {
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12);
  try {
    draw(cr);
  } catch (...) {
    cairo_destroy(cr);
    throw;
  }
  const cairo_status_t status = cairo_status(cr);
  cairo_destroy(cr);
  if (status != CAIRO_STATUS_SUCCESS) throw Error("plot", std::string("cairo: ") + cairo_status_to_string(status));
}

}  // namespace

RenderedPlot RenderPlot(int width_px, int height_px, const std::function<void(cairo_t*)>& draw) {
  if (width_px <= 0 || height_px <= 0 || width_px > 20000 || height_px > 20000) {
    throw Error("plot", "the picture's size must be 1..20000 px");
  }
  RenderedPlot plot;
  plot.width_px = width_px;
  plot.height_px = height_px;
  using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
  const Surface svg(cairo_svg_surface_create_for_stream(AppendTo, &plot.svg, width_px, height_px),
                    cairo_surface_destroy);
  DrawPage(svg.get(), draw);
  cairo_surface_finish(svg.get());  // flushes the SVG into plot.svg
  const Surface image(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px), cairo_surface_destroy);
  DrawPage(image.get(), draw);
  const cairo_status_t status = cairo_surface_write_to_png_stream(image.get(), AppendTo, &plot.png);
  if (status != CAIRO_STATUS_SUCCESS) throw Error("plot", std::string("PNG: ") + cairo_status_to_string(status));
  return plot;
}

}  // namespace platemeter::report
