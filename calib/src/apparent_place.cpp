// Observed places with ERFA: eraApco13 per instant, eraAtciq + eraAtioq per star.
#include "platemeter/calib/apparent_place.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <erfa.h>
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "platemeter/core/why.h"

namespace platemeter::calib {
namespace {

constexpr double kMasToRad = std::numbers::pi / (180.0 * 3600.0 * 1000.0);
constexpr double kDegToRad = std::numbers::pi / 180.0;

// ERFA wants dRA/dt (no cos dec); the catalogs give mu_alpha* = dRA/dt cos(dec).
// At the pole itself dRA/dt is undefined: the tiny floor keeps it finite.
double DraDtRadPerYear(const CatalogStar& s) {
  const double c = std::max(std::cos(s.dec_rad), 1e-12);
  return s.pm_ra_mas_yr * kMasToRad / c;
}

}  // namespace

ObservingSite ObservingSite::Seed004CameraMount() {
  return {(32.0 + 32.0 / 60.0) * kDegToRad, -(106.0 + 36.0 / 60.0) * kDegToRad, 1501.0};
}

bool ApparentPlaceOptions::Check(std::string* why) const {
  if (!(std::abs(site.latitude_rad) <= std::numbers::pi / 2))
    return Fail(why, fmt::format("site latitude {} rad is outside -pi/2..pi/2", site.latitude_rad));
  if (!std::isfinite(site.longitude_rad)) return Fail(why, "site longitude is not finite");
  if (!(site.height_m > -1000.0 && site.height_m < 20000.0))
    return Fail(why, fmt::format("site height {} m is outside -1000..20000", site.height_m));
  if (!(pressure_hpa >= 0.0 && pressure_hpa <= 1500.0))
    return Fail(why, fmt::format("pressure {} hPa is outside 0..1500", pressure_hpa));
  if (!(temperature_degC >= -150.0 && temperature_degC <= 200.0))
    return Fail(why, fmt::format("temperature {} degC is outside -150..200", temperature_degC));
  if (!(relative_humidity >= 0.0 && relative_humidity <= 1.0))
    return Fail(why, fmt::format("relative humidity {} is outside 0..1 (a fraction, not percent)", relative_humidity));
  if (!(wavelength_um >= 0.1 && wavelength_um <= 1e6))
    return Fail(why, fmt::format("wavelength {} um is outside 0.1..1e6", wavelength_um));
  if (!(std::abs(ut1_minus_utc_s) < 1.0))
    return Fail(why, fmt::format("UT1-UTC {} s; IERS keeps |UT1-UTC| < 0.9 s", ut1_minus_utc_s));
  const double one_arcsec = std::numbers::pi / 648000.0;
  if (!(std::abs(polar_motion_x_rad) < one_arcsec && std::abs(polar_motion_y_rad) < one_arcsec))
    return Fail(why, "polar motion must be below 1 arcsec (give radians, not arcsec)");
  return true;
}

struct ApparentPlaceCalculator::Impl {
  eraASTROM astrom{};
  bool dubious = false;
};

ApparentPlaceCalculator::ApparentPlaceCalculator(const ApparentPlaceOptions& options, const UtcInstant& utc)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.Check(&why)) throw Error("apparent place options", why);
  double eo = 0.0;
  const ObservingSite& s = options.site;
  const int status = eraApco13(utc.jd1, utc.jd2, options.ut1_minus_utc_s, s.longitude_rad, s.latitude_rad,
                               s.height_m, options.polar_motion_x_rad, options.polar_motion_y_rad,
                               options.pressure_hpa, options.temperature_degC, options.relative_humidity,
                               options.wavelength_um, &impl_->astrom, &eo);
  if (status < 0)
    throw Error(FormatUtcIso8601(utc), "date ERFA cannot convert (UTC before 1960 or out of range)");
  impl_->dubious = status > 0;
  if (impl_->dubious)
    Warn(fmt::format("{}: beyond ERFA's leap-second table; UTC-TAI may be off by whole seconds",
                     FormatUtcIso8601(utc)));
  if (!options.refraction) impl_->astrom.refa = impl_->astrom.refb = 0.0;
}

ApparentPlaceCalculator::~ApparentPlaceCalculator() = default;
ApparentPlaceCalculator::ApparentPlaceCalculator(ApparentPlaceCalculator&&) noexcept = default;
ApparentPlaceCalculator& ApparentPlaceCalculator::operator=(ApparentPlaceCalculator&&) noexcept = default;

bool ApparentPlaceCalculator::dubious_date() const { return impl_->dubious; }

ObservedPlace ApparentPlaceCalculator::Observe(const CatalogStar& star) const {
  // eraAtciq measures the proper-motion interval from J2000.0: move other epochs there first.
  const CatalogStar s = std::abs(star.epoch_jyear - 2000.0) > 1e-9 ? PropagateCatalogStar(star, 2000.0) : star;
  double ri = 0.0, di = 0.0;
  // eraAtciq/eraAtioq take a non-const pointer but do not modify astrom.
  eraASTROM* astrom = &impl_->astrom;
  eraAtciq(s.ra_rad, s.dec_rad, DraDtRadPerYear(s), s.pm_dec_mas_yr * kMasToRad, s.parallax_mas / 1000.0,
           s.radial_velocity_km_s, astrom, &ri, &di);
  double aob = 0.0, zob = 0.0, hob = 0.0, dob = 0.0, rob = 0.0;
  eraAtioq(ri, di, astrom, &aob, &zob, &hob, &dob, &rob);
  ObservedPlace p;
  p.azimuth_rad = eraAnp(aob);
  p.altitude_rad = std::numbers::pi / 2 - zob;
  p.hour_angle_rad = eraAnpm(hob);
  p.declination_rad = dob;
  const double ca = std::cos(p.altitude_rad);
  p.enu = Eigen::Vector3d(ca * std::sin(p.azimuth_rad), ca * std::cos(p.azimuth_rad), std::sin(p.altitude_rad));
  return p;
}

CatalogStar ApparentPlaceCalculator::Unobserve(const Eigen::Vector3d& enu) const {
  const Eigen::Vector3d u = enu.normalized();
  const double azimuth_rad = std::atan2(u.x(), u.y());
  const double zenith_distance_rad = std::acos(std::clamp(u.z(), -1.0, 1.0));
  eraASTROM* astrom = &impl_->astrom;  // not modified (see Observe)
  double ri = 0.0, di = 0.0;
  eraAtoiq("A", azimuth_rad, zenith_distance_rad, astrom, &ri, &di);
  double rc = 0.0, dc = 0.0;
  eraAticq(ri, di, astrom, &rc, &dc);
  CatalogStar star;
  star.ra_rad = eraAnp(rc);
  star.dec_rad = dc;
  star.epoch_jyear = 2000.0;
  return star;
}

ObservedPlace ObserveStar(const CatalogStar& star, const ApparentPlaceOptions& options, const UtcInstant& utc) {
  return ApparentPlaceCalculator(options, utc).Observe(star);
}

CatalogStar PropagateCatalogStar(const CatalogStar& star, double epoch_jyear) {
  if (!std::isfinite(epoch_jyear) || !std::isfinite(star.epoch_jyear))
    throw Error(fmt::format("star {}", star.id), "epoch is not finite");
  CatalogStar out = star;
  out.epoch_jyear = epoch_jyear;
  if (!(star.parallax_mas > 0.0)) {
    // No distance: eraPmsafe would invent one and then cap the implied
    // velocity. Move along the great circle instead (eraPmpx with the observer
    // at the barycentre); the proper motion is kept.
    double p[3] = {}, pob[3] = {0.0, 0.0, 0.0};
    eraPmpx(star.ra_rad, star.dec_rad, DraDtRadPerYear(star), star.pm_dec_mas_yr * kMasToRad, 0.0, 0.0,
            epoch_jyear - star.epoch_jyear, pob, p);
    double ra = 0.0, dec = 0.0;
    eraC2s(p, &ra, &dec);
    out.ra_rad = eraAnp(ra);
    out.dec_rad = dec;
    return out;
  }
  double a1 = 0.0, a2 = 0.0, b1 = 0.0, b2 = 0.0;
  eraEpj2jd(star.epoch_jyear, &a1, &a2);
  eraEpj2jd(epoch_jyear, &b1, &b2);
  double ra = 0.0, dec = 0.0, pmr = 0.0, pmd = 0.0, px = 0.0, rv = 0.0;
  const int status = eraPmsafe(star.ra_rad, star.dec_rad, DraDtRadPerYear(star), star.pm_dec_mas_yr * kMasToRad,
                               star.parallax_mas / 1000.0, star.radial_velocity_km_s, a1, a2, b1, b2, &ra, &dec,
                               &pmr, &pmd, &px, &rv);
  if (status < 0 || status >= 2)  // 1 = distance overridden: harmless
    throw Error(fmt::format("star {}", star.id),
                fmt::format("space motion failed (eraPmsafe status {}: excessive velocity or no convergence)",
                            status));
  out.ra_rad = eraAnp(ra);
  out.dec_rad = dec;
  out.pm_ra_mas_yr = pmr * std::cos(dec) / kMasToRad;
  out.pm_dec_mas_yr = pmd / kMasToRad;
  out.parallax_mas = px * 1000.0;
  out.radial_velocity_km_s = rv;
  return out;
}

}  // namespace platemeter::calib
