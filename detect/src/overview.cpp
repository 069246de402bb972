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
  const long image_width = image.info().width_px;
  // Tasks of whole tile rows (and whole blocks), read through private readers
  // so that the tiles are decoded in parallel; each task decodes its tiles once.
  const long alignment = image.rows_alignment_px();
  long task_rows = std::max<long>(alignment, 64);
  while (task_rows % factor != 0 || task_rows % alignment != 0) task_rows += alignment;
  const long blocks_per_task = task_rows / factor;
  const long tasks = (overview.height_px + blocks_per_task - 1) / blocks_per_task;
  tbb::parallel_for(0L, tasks, [&](long task) {
    const long oy0 = task * blocks_per_task;
    const long oy1 = std::min(overview.height_px, oy0 + blocks_per_task);
    std::vector<float> pixels(static_cast<size_t>(image_width * (oy1 - oy0) * factor));
    image.ReadRowsDirect(oy0 * factor, (oy1 - oy0) * factor, pixels.data());
    std::vector<double> sums(static_cast<size_t>(overview.width_px));
    const double norm = 1.0 / (static_cast<double>(factor) * factor);
    for (long oy = oy0; oy < oy1; ++oy) {
      std::fill(sums.begin(), sums.end(), 0.0);
      for (long r = 0; r < factor; ++r) {
        const float* row = pixels.data() + ((oy - oy0) * factor + r) * image_width;
        for (long x = 0; x < scan_width; ++x) sums[static_cast<size_t>(x / factor)] += row[x];
      }
      float* out = overview.values_dn.data() + oy * overview.width_px;
      for (long ox = 0; ox < overview.width_px; ++ox) out[ox] = static_cast<float>(sums[static_cast<size_t>(ox)] * norm);
    }
  });
  return overview;
}

}  // namespace platemeter
