#include "platemeter/detect/overview.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "platemeter/core/error.h"
#include "median.h"

namespace platemeter {
namespace {

// Block means of one band of block_rows rows of blocks (`pixels`: the band's scan rows).
// Integer scans take the plain sum (no pixel can be masked: the hot path stays as it was).
template <bool kMasked>
void BlockMeans(const float* pixels, long image_width, long blocks, int factor, long block_rows, float* out) {
  std::vector<double> sums(static_cast<size_t>(blocks));
  std::vector<int> counts(kMasked ? static_cast<size_t>(blocks) : 0);
  const long scan_width = blocks * factor;
  const double norm = 1.0 / (static_cast<double>(factor) * factor);
  for (long oy = 0; oy < block_rows; ++oy) {
    std::fill(sums.begin(), sums.end(), 0.0);
    if constexpr (kMasked) std::fill(counts.begin(), counts.end(), 0);
    for (long r = 0; r < factor; ++r) {
      const float* row = pixels + (oy * factor + r) * image_width;
      if constexpr (kMasked) {
        for (long ox = 0; ox < blocks; ++ox) {
          const float* block = row + ox * factor;
          double sum = 0.0;
          int count = 0;
          for (int k = 0; k < factor; ++k) {
            if (std::isnan(block[k])) continue;
            sum += block[k];
            ++count;
          }
          sums[static_cast<size_t>(ox)] += sum;
          counts[static_cast<size_t>(ox)] += count;
        }
      } else {
        for (long x = 0; x < scan_width; ++x) sums[static_cast<size_t>(x / factor)] += row[x];
      }
    }
    float* block = out + oy * blocks;
    for (long ox = 0; ox < blocks; ++ox) {
      const size_t k = static_cast<size_t>(ox);
      if constexpr (kMasked) {
        block[ox] = counts[k] > 0 ? static_cast<float>(sums[k] / counts[k]) : std::nanf("");
      } else {
        block[ox] = static_cast<float>(sums[k] * norm);
      }
    }
  }
}

// Blocks without any unmasked pixel take the median of the others: flat, so the
// correlations downstream see no structure there. Returns how many there were.
long FillEmptyBlocks(std::vector<float>* values) {
  if (CountMaskedPixels(values->data(), values->size()) == 0) return 0;
  std::vector<double> finite;
  long empty = 0;
  for (float v : *values) {
    if (std::isnan(v)) {
      ++empty;
    } else {
      finite.push_back(v);
    }
  }
  if (empty == 0) return 0;
  const float fill = static_cast<float>(detect_internal::Median(std::move(finite)));
  for (float& v : *values)
    if (std::isnan(v)) v = fill;
  return empty;
}

}  // namespace

Overview BuildOverview(const Image& image, int factor) {
  if (factor < 1) throw Error(image.info().path, "overview factor must be >= 1");
  Overview overview;
  overview.factor = factor;
  overview.width_px = image.info().width_px / factor;
  overview.height_px = image.info().height_px / factor;
  if (overview.width_px < 1 || overview.height_px < 1) throw Error(image.info().path, "scan smaller than one overview block");
  overview.values_dn.assign(static_cast<size_t>(overview.width_px * overview.height_px), 0.0f);
  const long image_width = image.info().width_px;
  const bool maskable = image.info().may_have_masked_pixels();
  std::atomic<long> masked{0};
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
    // The last task of a float scan also reads the rows below the last whole block: they are in no
    // block, but their masked pixels are the scan's (one read: a second would decode that strip again).
    const long y_end = maskable && oy1 == overview.height_px ? image.info().height_px : oy1 * factor;
    std::vector<float> pixels(static_cast<size_t>(image_width * (y_end - oy0 * factor)));
    image.ReadRowsDirect(oy0 * factor, y_end - oy0 * factor, pixels.data());
    float* out = overview.values_dn.data() + oy0 * overview.width_px;
    if (maskable) {
      masked += static_cast<long>(CountMaskedPixels(pixels.data(), pixels.size()));
      BlockMeans<true>(pixels.data(), image_width, overview.width_px, factor, oy1 - oy0, out);
    } else {
      BlockMeans<false>(pixels.data(), image_width, overview.width_px, factor, oy1 - oy0, out);
    }
  });
  overview.masked_px = masked.load();
  if (maskable) overview.empty_blocks = FillEmptyBlocks(&overview.values_dn);
  return overview;
}

}  // namespace platemeter
