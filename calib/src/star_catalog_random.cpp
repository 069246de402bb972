// Seeded random star field for tests that need stars but no catalog file.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/error.h"

namespace platemeter::calib {

bool RandomStarFieldOptions::Check(std::string* why) const {
  auto fail = [&](const std::string& r) {
    if (why) *why = r;
    return false;
  };
  if (count < 0) return fail(fmt::format("star count {} is negative", count));
  if (!(radius_rad > 0.0 && radius_rad <= std::numbers::pi))
    return fail(fmt::format("cone radius {} rad is outside (0, pi]", radius_rad));
  if (!(std::abs(center_dec_rad) <= std::numbers::pi / 2) || !std::isfinite(center_ra_rad))
    return fail("cone centre is not a valid direction");
  if (!(bright_mag <= faint_mag) || !std::isfinite(bright_mag) || !std::isfinite(faint_mag))
    return fail(fmt::format("magnitude range {}..{} is empty or not finite", bright_mag, faint_mag));
  if (!(pm_sigma_mas_yr >= 0.0) || !(parallax_max_mas >= 0.0))
    return fail("proper-motion sigma and parallax maximum must be >= 0");
  return true;
}

std::vector<CatalogStar> GenerateRandomStarField(const RandomStarFieldOptions& o) {
  std::string why;
  if (!o.Check(&why)) throw Error("random star field", why);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  constexpr double kPi = std::numbers::pi;
  // Counts rise by 10^0.544 (~3.5) per magnitude: sample m by inverting that CDF.
  constexpr double kSlope = 0.544;
  const double lo = std::pow(10.0, kSlope * o.bright_mag), hi = std::pow(10.0, kSlope * o.faint_mag);

  // Centre frame: c (centre), e (east), n (north).
  const double ca = std::cos(o.center_ra_rad), sa = std::sin(o.center_ra_rad);
  const double cd = std::cos(o.center_dec_rad), sd = std::sin(o.center_dec_rad);
  const double c[3] = {cd * ca, cd * sa, sd}, e[3] = {-sa, ca, 0.0}, n[3] = {-sd * ca, -sd * sa, cd};
  const double cos_r = std::cos(o.radius_rad);

  std::vector<CatalogStar> out;
  out.reserve(o.count);
  for (int i = 0; i < o.count; ++i) {
    const double cos_t = cos_r + (1.0 - cos_r) * uniform(rng);  // uniform on the cap
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
    const double phi = 2.0 * kPi * uniform(rng);
    double v[3];
    for (int k = 0; k < 3; ++k)
      v[k] = cos_t * c[k] + sin_t * (std::cos(phi) * e[k] + std::sin(phi) * n[k]);
    CatalogStar s;
    s.id = i + 1;
    s.ra_rad = std::atan2(v[1], v[0]);
    if (s.ra_rad < 0.0) s.ra_rad += 2.0 * kPi;
    s.dec_rad = std::asin(std::clamp(v[2], -1.0, 1.0));
    s.v_mag = o.bright_mag < o.faint_mag
                  ? std::log10(lo + uniform(rng) * (hi - lo)) / kSlope
                  : o.bright_mag;
    s.pm_ra_mas_yr = o.pm_sigma_mas_yr * normal(rng);
    s.pm_dec_mas_yr = o.pm_sigma_mas_yr * normal(rng);
    s.parallax_mas = o.parallax_max_mas * uniform(rng);
    out.push_back(s);
  }
  return out;
}

}  // namespace platemeter::calib
