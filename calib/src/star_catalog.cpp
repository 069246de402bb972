#include "platemeter/calib/star_catalog.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "star_catalog_formats.h"

namespace platemeter::calib {

bool StarQueryOptions::Check(std::string* why) const {
  auto fail = [&](const std::string& r) {
    if (why) *why = r;
    return false;
  };
  if (!std::isfinite(faint_limit_mag)) return fail("faint magnitude limit is not finite");
  if (!whole_sky) {
    if (!std::isfinite(center_ra_rad) || !std::isfinite(center_dec_rad))
      return fail("cone centre is not finite");
    if (std::abs(center_dec_rad) > std::numbers::pi / 2 + 1e-12)
      return fail(fmt::format("cone centre declination {} rad is outside -pi/2..pi/2", center_dec_rad));
    if (!(radius_rad >= 0.0 && radius_rad <= std::numbers::pi))
      return fail(fmt::format("cone radius {} rad is outside 0..pi", radius_rad));
  }
  return true;
}

std::string DefaultStarCatalogPath() { return "/usr/share/kstars/stars.dat"; }

double AngularSeparation(double ra1_rad, double dec1_rad, double ra2_rad, double dec2_rad) {
  // Vincenty's formula: accurate at 0 and at pi.
  const double dra = ra2_rad - ra1_rad;
  const double s1 = std::sin(dec1_rad), c1 = std::cos(dec1_rad);
  const double s2 = std::sin(dec2_rad), c2 = std::cos(dec2_rad);
  const double x = c2 * std::sin(dra);
  const double y = c1 * s2 - s1 * c2 * std::cos(dra);
  const double z = s1 * s2 + c1 * c2 * std::cos(dra);
  return std::atan2(std::hypot(x, y), z);
}

std::vector<CatalogStar> LoadStarCatalog(const std::string& path, const StarQueryOptions& query) {
  std::string why;
  if (!query.Check(&why)) throw Error(path, "bad star query: " + why);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(path, "star catalog file not found (Debian: apt-get install kstars-data)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the star catalog for reading");

  // Layout detection: the binary file carries the marker 'S','K' (or 'K','S'
  // when written big-endian) right after its 124-byte description.
  char head[128] = {};
  in.read(head, sizeof head);
  const std::streamsize got = in.gcount();
  in.clear();
  in.seekg(0);
  const bool binary = got >= 127 && ((head[124] == 'S' && head[125] == 'K') ||
                                     (head[124] == 'K' && head[125] == 'S'));
  std::vector<CatalogStar> out;
  const detail::StarSelector select(query);
  if (binary) {
    detail::ReadBinaryStarCatalog(in, path, select, &out);
  } else if (got > 0 && (head[0] == '#' || (head[0] >= '0' && head[0] <= '9'))) {
    detail::ReadTextStarCatalog(in, path, select, &out);
  } else {
    throw Error(path, got == 0 ? "star catalog file is empty"
                               : "not a KStars star catalog (neither the text layout nor a starData binary)");
  }
  return out;
}

std::string CatalogStarKey(const CatalogStar& star) {
  return (star.id_is_hd ? "HD" : "KS") + std::to_string(star.id);
}

}  // namespace platemeter::calib
