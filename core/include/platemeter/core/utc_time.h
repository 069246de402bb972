#pragma once
// UTC instants (DESIGN.md: time is UTC) as ERFA's two-part quasi Julian Date,
// and their ISO 8601 text. In core because the detect/measure pipeline tags
// trail dots with times and the calibration computes apparent places at them.
#include <string>

namespace platemeter {

// ERFA's two-part UTC quasi Julian Date (jd1 + jd2; leap-second aware).
struct UtcInstant {
  double jd1 = 2451545.0;
  double jd2 = 0.0;
  double Mjd() const { return (jd1 - 2400000.5) + jd2; }
  // A later instant; seconds are counted as 1/86400 day (exact unless a leap
  // second falls inside the interval).
  UtcInstant PlusSeconds(double seconds) const { return {jd1, jd2 + seconds / 86400.0}; }
};

// ISO 8601 UTC: "YYYY-MM-DDThh:mm:ss[.fff][Z|+00:00]" ('T' or a space; seconds
// may be 60 in a leap second). Throws platemeter::Error(text, reason).
UtcInstant ParseUtcIso8601(const std::string& text);
// Inverse of ParseUtcIso8601, with `decimals` digits of seconds, 'Z' suffix.
std::string FormatUtcIso8601(const UtcInstant& utc, int decimals = 3);
UtcInstant UtcFromMjd(double mjd_utc);

}  // namespace platemeter
