// Reads the simulator's spec (docs/simulator.md). Every problem is an Error
// "<file>: line N: <table>: <problem>"; unknown keys are errors.
#include "platemeter/samples/spec.h"

#include <cmath>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "platemeter/core/error.h"
#include "spec_toml.h"

namespace platemeter::sim {
namespace {

using spec_toml::LineOf;
using spec_toml::Table;

constexpr double kBig = 1e9;

void ReadLook(Table& t, SpecMarkLook* look) {
  t.Polarity("polarity", &look->dark);
  t.Number("contrast_dn", &look->contrast_dn, 0, 65535);
  look->line_width_um = t.OptionalNumber("line_width_um", 0.1, 5000);
  look->size_um = t.OptionalNumber("size_um", 1, 50000);
  t.Finish();
}

SpecPoint ReadPoint(const toml::table& table, const std::string& origin, const std::string& what, bool star) {
  Table t(table, origin, what);
  SpecPoint p;
  p.id = t.RequireString("id");
  if (p.id.empty() || p.id.find_first_of(",|\n\r") != std::string::npos) {
    t.Fail(LineOf(table), "id '" + p.id + "' must be non-empty without ',', '|' or newlines");
  }
  const auto x = t.OptionalNumber("x_mm", -1000, 1000), y = t.OptionalNumber("y_mm", -1000, 1000);
  if (!x || !y) t.Fail(LineOf(table), "point '" + p.id + "' needs x_mm and y_mm");
  p.x_mm = *x;
  p.y_mm = *y;
  if (star) {
    const auto m = t.OptionalNumber("magnitude", -30, 30);
    if (!m) t.Fail(LineOf(table), "star '" + p.id + "' needs a magnitude");
    p.magnitude = *m;
  }
  t.Finish();
  return p;
}

}  // namespace

SimulationSpec ParseSimulationSpec(const std::string& text, const std::string& origin) {
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw Error(origin, "line " + std::to_string(e.source().begin.line) + ": " + OneLine(std::string(e.description())));
  }
  SimulationSpec spec;
  spec.origin = origin;
  Table top(root, origin, "");
  spec.name = top.RequireString("name");
  static const std::regex kName("[A-Za-z0-9][A-Za-z0-9._-]*");
  if (!std::regex_match(spec.name, kName)) {
    top.Fail(top.Get("name"), "name '" + spec.name + "' must be a plain file name (letters, digits, '.', '_', '-')");
  }
  spec.description = top.String("description", "");
  spec.camera = top.RequireString("camera");
  if (const toml::node* node = top.Get("seed")) {
    if (!node->is_integer() || node->as_integer()->get() < 0) top.Fail(node, "key 'seed' must be a non-negative integer");
    spec.seed = static_cast<uint64_t>(node->as_integer()->get());
  }

  if (const toml::table* table = top.SubTable("output")) {
    Table t(*table, origin, "output");
    SpecOutput& o = spec.output;
    t.Number("pixel_size_um", &o.pixel_size_um, 0.5, 500);
    o.full_size_pixel_size_um = t.OptionalNumber("full_size_pixel_size_um", 0.5, 500);
    t.Number("margin_mm", &o.margin_mm, 0, 100);
    int width = 0, height = 0;
    t.Integer("width_px", &width, 16, 1000000);
    t.Integer("height_px", &height, 16, 1000000);
    if ((width > 0) != (height > 0)) t.Fail(table, "give both width_px and height_px or neither");
    if (width > 0) {
      o.width_px = width;
      o.height_px = height;
    }
    t.Integer("bits", &o.bits, 8, 16);
    if (o.bits != 8 && o.bits != 16) t.Fail(t.Get("bits"), "key 'bits' must be 8 or 16");
    t.Integer("tile_size_px", &o.tile_size_px, 0, 4096);
    if (o.tile_size_px % 16 != 0) t.Fail(t.Get("tile_size_px"), "key 'tile_size_px' must be a multiple of 16 (TIFF)");
    o.compression = t.String("compression", o.compression);
    if (o.compression != "none" && o.compression != "lzw" && o.compression != "zip") {
      t.Fail(t.Get("compression"), "key 'compression' must be \"none\", \"lzw\" or \"zip\"");
    }
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("thermal")) {
    Table t(*table, origin, "thermal");
    spec.thermal.temperature_degC = t.OptionalNumber("temperature_degC", -100, 100);
    spec.thermal.calibration_temperature_degC = t.OptionalNumber("calibration_temperature_degC", -100, 100);
    spec.thermal.expansion_per_degC = t.OptionalNumber("expansion_per_degC", -1e-3, 1e-3);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("emulsion")) {
    Table t(*table, origin, "emulsion");
    t.Number("depth_um", &spec.emulsion.depth_um, 0, 1000);
    t.Number("refractive_index", &spec.emulsion.refractive_index, 1, 3);
    spec.emulsion.principal_distance_mm = t.OptionalNumber("principal_distance_mm", 1, 10000);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("film")) {
    Table t(*table, origin, "film");
    FilmDeformationStep& f = spec.film;
    t.Numbers("affine_ppm", f.affine_ppm, 4, -1e4, 1e4);
    t.Numbers("shift_um", f.shift_um, 2, -1e4, 1e4);
    if (auto r = t.OptionalNumber("normalization_mm", 1, 1000)) {
      f.normalization_mm = *r;
      spec.film_normalization_given = true;
    }
    for (const toml::table* wt : t.TableArray("wave")) {
      Table w(*wt, origin, "film.wave");
      FilmWave wave;
      double amplitude[2] = {0, 0};
      w.Numbers("amplitude_um", amplitude, 2, -100, 100);
      wave.amplitude_x_um = amplitude[0];
      wave.amplitude_y_um = amplitude[1];
      w.Number("wavelength_mm", &wave.wavelength_mm, 5, 1e4);
      w.Number("direction_deg", &wave.direction_deg, -360, 360);
      w.Number("phase_deg", &wave.phase_deg, -360, 360);
      w.Finish();
      f.waves.push_back(wave);
    }
    for (const toml::table* pt : t.TableArray("polynomial")) {
      Table p(*pt, origin, "film.polynomial");
      FilmPolynomialTerm term;
      p.Integer("power_x", &term.power_x, 0, 5);
      p.Integer("power_y", &term.power_y, 0, 5);
      if (term.power_x + term.power_y > 5) p.Fail(pt, "power_x + power_y must be at most 5");
      double amplitude[2] = {0, 0};
      p.Numbers("amplitude_um", amplitude, 2, -100, 100);
      term.amplitude_x_um = amplitude[0];
      term.amplitude_y_um = amplitude[1];
      p.Finish();
      f.polynomial.push_back(term);
    }
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("scanner")) {
    Table t(*table, origin, "scanner");
    SpecScanner& s = spec.scanner;
    t.Number("pixel_aspect", &s.pixel_aspect, 0.5, 2);
    t.Number("rotation_deg", &s.rotation_deg, -45, 45);
    t.Number("non_orthogonality_arcsec", &s.non_orthogonality_arcsec, -3600, 3600);
    t.Integer("orientation_deg", &s.orientation_deg, 0, 270);
    if (s.orientation_deg % 90 != 0) t.Fail(t.Get("orientation_deg"), "key 'orientation_deg' must be 0, 90, 180 or 270");
    t.Bool("mirrored", &s.mirrored);
    t.Numbers("offset_px", s.offset_px, 2, -1e6, 1e6);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("marks")) {
    Table t(*table, origin, "marks");
    if (const toml::table* r = t.SubTable("reseau")) {
      Table rt(*r, origin, "marks.reseau");
      ReadLook(rt, &spec.reseau);
    }
    if (const toml::table* f = t.SubTable("fiducials")) {
      Table ft(*f, origin, "marks.fiducials");
      ReadLook(ft, &spec.fiducials);
    }
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("passpoints")) {
    Table t(*table, origin, "passpoints");
    SpecPasspoints& p = spec.passpoints;
    p.shape = t.String("shape", p.shape);
    if (p.shape != "dot" && p.shape != "ring") t.Fail(t.Get("shape"), "key 'shape' must be \"dot\" or \"ring\"");
    t.Number("diameter_um", &p.diameter_um, 1, 50000);
    t.Number("line_width_um", &p.line_width_um, 0.1, 5000);
    if (p.shape == "ring" && 2 * p.line_width_um >= p.diameter_um) {
      t.Fail(table, "a ring's line_width_um must be less than half its diameter_um");
    }
    t.Polarity("polarity", &p.dark);
    t.Number("contrast_dn", &p.contrast_dn, 0, 65535);
    t.Integer("count", &p.count, 0, 100000);
    t.Number("clearance_mm", &p.clearance_mm, 0, 100);
    for (const toml::table* pt : t.TableArray("point")) p.points.push_back(ReadPoint(*pt, origin, "passpoints.point", false));
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("stars")) {
    Table t(*table, origin, "stars");
    SpecStars& s = spec.stars;
    t.Integer("count", &s.count, 0, 1000000);
    t.Number("magnitude_min", &s.magnitude_min, -30, 30);
    t.Number("magnitude_max", &s.magnitude_max, -30, 30);
    if (s.magnitude_max < s.magnitude_min) t.Fail(table, "magnitude_max must not be less than magnitude_min");
    t.Number("reference_magnitude", &s.reference_magnitude, -30, 30);
    t.Number("reference_peak_dn", &s.reference_peak_dn, 0, 1e7);
    t.Number("fwhm_um", &s.fwhm_um, 0.5, 1000);
    t.Polarity("polarity", &s.dark);
    for (const toml::table* st : t.TableArray("star")) s.points.push_back(ReadPoint(*st, origin, "stars.star", true));
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("star_field")) {
    Table t(*table, origin, "star_field");
    SpecStarField& f = spec.star_field;
    f.enabled = true;
    t.Number("latitude_deg", &f.latitude_deg, -90, 90);
    t.Number("longitude_deg", &f.longitude_deg, -360, 360);
    t.Number("height_m", &f.height_m, -1000, 20000);
    f.start_utc = t.RequireString("start_utc");
    f.pressure_hpa = t.OptionalNumber("pressure_hpa", 0, 1500);
    t.Number("temperature_degC", &f.temperature_degC, -150, 200);
    t.Number("relative_humidity", &f.relative_humidity, 0, 1);
    t.Number("wavelength_um", &f.wavelength_um, 0.1, 1e6);
    t.Bool("refraction", &f.refraction);
    t.Number("ut1_minus_utc_s", &f.ut1_minus_utc_s, -0.9999, 0.9999);
    t.Number("axis_azimuth_deg", &f.axis_azimuth_deg, -360, 360);
    t.Number("axis_altitude_deg", &f.axis_altitude_deg, 0.001, 90);
    t.Number("roll_deg", &f.roll_deg, -360, 360);
    f.catalog = t.String("catalog", f.catalog);
    t.Number("magnitude_limit", &f.magnitude_limit, -30, 30);
    f.exposure = t.String("exposure", f.exposure);
    if (f.exposure != "duty_cycle" && f.exposure != "single") {
      t.Fail(t.Get("exposure"), "key 'exposure' must be \"duty_cycle\" or \"single\"");
    }
    if (const toml::node* node = t.Get("leading_dashes")) {
      const toml::array* array = node->as_array();
      if (!array || array->empty() || array->size() > 4) t.Fail(node, "key 'leading_dashes' must be an array of 1 to 4 integers");
      f.leading_dashes.clear();
      for (const toml::node& item : *array) {
        if (!item.is_integer() || item.as_integer()->get() < 2 || item.as_integer()->get() > 5) {
          t.Fail(node, "key 'leading_dashes' values must be integers 2..5");
        }
        f.leading_dashes.push_back(static_cast<int>(item.as_integer()->get()));
      }
    }
    t.Number("break_s", &f.break_s, 420, 600);
    t.Number("exposure_s", &f.exposure_s, 0, 86400);
    t.Number("reference_exposure_s", &f.reference_exposure_s, 1e-3, 86400);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("background")) {
    Table t(*table, origin, "background");
    SpecBackground& b = spec.background;
    t.Number("level_dn", &b.level_dn, 0, 65535);
    t.Number("terrain_amplitude_dn", &b.terrain_amplitude_dn, 0, 65535);
    t.Number("terrain_scale_mm", &b.terrain_scale_mm, 0.01, 1000);
    t.Number("vignetting_fraction", &b.vignetting_fraction, 0, 1);
    t.Number("vignetting_radius_mm", &b.vignetting_radius_mm, 0.1, 1000);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("noise")) {
    Table t(*table, origin, "noise");
    t.Number("blur_sigma_um", &spec.noise.blur_sigma_um, 0, 1000);
    t.Number("sensor_sigma_dn", &spec.noise.sensor_sigma_dn, 0, 65535);
    t.Number("grain_sigma_dn", &spec.noise.grain_sigma_dn, 0, 65535);
    t.Bool("quantize", &spec.noise.quantize);
    t.Finish();
  }
  if (const toml::table* table = top.SubTable("defects")) {
    Table t(*table, origin, "defects");
    SpecDefects& d = spec.defects;
    t.Integer("dust_count", &d.dust_count, 0, 1000000);
    t.Number("dust_diameter_min_um", &d.dust_diameter_min_um, 1, 1e5);
    t.Number("dust_diameter_max_um", &d.dust_diameter_max_um, 1, 1e5);
    if (d.dust_diameter_max_um < d.dust_diameter_min_um) t.Fail(table, "dust_diameter_max_um < dust_diameter_min_um");
    t.Number("dust_contrast_dn", &d.dust_contrast_dn, 0, 65535);
    t.Polarity("dust_polarity", &d.dust_dark);
    t.Integer("scratch_count", &d.scratch_count, 0, 100000);
    t.Number("scratch_length_mm", &d.scratch_length_mm, 0.01, 1000);
    t.Number("scratch_width_um", &d.scratch_width_um, 0.1, 5000);
    t.Number("scratch_contrast_dn", &d.scratch_contrast_dn, 0, 65535);
    t.Polarity("scratch_polarity", &d.scratch_dark);
    d.missing_crosses = t.Strings("missing_crosses");
    d.damaged_crosses = t.Strings("damaged_crosses");
    t.Number("damage_fraction", &d.damage_fraction, 0, 1);
    for (const toml::table* ft : t.TableArray("false_mark")) {
      Table f(*ft, origin, "defects.false_mark");
      SpecFalseMark mark;
      mark.near = f.RequireString("near");
      f.Numbers("offset_um", mark.offset_um, 2, -1e5, 1e5);
      f.Finish();
      d.false_marks.push_back(mark);
    }
    d.saturation_dn = t.OptionalNumber("saturation_dn", 1, 65535);
    t.Finish();
  }
  top.Finish();
  return spec;
}

SimulationSpec ReadSimulationSpec(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the spec file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseSimulationSpec(buffer.str(), path);
}

}  // namespace platemeter::sim
