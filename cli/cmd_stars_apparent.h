#pragma once
// platemeter stars apparent: observed places of a list of stars (or of the
// KStars catalog) at a site, a UTC instant and an atmosphere, through
// calib/apparent_place.h (ERFA: eraApco13, eraAtciq, eraAtioq). The output is
// what the stellar calibration uses (seed 001: "corrected for atmospheric
// refraction and diurnal aberration, and transformed to a local cartesian
// coordinate system"): observed azimuth and altitude, observed hour angle and
// declination, and the local east-north-up unit vector. docs/apparent-places.md.
//
//   platemeter stars apparent --stars list.csv --utc 1972-10-10T03:00:00Z
//       --lat-deg 39.03 --lon-deg -76.93 --height-m 50
//       --pressure-hpa 1010 --temperature-degc 8 --humidity 0.6 --wavelength-um 0.45
#include <istream>
#include <string>
#include <vector>

#include "commands.h"
#include "platemeter/calib/apparent_place.h"
#include "platemeter/calib/star_catalog.h"

namespace platemeter::cli {

// A star list as CSV: '#' comment lines and blank lines are skipped; the first
// other line is the header naming the columns (any order):
//   ra_deg, dec_deg     ICRS position at epoch_jyear (required)
//   id                  integer (default: the 1-based row number)
//   pm_ra_mas_yr        mu_alpha* = dRA/dt cos(dec), mas/yr (default 0)
//   pm_dec_mas_yr       mas/yr (default 0)
//   parallax_mas        mas (default 0: no parallax, great-circle proper motion)
//   rv_km_s             radial velocity, km/s, positive receding (default 0)
//   epoch_jyear         Julian epoch (TDB) of ra/dec, "2000", "J2000.0", "1991.25" (default 2000)
//   v_mag               magnitude, carried to the output (default 0)
// An unknown column name, a missing required column or a bad number throws
// platemeter::Error(source, "line N: reason").
std::vector<calib::CatalogStar> ReadStarListCsv(std::istream& in, const std::string& source);

struct ApparentPlaceRow {
  calib::CatalogStar star;
  calib::ObservedPlace place;
};

// The output CSV: a '#' comment block with the settings, then
// id,v_mag,az_deg,alt_deg,zd_deg,ha_deg,dec_obs_deg,east,north,up
// (azimuth from north through east; hour angle west positive; east/north/up the
// unit vector of (az, alt); all observed, i.e. refracted unless refraction is off).
std::string FormatApparentPlacesCsv(const std::vector<ApparentPlaceRow>& rows,
                                    const calib::ApparentPlaceOptions& options, const calib::UtcInstant& utc);

// Adds `stars` with its subcommand `apparent`.
void RegisterStarsCommand(CLI::App& app, GlobalOptions& global);

}  // namespace platemeter::cli
