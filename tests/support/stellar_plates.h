#pragma once
// Simulated Orbigon star plates of the stellar-calibration tests (seed 001):
// Beltsville (assumed 39.03 N, 76.93 W, 50 m), the camera at the zenith, stars
// to V = 6, seed 001's duty cycle and selection of trail dots.
#include <cmath>
#include <string>

#include "platemeter/samples/stellar_plates.h"

namespace platemeter::testing {

inline sim::StellarPlateSimulation BeltsvillePlate(const std::string& id, const std::string& start_utc,
                                                   double roll_deg) {
  sim::StellarPlateSimulation s;
  s.plate_id = id;
  constexpr double kDeg = M_PI / 180.0;
  s.field.place.site = {39.03 * kDeg, -76.93 * kDeg, 50.0};
  s.field.start_utc = calib::ParseUtcIso8601(start_utc);
  s.field.roll_deg = roll_deg;
  s.magnitude_limit = 6.0;
  return s;
}

}  // namespace platemeter::testing
