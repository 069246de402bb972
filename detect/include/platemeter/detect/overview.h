#pragma once
// A reduced-resolution overview of a whole scan: each overview pixel is the
// mean of a factor x factor block. Built band by band through the image cache
// (never the whole scan in memory) and in parallel.
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/core/pixel.h"

namespace platemeter {

struct Overview {
  int factor = 1;      // full-resolution pixels per overview pixel, per axis
  long width_px = 0;   // overview size
  long height_px = 0;
  std::vector<float> values_dn;  // row-major block means of the unmasked pixels (never NaN)
  long masked_px = 0;  // masked pixels of the whole scan (image.h), edges beyond the last whole block included
  long empty_blocks = 0;  // blocks with no unmasked pixel: they hold the median of the other blocks
  // Full-resolution position of an overview position (block centres map to block centres).
  PixelPoint ToScan(double x_overview_px, double y_overview_px) const {
    return {factor * x_overview_px + 0.5 * (factor - 1), factor * y_overview_px + 0.5 * (factor - 1)};
  }
};

// Blocks that do not fit whole at the right and bottom edges are dropped (their
// pixels still count in masked_px). A block's masked pixels are left out of its
// mean, so a few missing pixels change no overview pixel by more than noise.
Overview BuildOverview(const Image& image, int factor);

}  // namespace platemeter
