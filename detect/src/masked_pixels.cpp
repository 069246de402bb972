// Masked pixels in correlation and filter inputs (masked_pixels.h).
#include "masked_pixels.h"

#include <cmath>
#include <vector>

#include "platemeter/core/image.h"
#include "median.h"

namespace platemeter::detect_internal {

size_t FillMasked(float* values_dn, size_t count, float fill) {
  size_t masked = 0;
  for (size_t i = 0; i < count; ++i) {
    if (std::isnan(values_dn[i])) {
      values_dn[i] = fill;
      ++masked;
    }
  }
  return masked;
}

size_t FillMaskedWithMedian(float* values_dn, size_t count) {
  const size_t masked = CountMaskedPixels(values_dn, count);
  if (masked == 0) return 0;
  std::vector<double> others;
  others.reserve(count - masked);
  for (size_t i = 0; i < count; ++i)
    if (!std::isnan(values_dn[i])) others.push_back(values_dn[i]);
  FillMasked(values_dn, count, static_cast<float>(Median(std::move(others))));
  return masked;
}

}  // namespace platemeter::detect_internal
