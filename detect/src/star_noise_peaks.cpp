// How high pure noise reaches after the matched filter (star_internal.h).
#include <cmath>
#include <numbers>

#include "star_internal.h"

namespace platemeter::star_internal {

double ExpectedNoisePeaks(double area_px2, double filter_sigma_px, double level_sigma) {
  const double lambda = 1.0 / (2.0 * filter_sigma_px * filter_sigma_px);
  return area_px2 * lambda * level_sigma * std::exp(-0.5 * level_sigma * level_sigma) /
         std::pow(2.0 * std::numbers::pi, 1.5);
}

double NoisePeakLevel(double area_px2, double filter_sigma_px, double expected_peaks) {
  // N(u) falls monotonically above u = 1: bisection.
  double low = 1.0, high = 40.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (low + high);
    (ExpectedNoisePeaks(area_px2, filter_sigma_px, mid) > expected_peaks ? low : high) = mid;
  }
  return high;
}

}  // namespace platemeter::star_internal
