#pragma once
// Observed places of catalog stars with ERFA (IAU SOFA): from ICRS catalog data
// (position, proper motion, parallax, radial velocity, epoch) to the direction a
// ground camera sees at a UTC instant: space motion, parallax, light deflection
// by the Sun, annual aberration, precession-nutation (IAU 2006/2000A), Earth
// rotation, polar motion, diurnal aberration and (optionally) refraction.
// Route: eraApco13 once per instant (star-independent parameters), then per star
// eraAtciq (ICRS -> CIRS) and eraAtioq (CIRS -> observed); the same chain as
// eraAtco13, with the per-instant work shared by all stars of a plate.
//
// Local cartesian frame of the result (seed 001 "local cartesian coordinate
// system"): x east, y north, z zenith (geodetic normal), right-handed.
//
// Earth orientation: UT1-UTC and polar motion default to 0. |UT1-UTC| < 0.9 s,
// so the default misplaces the hour angle by up to 0.9 s * 15"/s = 13.5"
// (times cos(dec) on the sky); polar motion (< ~0.5") moves the site's zenith by
// as much. For the simulator this is a convention shared by truth and test; for
// real plates give the IERS values for the night.
#include <memory>
#include <string>

#include <Eigen/Core>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/utc_time.h"

namespace platemeter::calib {

// UTC instants live in core (the pipeline tags trail dots with them).
using ::platemeter::FormatUtcIso8601;
using ::platemeter::ParseUtcIso8601;
using ::platemeter::UtcFromMjd;
using ::platemeter::UtcInstant;

struct ObservingSite {
  double latitude_rad = 0.0;   // geodetic (WGS84), north positive
  double longitude_rad = 0.0;  // east positive
  double height_m = 0.0;       // above the WGS84 ellipsoid

  // Seed 004 camera mount: 32 32'00"N, 106 36'00"W, 1501.0 m.
  static ObservingSite Seed004CameraMount();
};

struct ApparentPlaceOptions {
  ObservingSite site;
  bool refraction = true;           // false: the unrefracted (vacuum) topocentric direction
  double pressure_hpa = 1013.25;    // pressure at the site (not reduced to sea level), 0..1500
  double temperature_degC = 10.0;   // ambient temperature at the site, -150..200
  double relative_humidity = 0.5;   // 0..1
  double wavelength_um = 0.55;      // effective wavelength (emulsion x filter), 0.1..1e6
  double ut1_minus_utc_s = 0.0;     // UT1-UTC (IERS), |.| < 1 (see the note above)
  double polar_motion_x_rad = 0.0;  // IERS xp
  double polar_motion_y_rad = 0.0;  // IERS yp

  bool Check(std::string* why) const;
};

struct ObservedPlace {
  double azimuth_rad = 0.0;        // from north through east, 0..2pi
  double altitude_rad = 0.0;       // above the horizon (refracted if options.refraction)
  double hour_angle_rad = 0.0;     // observed hour angle (west positive), -pi..pi
  double declination_rad = 0.0;    // observed declination
  Eigen::Vector3d enu = Eigen::Vector3d::UnitZ();  // unit vector: x east, y north, z zenith
};

// Star-independent astrometry for one site, instant and atmosphere; Observe()
// is cheap per star. Throws platemeter::Error for bad options or a date ERFA
// cannot handle (before 1960 UTC).
class ApparentPlaceCalculator {
 public:
  ApparentPlaceCalculator(const ApparentPlaceOptions& options, const UtcInstant& utc);
  ~ApparentPlaceCalculator();
  ApparentPlaceCalculator(ApparentPlaceCalculator&&) noexcept;
  ApparentPlaceCalculator& operator=(ApparentPlaceCalculator&&) noexcept;

  ObservedPlace Observe(const CatalogStar& star) const;
  // The inverse: the ICRS place (J2000.0, no proper motion or parallax) of a
  // star seen in the direction `enu` (x east, y north, z up), through ERFA's
  // eraAtoiq and eraAticq (refraction, aberration, light deflection undone).
  // Observe() of the result returns `enu` to well under 0.01".
  CatalogStar Unobserve(const Eigen::Vector3d& enu) const;
  // True when ERFA flags the date as beyond its leap-second table (UTC-TAI may be off by whole seconds).
  bool dubious_date() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-shot convenience.
ObservedPlace ObserveStar(const CatalogStar& star, const ApparentPlaceOptions& options, const UtcInstant& utc);

// Space motion (eraPmsafe: proper motion, parallax, radial velocity) from the
// star's epoch to `epoch_jyear` (Julian epoch, TDB). Returns the star with
// position, proper motion, parallax, radial velocity and epoch updated.
CatalogStar PropagateCatalogStar(const CatalogStar& star, double epoch_jyear);

}  // namespace platemeter::calib
