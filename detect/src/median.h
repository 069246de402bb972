#pragma once
// The median the detectors use for backgrounds and robust spreads (not installed).
#include <algorithm>
#include <vector>

namespace platemeter::detect_internal {

// The upper median (the element at size / 2 in order); 0 for no values.
inline double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

}  // namespace platemeter::detect_internal
