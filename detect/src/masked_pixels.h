#pragma once
// Masked pixels (no value in the scan; core/image.h returns them as NaN) in the
// detectors' correlation and filter inputs, which must not see NaN: one NaN
// would spread over a template's or a kernel's whole footprint. Fits never get
// here: they leave masked pixels out of their samples. (Not installed.)
#include <cstddef>

namespace platemeter::detect_internal {

// Replaces the masked values with `fill`; returns how many there were. A clean
// window costs one pass of comparisons.
size_t FillMasked(float* values_dn, size_t count, float fill);

// Replaces the masked values with the median of the others (flat: no structure
// a template could match; 0 when all are masked); returns how many there were.
size_t FillMaskedWithMedian(float* values_dn, size_t count);

}  // namespace platemeter::detect_internal
