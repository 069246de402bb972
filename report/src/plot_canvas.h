#pragma once
// Drawing one picture into both files: the same cairo drawing is run on an SVG
// surface and on an image surface (written as PNG), both in memory.
#include <functional>
#include <string>

#include <cairo.h>

#include "platemeter/report/plot.h"

namespace platemeter::report {

// Runs `draw` on a white page of width x height px, once per format. Throws
// Error("plot", why) if cairo fails (out of memory, a bad size).
RenderedPlot RenderPlot(int width_px, int height_px, const std::function<void(cairo_t*)>& draw);

inline void SetColour(cairo_t* cr, unsigned rgb, double alpha = 1.0) {
  cairo_set_source_rgba(cr, ((rgb >> 16) & 0xff) / 255.0, ((rgb >> 8) & 0xff) / 255.0, (rgb & 0xff) / 255.0, alpha);
}

}  // namespace platemeter::report
