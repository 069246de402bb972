#include "platemeter/detect/overview.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "platemeter/core/error.h"

namespace platemeter {

Overview BuildOverview(const Image& image, int factor) {
  if (factor < 1) throw Error(image.info().path, "overview factor must be >= 1");
  Overview overview;
  overview.factor = factor;
  overview.width_px = image.info().width_px / factor;
  overview.height_px = image.info().height_px / factor;
  if (overview.width_px < 1 || overview.height_px < 1) throw Error(image.info().path, "scan smaller than one overview block");
  overview.values_dn.assign(static_cast<size_t>(overview.width_px * overview.height_px), 0.0f);
  const long scan_width = overview.width_px * factor;
  // Bands of whole block rows, read and reduced independently.
  const long rows_per_band = std::max(1L, 64L / factor);
  const long bands = (overview.height_px + rows_per_band - 1) / rows_per_band;
  tbb::parallel_for(0L, bands, [&](long band) {
    const long oy0 = band * rows_per_band;
    const long oy1 = std::min(overview.height_px, oy0 + rows_per_band);
    std::vector<float> pixels(static_cast<size_t>(scan_width * factor));
    std::vector<double> sums(static_cast<size_t>(overview.width_px));
    const double norm = 1.0 / (static_cast<double>(factor) * factor);
    for (long oy = oy0; oy < oy1; ++oy) {
      image.ReadWindowInto({0, oy * factor, scan_width, factor}, pixels.data());
      std::fill(sums.begin(), sums.end(), 0.0);
      for (long r = 0; r < factor; ++r) {
        const float* row = pixels.data() + r * scan_width;
        for (long x = 0; x < scan_width; ++x) sums[static_cast<size_t>(x / factor)] += row[x];
      }
      float* out = overview.values_dn.data() + oy * overview.width_px;
      for (long ox = 0; ox < overview.width_px; ++ox) out[ox] = static_cast<float>(sums[static_cast<size_t>(ox)] * norm);
    }
  });
  return overview;
}

}  // namespace platemeter
