#pragma once
// Cramer-Rao bound of every mark's position: the best any unbiased detector can
// do on the simulated scan. The local model is the mark's exact noise-free
// image (render_model.h) on a constant background,
//   m(x, y, a, b) = b + a * g(pixel; centre (x, y)),
// with all four parameters free; the noise is white with per-pixel variance
//   sensor^2 + grain^2 + 1/12 (the 1/12 only when quantize is on).
// Fisher information F = J^T J / variance over a window covering the mark's
// support; the position block of F^-1 gives sigma_x, sigma_y and their
// correlation. Position derivatives are central differences of the exact
// pixel-integrated model.
#include <limits>
#include <string>
#include <vector>

#include "platemeter/samples/render_model.h"
#include "platemeter/samples/scene.h"

namespace platemeter::sim {

struct CramerRaoOptions {
  long margin_px = 4;      // px; the window is the mark's support grown by this (then clipped to the image)
  double step_px = 0.005;  // px; central-difference step of the position derivatives
  bool Check(std::string* why) const;
};

struct MarkCramerRao {
  double sigma_x_px = std::numeric_limits<double>::infinity();
  double sigma_y_px = std::numeric_limits<double>::infinity();
  double correlation_xy = 0.0;  // of the x and y estimates
  double sigma_amplitude_dn = std::numeric_limits<double>::infinity();
  double sigma_background_dn = std::numeric_limits<double>::infinity();
  long window_pixels = 0;  // pixels used
  bool valid = false;      // false: no information (zero amplitude, no noise, or outside the image)
};

// Per-pixel noise variance in DN^2 the bound assumes.
double PixelNoiseVariance(const SceneNoise& noise);

// The bound for one mark of a scene (window clipped to the scene's image).
MarkCramerRao CramerRaoBound(const Scene& scene, const SceneMark& mark, const RenderOptions& render_options = {},
                             const CramerRaoOptions& options = {});
// The same from a built model and an explicit window (not clipped).
MarkCramerRao CramerRaoBound(const MarkModel& model, const SceneNoise& noise, const PixelRect& window,
                             const CramerRaoOptions& options = {});
// All marks of a scene, in scene order, in parallel.
std::vector<MarkCramerRao> CramerRaoBounds(const Scene& scene, const RenderOptions& render_options = {},
                                           const CramerRaoOptions& options = {});

}  // namespace platemeter::sim
