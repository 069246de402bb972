#pragma once
// Image formation of the plate simulator: a Scene (marks, background, noise)
// turned into scan pixels band by band.
//
// Intensity model, in DN, for pixel (x, y):
//   I = (level + terrain(x, y)) * vignetting(x, y) + sum over marks of their
//       pixel-integrated, scanner-blurred contribution (render_model.h)
//       + noise(seed, x, y),
//   then clipped to [0, saturation_dn] and, when SceneNoise::quantize, rounded
//   to integer DN.
// The marks add in DN (amplitude_dn is the contrast against the local
// background, as a comparator operator sees it), and are not scaled by the
// vignetting: the contrast a detector must measure is exactly amplitude_dn.
// terrain: a sum of 8 plane cosine waves with wavelengths 0.6..1.4 x
//   terrain_scale_px, random directions and phases from the noise seed, scaled
//   so its RMS over the plate is terrain_amplitude_dn (smooth on the scale of a
//   cross; separable, so cheap).
// vignetting: 1 - vignetting_fraction * (r / vignetting_radius_px)^2 about
//   optical_centre_px (the leading term of the cos^4 law), never below 0.
// noise: sensor and grain are independent white Gaussians, so their sum is one
//   Gaussian of sigma hypot(sensor, grain); its standard normal deviate is a
//   counter-based hash (SplitMix64) of (seed, x, y) through Box-Muller, so a
//   pixel's value does not depend on how the image is cut into bands.
#include <cstdint>
#include <vector>

#include "platemeter/samples/render_model.h"
#include "platemeter/samples/scene.h"

namespace platemeter::sim {

// The standard normal deviate of pixel (x_px, y_px) for a noise seed.
double StandardNormalAt(uint64_t seed, long x_px, long y_px);

// Builds every mark's model once and indexes marks by rows, then renders any
// band. Thread-safe: bands may be rendered concurrently.
class SceneRenderer {
 public:
  explicit SceneRenderer(const Scene& scene, const RenderOptions& options = {});

  // Rows [y0_px, y0_px + rows) into values_dn (row-major, scene.width_px wide).
  // Multi-threaded over rows.
  void RenderBand(long y0_px, long rows, float* values_dn) const;

  // The noise-free background (level, terrain, vignetting) at a pixel.
  double BackgroundAt(long x_px, long y_px) const;

  const Scene& scene() const { return scene_; }
  const std::vector<MarkModel>& models() const { return models_; }

 private:
  void RenderRow(long y_px, double* row) const;

  Scene scene_;
  std::vector<MarkModel> models_;
  static constexpr long kBucketRows = 64;
  std::vector<std::vector<int>> buckets_;  // per 64 rows: marks whose support meets them, in scene order
  // Terrain as a sum of cos(kx x + ky y + phase) = cos(kx x + phase) cos(ky y) - sin(kx x + phase) sin(ky y).
  std::vector<double> wave_ky_;
  std::vector<std::vector<double>> wave_cos_x_, wave_sin_x_;  // amplitude * cos/sin(kx x + phase), per column
  std::vector<double> vignetting_dx2_;                        // (x - centre_x)^2 / radius^2 per column
};

// One band of a scene (builds a SceneRenderer; use the class for many bands).
void RenderBand(const Scene& scene, long y0_px, long rows, float* values_dn);

}  // namespace platemeter::sim
