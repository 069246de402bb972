// The chain file: every step's parameters as JSON (docs/simulator.md).
#include <nlohmann/json.hpp>

#include "platemeter/core/error.h"
#include "platemeter/samples/geometry.h"

namespace platemeter::sim {

using nlohmann::ordered_json;

std::string GeometryChain::ToJson() const {
  ordered_json j;
  j["order"] = {"thermal", "emulsion_depth", "film_deformation", "scanner"};
  j["thermal"] = {{"temperature_degC", thermal.temperature_degC},
                  {"calibration_temperature_degC", thermal.calibration_temperature_degC},
                  {"expansion_per_degC", thermal.expansion_per_degC},
                  {"scale", thermal.Scale()}};
  j["emulsion_depth"] = {{"depth_um", emulsion.depth_um},
                         {"refractive_index", emulsion.refractive_index},
                         {"principal_distance_mm", emulsion.principal_distance_mm},
                         {"principal_point_mm", {emulsion.principal_point_mm.x_mm, emulsion.principal_point_mm.y_mm}},
                         {"equivalent_scale", emulsion.EquivalentScale()}};
  ordered_json waves = ordered_json::array(), terms = ordered_json::array();
  for (const FilmWave& w : film.waves) {
    waves.push_back({{"amplitude_um", {w.amplitude_x_um, w.amplitude_y_um}},
                     {"wavelength_mm", w.wavelength_mm},
                     {"direction_deg", w.direction_deg},
                     {"phase_deg", w.phase_deg}});
  }
  for (const FilmPolynomialTerm& t : film.polynomial) {
    terms.push_back({{"power_x", t.power_x}, {"power_y", t.power_y},
                     {"amplitude_um", {t.amplitude_x_um, t.amplitude_y_um}}});
  }
  j["film_deformation"] = {
      {"affine_ppm", {film.affine_ppm[0], film.affine_ppm[1], film.affine_ppm[2], film.affine_ppm[3]}},
      {"shift_um", {film.shift_um[0], film.shift_um[1]}},
      {"normalization_mm", film.normalization_mm},
      {"waves", waves},
      {"polynomial", terms}};
  const Matrix2 m = scanner.PixelPerMm();
  j["scanner"] = {{"pixel_size_um", scanner.pixel_size_um},
                  {"pixel_aspect", scanner.pixel_aspect},
                  {"rotation_deg", scanner.rotation_deg},
                  {"non_orthogonality_arcsec", scanner.non_orthogonality_arcsec},
                  {"orientation_deg", scanner.orientation_deg},
                  {"mirrored", scanner.mirrored},
                  {"origin_px", {scanner.origin_px.x_px, scanner.origin_px.y_px}},
                  {"pixel_per_mm", {m.a[0], m.a[1], m.a[2], m.a[3]}}};
  return j.dump(2) + "\n";
}

GeometryChain GeometryChain::FromJson(const std::string& text, const std::string& origin) {
  GeometryChain chain;
  try {
    const auto j = nlohmann::json::parse(text);
    const auto& t = j.at("thermal");
    chain.thermal.temperature_degC = t.at("temperature_degC").get<double>();
    chain.thermal.calibration_temperature_degC = t.at("calibration_temperature_degC").get<double>();
    chain.thermal.expansion_per_degC = t.at("expansion_per_degC").get<double>();
    const auto& e = j.at("emulsion_depth");
    chain.emulsion.depth_um = e.at("depth_um").get<double>();
    chain.emulsion.refractive_index = e.at("refractive_index").get<double>();
    chain.emulsion.principal_distance_mm = e.at("principal_distance_mm").get<double>();
    chain.emulsion.principal_point_mm = {e.at("principal_point_mm").at(0).get<double>(),
                                         e.at("principal_point_mm").at(1).get<double>()};
    const auto& f = j.at("film_deformation");
    for (int i = 0; i < 4; ++i) chain.film.affine_ppm[i] = f.at("affine_ppm").at(i).get<double>();
    for (int i = 0; i < 2; ++i) chain.film.shift_um[i] = f.at("shift_um").at(i).get<double>();
    chain.film.normalization_mm = f.at("normalization_mm").get<double>();
    for (const auto& w : f.at("waves")) {
      chain.film.waves.push_back({w.at("amplitude_um").at(0).get<double>(), w.at("amplitude_um").at(1).get<double>(),
                                  w.at("wavelength_mm").get<double>(), w.at("direction_deg").get<double>(),
                                  w.at("phase_deg").get<double>()});
    }
    for (const auto& p : f.at("polynomial")) {
      chain.film.polynomial.push_back({p.at("power_x").get<int>(), p.at("power_y").get<int>(),
                                       p.at("amplitude_um").at(0).get<double>(),
                                       p.at("amplitude_um").at(1).get<double>()});
    }
    const auto& s = j.at("scanner");
    chain.scanner.pixel_size_um = s.at("pixel_size_um").get<double>();
    chain.scanner.pixel_aspect = s.at("pixel_aspect").get<double>();
    chain.scanner.rotation_deg = s.at("rotation_deg").get<double>();
    chain.scanner.non_orthogonality_arcsec = s.at("non_orthogonality_arcsec").get<double>();
    chain.scanner.orientation_deg = s.at("orientation_deg").get<int>();
    chain.scanner.mirrored = s.at("mirrored").get<bool>();
    chain.scanner.origin_px = {s.at("origin_px").at(0).get<double>(), s.at("origin_px").at(1).get<double>()};
  } catch (const nlohmann::json::exception& e) {
    throw Error(origin, std::string("malformed chain file: ") + OneLine(e.what()));
  }
  std::string why;
  if (!chain.Check(&why)) throw Error(origin, why);
  return chain;
}

}  // namespace platemeter::sim
