#pragma once
// A scan's pixels as the trail steps read them: windows, never the whole image
// (a scan may be larger than memory; the CLI reads through the image's cache).
#include <functional>

#include "platemeter/core/pixel.h"

namespace platemeter {

// Reads the pixels of `rect` (inside the scan) into values_dn, row-major, in DN. Must be safe to call from
// several threads at once.
using WindowReader = std::function<void(const PixelRect& rect, float* values_dn)>;

struct ScanPixels {
  WindowReader read;
  long width_px = 0, height_px = 0;
  bool dark = true;                // star images darker than the background (a negative)
  double low_dn = 0.0;             // DN; pixels at or below are clipped (dark images at the film's floor)
  double high_dn = 65535.0;        // DN; pixels at or above are clipped (saturated)
};

}  // namespace platemeter
