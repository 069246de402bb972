// platemeter stars apparent: observed places of listed or catalog stars
// (cmd_stars_apparent.h, docs/apparent-places.md).
#include "cmd_stars_apparent.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"

namespace platemeter::cli {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kArcsec = kPi / 648000.0;

std::string TrimSpace(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) out.push_back(TrimSpace(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double ParseNumber(const std::string& text, const std::string& column, const std::string& where) {
  std::string t = text;
  if (column == "epoch_jyear" && !t.empty() && (t[0] == 'J' || t[0] == 'j')) t.erase(0, 1);
  double value = 0.0;
  const char* end = t.data() + t.size();
  const auto [ptr, ec] = std::from_chars(t.data(), end, value);
  if (t.empty() || ec != std::errc() || ptr != end || !std::isfinite(value))
    throw Error(where, fmt::format("{} '{}' is not a number", column, text));
  return value;
}

const std::vector<std::string>& KnownColumns() {
  static const std::vector<std::string> kColumns = {"id",           "ra_deg",  "dec_deg",     "pm_ra_mas_yr",
                                                    "pm_dec_mas_yr", "parallax_mas", "rv_km_s", "epoch_jyear",
                                                    "v_mag"};
  return kColumns;
}

struct StarsApparentArgs {
  std::string stars;    // CSV star list, "-" for stdin
  std::string catalog;  // KStars catalog file
  double faint_mag = 6.0;
  std::string utc;
  double lat_deg = 0.0, lon_deg = 0.0, height_m = 0.0;
  double pressure_hpa = 1013.25;
  double temperature_degC = 10.0;
  double humidity = 0.5;
  double wavelength_um = 0.55;
  bool no_refraction = false;
  double ut1_utc_s = 0.0;
  double xp_arcsec = 0.0, yp_arcsec = 0.0;
  double min_alt_deg = -90.0;
  std::string output;
};

void RunStarsApparent(const StarsApparentArgs& args) {
  if (args.stars.empty() == args.catalog.empty())
    throw Error("stars apparent", "give exactly one of --stars FILE and --catalog FILE");
  calib::ApparentPlaceOptions options;
  options.site.latitude_rad = args.lat_deg * kDeg;
  options.site.longitude_rad = args.lon_deg * kDeg;
  options.site.height_m = args.height_m;
  options.refraction = !args.no_refraction;
  options.pressure_hpa = args.pressure_hpa;
  options.temperature_degC = args.temperature_degC;
  options.relative_humidity = args.humidity;
  options.wavelength_um = args.wavelength_um;
  options.ut1_minus_utc_s = args.ut1_utc_s;
  options.polar_motion_x_rad = args.xp_arcsec * kArcsec;
  options.polar_motion_y_rad = args.yp_arcsec * kArcsec;
  std::string why;
  if (!options.Check(&why)) throw Error("stars apparent", why);
  const calib::UtcInstant utc = calib::ParseUtcIso8601(args.utc);

  std::vector<calib::CatalogStar> stars;
  if (!args.stars.empty()) {
    if (args.stars == "-") {
      stars = ReadStarListCsv(std::cin, "<stdin>");
    } else {
      std::ifstream in(args.stars);
      if (!in) throw Error(args.stars, "cannot open the star list");
      stars = ReadStarListCsv(in, args.stars);
    }
  } else {
    calib::StarQueryOptions query;
    query.faint_limit_mag = args.faint_mag;
    stars = calib::LoadStarCatalog(args.catalog, query);
  }

  const calib::ApparentPlaceCalculator calculator(options, utc);
  std::vector<ApparentPlaceRow> rows;
  rows.reserve(stars.size());
  for (const calib::CatalogStar& star : stars) {
    ApparentPlaceRow row{star, calculator.Observe(star)};
    if (row.place.altitude_rad >= args.min_alt_deg * kDeg) rows.push_back(std::move(row));
  }
  const std::string csv = FormatApparentPlacesCsv(rows, options, utc);
  if (args.output.empty()) {
    std::cout << csv;
  } else {
    WriteFileAtomically(args.output, csv);
    std::cerr << fmt::format("wrote {} ({} of {} stars)\n", args.output, rows.size(), stars.size());
  }
}

}  // namespace

std::vector<calib::CatalogStar> ReadStarListCsv(std::istream& in, const std::string& source) {
  std::vector<calib::CatalogStar> stars;
  std::map<std::string, size_t> column;  // name -> index
  std::vector<std::string> names;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string trimmed = TrimSpace(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const std::string where = fmt::format("{} line {}", source, line_number);
    const std::vector<std::string> fields = SplitCsv(trimmed);
    if (names.empty()) {
      names = fields;
      for (size_t i = 0; i < names.size(); ++i) {
        const auto& known = KnownColumns();
        if (std::find(known.begin(), known.end(), names[i]) == known.end()) {
          std::string list;
          for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
          throw Error(where, fmt::format("unknown column '{}' (known: {})", names[i], list));
        }
        if (!column.emplace(names[i], i).second) throw Error(where, fmt::format("column '{}' twice", names[i]));
      }
      for (const char* required : {"ra_deg", "dec_deg"})
        if (!column.count(required)) throw Error(where, fmt::format("the header has no '{}' column", required));
      continue;
    }
    if (fields.size() != names.size())
      throw Error(where, fmt::format("{} fields, the header has {}", fields.size(), names.size()));
    auto value = [&](const char* name, double fallback) {
      const auto it = column.find(name);
      return it == column.end() ? fallback : ParseNumber(fields[it->second], name, where);
    };
    calib::CatalogStar s;
    const double id = value("id", static_cast<double>(stars.size() + 1));
    if (id != std::floor(id) || std::abs(id) > 9.0e15) throw Error(where, "id must be an integer");
    s.id = static_cast<int64_t>(id);
    const double ra_deg = value("ra_deg", 0.0), dec_deg = value("dec_deg", 0.0);
    if (!(std::abs(dec_deg) <= 90.0)) throw Error(where, fmt::format("dec_deg {} is outside -90..90", dec_deg));
    s.ra_rad = std::fmod(ra_deg, 360.0) * kDeg;
    if (s.ra_rad < 0.0) s.ra_rad += 2.0 * kPi;
    s.dec_rad = dec_deg * kDeg;
    s.pm_ra_mas_yr = value("pm_ra_mas_yr", 0.0);
    s.pm_dec_mas_yr = value("pm_dec_mas_yr", 0.0);
    s.parallax_mas = value("parallax_mas", 0.0);
    if (s.parallax_mas < 0.0)
      throw Error(where, fmt::format("parallax_mas {} is negative (give 0 for no parallax)", s.parallax_mas));
    s.radial_velocity_km_s = value("rv_km_s", 0.0);
    s.epoch_jyear = value("epoch_jyear", 2000.0);
    s.v_mag = value("v_mag", 0.0);
    stars.push_back(s);
  }
  if (names.empty()) throw Error(source, "no header line (e.g. id,ra_deg,dec_deg,pm_ra_mas_yr,...)");
  return stars;
}

std::string FormatApparentPlacesCsv(const std::vector<ApparentPlaceRow>& rows,
                                    const calib::ApparentPlaceOptions& o, const calib::UtcInstant& utc) {
  std::string out;
  out += "# platemeter stars apparent: observed places (ERFA eraApco13 + eraAtciq + eraAtioq)\n";
  out += fmt::format("# utc {}  site lat {:.9f} deg lon {:.9f} deg height {:.3f} m (WGS84)\n",
                     calib::FormatUtcIso8601(utc, 6), o.site.latitude_rad / kDeg, o.site.longitude_rad / kDeg,
                     o.site.height_m);
  if (o.refraction) {
    out += fmt::format("# refraction: pressure {} hPa, temperature {} degC, relative humidity {}, wavelength {} um\n",
                       o.pressure_hpa, o.temperature_degC, o.relative_humidity, o.wavelength_um);
  } else {
    out += "# refraction: off (vacuum topocentric directions)\n";
  }
  out += fmt::format("# UT1-UTC {} s, polar motion xp {} yp {} arcsec\n", o.ut1_minus_utc_s,
                     o.polar_motion_x_rad / kArcsec, o.polar_motion_y_rad / kArcsec);
  out += "id,v_mag,az_deg,alt_deg,zd_deg,ha_deg,dec_obs_deg,east,north,up\n";
  for (const ApparentPlaceRow& r : rows) {
    const calib::ObservedPlace& p = r.place;
    out += fmt::format("{},{:.2f},{:.10f},{:.10f},{:.10f},{:.10f},{:.10f},{:.12f},{:.12f},{:.12f}\n", r.star.id,
                       r.star.v_mag, p.azimuth_rad / kDeg, p.altitude_rad / kDeg, 90.0 - p.altitude_rad / kDeg,
                       p.hour_angle_rad / kDeg, p.declination_rad / kDeg, p.enu.x(), p.enu.y(), p.enu.z());
  }
  return out;
}

void RegisterStarsCommand(CLI::App& app, GlobalOptions& global) {
  (void)global;
  auto* stars = app.add_subcommand("stars", "star catalogs and star places");
  stars->require_subcommand(1);
  auto args = std::make_shared<StarsApparentArgs>();
  auto* cmd = stars->add_subcommand(
      "apparent",
      "observed places (azimuth, altitude, hour angle, declination, east-north-up vector) of stars at a site, a UTC "
      "instant and an atmosphere (docs/apparent-places.md)");
  cmd->add_option("--stars", args->stars,
                  "star list CSV (header: ra_deg,dec_deg[,id,pm_ra_mas_yr,pm_dec_mas_yr,parallax_mas,rv_km_s,"
                  "epoch_jyear,v_mag]); '-' reads stdin");
  cmd->add_option("--catalog", args->catalog, "or a KStars star catalog, e.g. " + calib::DefaultStarCatalogPath())
      ->check(CLI::ExistingFile);
  cmd->add_option("--faint-mag", args->faint_mag, "with --catalog: stars down to this magnitude")
      ->capture_default_str();
  cmd->add_option("--utc", args->utc, "the instant, ISO 8601 UTC (YYYY-MM-DDThh:mm:ss[.fff]Z)")->required();
  cmd->add_option("--lat-deg", args->lat_deg, "site geodetic latitude (WGS84), north positive")->required();
  cmd->add_option("--lon-deg", args->lon_deg, "site longitude, east positive")->required();
  cmd->add_option("--height-m", args->height_m, "site height above the WGS84 ellipsoid")->capture_default_str();
  cmd->add_option("--pressure-hpa", args->pressure_hpa, "pressure at the site (not reduced to sea level)")
      ->capture_default_str();
  cmd->add_option("--temperature-degc", args->temperature_degC, "air temperature at the site")->capture_default_str();
  cmd->add_option("--humidity", args->humidity, "relative humidity, a fraction 0..1")->capture_default_str();
  cmd->add_option("--wavelength-um", args->wavelength_um, "effective wavelength (emulsion x filter)")
      ->capture_default_str();
  cmd->add_flag("--no-refraction", args->no_refraction, "vacuum topocentric directions (same as --pressure-hpa 0)");
  cmd->add_option("--ut1-utc-s", args->ut1_utc_s, "UT1-UTC from the IERS (|.| < 0.9 s)")->capture_default_str();
  cmd->add_option("--xp-arcsec", args->xp_arcsec, "polar motion x from the IERS")->capture_default_str();
  cmd->add_option("--yp-arcsec", args->yp_arcsec, "polar motion y from the IERS")->capture_default_str();
  cmd->add_option("--min-alt-deg", args->min_alt_deg, "print only stars at or above this observed altitude")
      ->capture_default_str();
  cmd->add_option("-o,--output", args->output, "write the CSV here (atomically) instead of stdout");
  cmd->callback([args] { RunStarsApparent(*args); });
}

}  // namespace platemeter::cli
