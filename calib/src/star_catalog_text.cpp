// KStars text star catalog (fixed columns, documented in star_catalog.h).
#include <charconv>
#include <cmath>
#include <numbers>
#include <string_view>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "star_catalog_formats.h"

namespace platemeter::calib::detail {
namespace {


std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Parses columns [first, last] (1-based, inclusive) as a number; false if malformed.
bool Field(const std::string& line, int first, int last, double* value) {
  if (static_cast<int>(line.size()) < last) return false;
  std::string_view s = Trim(std::string_view(line).substr(first - 1, last - first + 1));
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *value);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// "hhmmss.ss" (RA) or "sddmmss.s" (Dec) to the sexagesimal value in hours or degrees.
bool Sexagesimal(const std::string& line, int first, int last, bool has_sign, double* value) {
  if (static_cast<int>(line.size()) < last) return false;
  std::string_view s = std::string_view(line).substr(first - 1, last - first + 1);
  double sign = 1.0;
  if (has_sign) {
    if (s.front() == '-') sign = -1.0;
    else if (s.front() != '+' && s.front() != ' ') return false;
    s.remove_prefix(1);
  }
  if (s.size() < 6) return false;
  int whole = 0, minutes = 0;
  for (int i = 0; i < 4; ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  whole = (s[0] - '0') * 10 + (s[1] - '0');
  minutes = (s[2] - '0') * 10 + (s[3] - '0');
  double seconds = 0.0;
  const std::string_view sec = s.substr(4);
  const auto r = std::from_chars(sec.data(), sec.data() + sec.size(), seconds);
  if (r.ec != std::errc() || r.ptr != sec.data() + sec.size()) return false;
  // The file rounds 59.995 s up to "60.00" without carrying (12 records): accept 60.
  if (minutes >= 60 || seconds < 0.0 || seconds > 60.0) return false;
  *value = sign * (whole + minutes / 60.0 + seconds / 3600.0);
  return true;
}

}  // namespace

void ReadTextStarCatalog(std::ifstream& in, const std::string& path, const StarSelector& select,
                         std::vector<CatalogStar>* out) {
  std::string line;
  int64_t line_no = 0, record = 0;
  auto bad = [&](const std::string& what) {
    throw Error(path, fmt::format("line {}: {} in \"{}\"", line_no, what, line.substr(0, 80)));
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    ++record;
    double v_mag = 0.0;
    if (!Field(line, 46, 51, &v_mag)) bad("malformed V magnitude (columns 46-51)");
    if (!select.KeepMagnitude(v_mag)) continue;
    double ra_h = 0.0, dec_deg = 0.0;
    if (!Sexagesimal(line, 1, 9, false, &ra_h) || ra_h >= 24.0) bad("malformed RA (columns 1-9, hhmmss.ss)");
    if (!Sexagesimal(line, 11, 19, true, &dec_deg) || std::abs(dec_deg) > 90.0)
      bad("malformed Dec (columns 11-19, sddmmss.s)");
    const double ra = ra_h * std::numbers::pi / 12.0, dec = dec_deg * std::numbers::pi / 180.0;
    if (!select.KeepPosition(ra, dec)) continue;

    CatalogStar s;
    s.id = record;
    s.ra_rad = ra;
    s.dec_rad = dec;
    s.v_mag = v_mag;
    if (!Field(line, 21, 29, &s.pm_ra_mas_yr)) bad("malformed pmRA (columns 21-29)");
    if (!Field(line, 30, 38, &s.pm_dec_mas_yr)) bad("malformed pmDec (columns 30-38)");
    if (!Field(line, 39, 45, &s.parallax_mas)) bad("malformed parallax (columns 39-45)");
    if (!Field(line, 52, 56, &s.bv_mag)) s.bv_mag = 0.0;  // optional colour
    if (line.size() >= 58) {
      const std::string_view spt = Trim(std::string_view(line).substr(56, 2));
      s.spectral_type = std::string(spt);
    }
    // ", genitive, common name" (either may be missing).
    const size_t comma = line.find(',', 56);
    if (comma != std::string::npos) {
      std::string_view rest = std::string_view(line).substr(comma + 1);
      const size_t second = rest.find(',');
      const std::string_view genitive = Trim(rest.substr(0, second));
      const std::string_view common =
          second == std::string_view::npos ? std::string_view() : Trim(rest.substr(second + 1));
      s.name = std::string(common.empty() ? genitive : common);
    }
    out->push_back(std::move(s));
  }
  if (in.bad()) throw Error(path, fmt::format("read error after line {}", line_no));
  if (record == 0) throw Error(path, "no star records in the text catalog");
}

}  // namespace platemeter::calib::detail
