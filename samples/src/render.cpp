#include "platemeter/samples/render.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "platemeter/core/error.h"
#include "render_geometry.h"

namespace platemeter::sim {

using render_detail::Mix64;

namespace {

constexpr int kTerrainWaves = 8;

// Box-Muller on one 64-bit hash gives the normals of the pixel pair (2j, 2j + 1).
inline void NormalPair(uint64_t seed_key, long pair, long y_px, double* z0, double* z1) {
  const uint64_t counter = (static_cast<uint64_t>(y_px) << 32) ^ static_cast<uint64_t>(pair);
  const uint64_t h = Mix64(seed_key + counter * 0x9E3779B97F4A7C15ull);
  const double u1 = (static_cast<double>(h >> 32) + 0.5) * (1.0 / 4294967296.0);
  const double u2 = (static_cast<double>(h & 0xFFFFFFFFull) + 0.5) * (1.0 / 4294967296.0);
  const double radius = std::sqrt(-2.0 * std::log(u1));
  const double angle = 2.0 * M_PI * u2;
  *z0 = radius * std::cos(angle);
  *z1 = radius * std::sin(angle);
}

uint64_t SeedKey(uint64_t seed) { return Mix64(seed ^ 0x6A09E667F3BCC909ull); }

}  // namespace

double StandardNormalAt(uint64_t seed, long x_px, long y_px) {
  double z0, z1;
  const long pair = x_px >= 0 ? x_px / 2 : -((-x_px + 1) / 2);
  NormalPair(SeedKey(seed), pair, y_px, &z0, &z1);
  return (x_px - 2 * pair) == 0 ? z0 : z1;
}

SceneRenderer::SceneRenderer(const Scene& scene, const RenderOptions& options) : scene_(scene) {
  if (scene.width_px <= 0 || scene.height_px <= 0) throw Error("scene", "width_px and height_px must be > 0");
  const SceneBackground& bg = scene.background;
  const SceneNoise& noise = scene.noise;
  if (!(noise.sensor_sigma_dn >= 0 && noise.grain_sigma_dn >= 0 && noise.scanner_blur_sigma_px >= 0))
    throw Error("scene noise", "sigmas must be >= 0");
  if (!(noise.saturation_dn > 0)) throw Error("scene noise", "saturation_dn must be > 0");
  if (!(bg.terrain_scale_px > 0)) throw Error("scene background", "terrain_scale_px must be > 0");
  if (!(bg.vignetting_radius_px > 0)) throw Error("scene background", "vignetting_radius_px must be > 0");
  if (!(bg.vignetting_fraction >= 0 && bg.vignetting_fraction <= 1))
    throw Error("scene background", "vignetting_fraction must be in [0, 1]");

  // Mark models (disk tables take a moment: build in parallel).
  std::vector<std::optional<MarkModel>> built(scene.marks.size());
  tbb::parallel_for(size_t{0}, scene.marks.size(), [&](size_t i) {
    built[i].emplace(scene.marks[i], noise.scanner_blur_sigma_px, options);
  });
  models_.reserve(built.size());
  for (auto& model : built) models_.push_back(std::move(*model));

  buckets_.resize(static_cast<size_t>((scene.height_px + kBucketRows - 1) / kBucketRows));
  for (size_t i = 0; i < models_.size(); ++i) {
    const PixelRect& s = models_[i].support();
    if (s.x_end_px() <= 0 || s.x0_px >= scene.width_px) continue;
    const long y_lo = std::max(0L, s.y0_px), y_hi = std::min(scene.height_px, s.y_end_px());
    for (long b = y_lo / kBucketRows; y_lo < y_hi && b <= (y_hi - 1) / kBucketRows; ++b)
      buckets_[b].push_back(static_cast<int>(i));
  }

  // Terrain waves from the noise seed.
  if (bg.terrain_amplitude_dn != 0.0) {
    uint64_t state = Mix64(noise.seed ^ 0xBB67AE8584CAA73Bull);
    auto uniform = [&state] {
      state += 0x9E3779B97F4A7C15ull;
      return (Mix64(state) >> 11) * (1.0 / 9007199254740992.0);
    };
    double amplitudes[kTerrainWaves], sum_sq = 0.0;
    double kx[kTerrainWaves], phase[kTerrainWaves];
    wave_ky_.resize(kTerrainWaves);
    for (int k = 0; k < kTerrainWaves; ++k) {
      const double wavelength = bg.terrain_scale_px * (0.6 + 0.8 * uniform());
      const double direction = 2.0 * M_PI * uniform();
      kx[k] = 2.0 * M_PI / wavelength * std::cos(direction);
      wave_ky_[k] = 2.0 * M_PI / wavelength * std::sin(direction);
      phase[k] = 2.0 * M_PI * uniform();
      amplitudes[k] = 0.5 + uniform();
      sum_sq += 0.5 * amplitudes[k] * amplitudes[k];
    }
    const double norm = bg.terrain_amplitude_dn / std::sqrt(sum_sq);  // RMS of the sum = terrain_amplitude_dn
    wave_cos_x_.assign(kTerrainWaves, std::vector<double>(scene.width_px));
    wave_sin_x_.assign(kTerrainWaves, std::vector<double>(scene.width_px));
    for (int k = 0; k < kTerrainWaves; ++k)
      for (long x = 0; x < scene.width_px; ++x) {
        wave_cos_x_[k][x] = norm * amplitudes[k] * std::cos(kx[k] * x + phase[k]);
        wave_sin_x_[k][x] = norm * amplitudes[k] * std::sin(kx[k] * x + phase[k]);
      }
  }
  if (bg.vignetting_fraction != 0.0) {
    vignetting_dx2_.resize(scene.width_px);
    for (long x = 0; x < scene.width_px; ++x) {
      const double dx = (x - bg.optical_centre_px.x_px) / bg.vignetting_radius_px;
      vignetting_dx2_[x] = dx * dx;
    }
  }
}

double SceneRenderer::BackgroundAt(long x_px, long y_px) const {
  const SceneBackground& bg = scene_.background;
  double value = bg.level_dn;
  for (size_t k = 0; k < wave_ky_.size(); ++k)
    value += wave_cos_x_[k][x_px] * std::cos(wave_ky_[k] * y_px) - wave_sin_x_[k][x_px] * std::sin(wave_ky_[k] * y_px);
  if (!vignetting_dx2_.empty()) {
    const double dy = (y_px - bg.optical_centre_px.y_px) / bg.vignetting_radius_px;
    value *= std::max(0.0, 1.0 - bg.vignetting_fraction * (vignetting_dx2_[x_px] + dy * dy));
  }
  return value;
}

void SceneRenderer::RenderRow(long y, double* row) const {
  const long width = scene_.width_px;
  const SceneBackground& bg = scene_.background;
  // Background: the same arithmetic as BackgroundAt, vectorisable by columns.
  std::fill(row, row + width, bg.level_dn);
  for (size_t k = 0; k < wave_ky_.size(); ++k) {
    const double cy = std::cos(wave_ky_[k] * y), sy = std::sin(wave_ky_[k] * y);
    const double* cx = wave_cos_x_[k].data();
    const double* sx = wave_sin_x_[k].data();
    for (long x = 0; x < width; ++x) row[x] += cx[x] * cy - sx[x] * sy;
  }
  if (!vignetting_dx2_.empty()) {
    const double dy = (y - bg.optical_centre_px.y_px) / bg.vignetting_radius_px;
    const double dy2 = dy * dy, fraction = bg.vignetting_fraction;
    for (long x = 0; x < width; ++x) row[x] *= std::max(0.0, 1.0 - fraction * (vignetting_dx2_[x] + dy2));
  }
  // Marks whose support meets this row, in scene order.
  for (int index : buckets_[y / kBucketRows]) {
    const MarkModel& model = models_[index];
    const PixelRect& s = model.support();
    if (y < s.y0_px || y >= s.y_end_px()) continue;
    const long x_lo = std::max(0L, s.x0_px), x_hi = std::min(width, s.x_end_px());
    for (long x = x_lo; x < x_hi; ++x) row[x] += model.PixelValue(x, y);
  }
  // Noise, clip, quantization.
  const SceneNoise& noise = scene_.noise;
  const double sigma = std::hypot(noise.sensor_sigma_dn, noise.grain_sigma_dn);
  if (sigma > 0.0) {
    const uint64_t key = SeedKey(noise.seed);
    for (long x = 0; x < width; x += 2) {
      double z0, z1;
      NormalPair(key, x / 2, y, &z0, &z1);
      row[x] += sigma * z0;
      if (x + 1 < width) row[x + 1] += sigma * z1;
    }
  }
  const double saturation = noise.saturation_dn;
  for (long x = 0; x < width; ++x) {
    double v = std::clamp(row[x], 0.0, saturation);
    if (noise.quantize) v = std::nearbyint(v);
    row[x] = v;
  }
}

void SceneRenderer::RenderBand(long y0_px, long rows, float* values_dn) const {
  if (rows <= 0) return;
  if (y0_px < 0 || y0_px + rows > scene_.height_px) throw Error("scene", "band outside the image rows");
  const long width = scene_.width_px;
  tbb::parallel_for(tbb::blocked_range<long>(y0_px, y0_px + rows), [&](const tbb::blocked_range<long>& range) {
    std::vector<double> row(width);
    for (long y = range.begin(); y < range.end(); ++y) {
      RenderRow(y, row.data());
      float* out = values_dn + (y - y0_px) * width;
      for (long x = 0; x < width; ++x) out[x] = static_cast<float>(row[x]);
    }
  });
}

void RenderBand(const Scene& scene, long y0_px, long rows, float* values_dn) {
  SceneRenderer(scene).RenderBand(y0_px, rows, values_dn);
}

}  // namespace platemeter::sim
