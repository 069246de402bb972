#pragma once
// Catalogue angles as printed (hours/degrees, minutes, seconds) in radians, for the astrometry tests.
#include <numbers>

namespace platemeter::testing {

inline double Hms(double hours, double minutes, double seconds) {
  return (hours + minutes / 60 + seconds / 3600) * std::numbers::pi / 12;
}
inline double Dms(double sign, double degrees, double minutes, double seconds) {
  return sign * (degrees + minutes / 60 + seconds / 3600) * std::numbers::pi / 180;
}

}  // namespace platemeter::testing
