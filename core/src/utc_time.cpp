// UTC instants: ISO 8601 <-> ERFA two-part JD.
#include <algorithm>
#include <cmath>
#include <regex>

#include <erfa.h>
#include <fmt/format.h>

#include "platemeter/core/utc_time.h"

#include "platemeter/core/error.h"

namespace platemeter {

UtcInstant ParseUtcIso8601(const std::string& text) {
  // std::regex recurses per character: a long string would overflow the stack (found by fuzzing).
  // No ISO 8601 time with its fraction of a second needs more than 64 characters.
  constexpr size_t kMaxLength = 64;
  if (text.size() > kMaxLength) {
    throw Error(text.substr(0, 24) + "...", "not an ISO 8601 UTC time (" + std::to_string(text.size()) +
                                                " characters; at most " + std::to_string(kMaxLength) + ")");
  }
  // Only UTC is accepted (DESIGN.md: time is UTC); an explicit zero offset is fine.
  static const std::regex kIso(
      R"(^\s*(\d{4})-(\d{2})-(\d{2})[T ](\d{2}):(\d{2})(?::(\d{2}(?:\.\d*)?))?\s*(Z|[+-]00(?::?00)?)?\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, kIso)) {
    static const std::regex kOffset(R"([T ]\d{2}:\d{2}(:\d{2}(\.\d*)?)?\s*[+-]\d{2})");
    if (std::regex_search(text, kOffset))
      throw Error(text, "time zone offset other than UTC; give the time in UTC (suffix Z)");
    throw Error(text, "not an ISO 8601 UTC time (expected YYYY-MM-DDThh:mm:ss[.fff][Z])");
  }
  const int iy = std::stoi(m[1]), im = std::stoi(m[2]), id = std::stoi(m[3]);
  const int ih = std::stoi(m[4]), imin = std::stoi(m[5]);
  const double sec = m[6].matched ? std::stod(m[6]) : 0.0;
  UtcInstant utc;
  const int status = eraDtf2d("UTC", iy, im, id, ih, imin, sec, &utc.jd1, &utc.jd2);
  switch (status) {
    case 0:
    case 1:  // dubious year (outside the leap-second table's reach): accepted, flagged later
      return utc;
    case -1: throw Error(text, "year outside ERFA's calendar range");
    case -2: throw Error(text, "month is not 1..12");
    case -3: throw Error(text, "day does not exist in that month");
    case -4: throw Error(text, "hour is not 0..23");
    case -5: throw Error(text, "minute is not 0..59");
    case -6: throw Error(text, "negative seconds");
    default: throw Error(text, "seconds run past the end of the day (60 only in a leap second)");
  }
}

std::string FormatUtcIso8601(const UtcInstant& utc, int decimals) {
  decimals = std::clamp(decimals, 0, 9);
  int iy = 0, im = 0, id = 0, hmsf[4] = {};
  if (eraD2dtf("UTC", decimals, utc.jd1, utc.jd2, &iy, &im, &id, hmsf) < 0)
    throw Error(fmt::format("JD {} + {}", utc.jd1, utc.jd2), "date outside ERFA's calendar range");
  std::string out = fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}", iy, im, id, hmsf[0], hmsf[1], hmsf[2]);
  if (decimals > 0) out += fmt::format(".{:0{}d}", hmsf[3], decimals);
  return out + "Z";
}

UtcInstant UtcFromMjd(double mjd_utc) {
  const double day = std::floor(mjd_utc);
  return {2400000.5 + day, mjd_utc - day};
}

}  // namespace platemeter
