// Spec + camera definitions -> geometry chain, scene and truth (docs/simulator.md).
#include "platemeter/samples/simulate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "platemeter/core/error.h"
#include "platemeter/samples/star_field.h"

namespace platemeter::sim {
namespace {

// Independent random streams per component, all derived from the one seed.
uint64_t DeriveSeed(uint64_t seed, uint64_t component) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (component + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
enum Component : uint64_t { kNoise = 1, kPasspoints, kStars, kDust, kScratches, kDamage, kTerrain };

MarkShapeKind ShapeOf(MarkType type) {
  switch (type) {
    case MarkType::kCross: return MarkShapeKind::kCross;
    case MarkType::kDot: return MarkShapeKind::kDot;
    case MarkType::kRing: return MarkShapeKind::kRing;
    case MarkType::kCorner: return MarkShapeKind::kCorner;
  }
  return MarkShapeKind::kCross;
}

void SetLocalMap(const GeometryChain& chain, PlatePoint p, SceneMark* mark) {
  mark->centre_px = chain.PixelFromPlate(p);
  const Matrix2 m = chain.PxFromUm(p);
  for (int k = 0; k < 4; ++k) mark->px_from_um[k] = m.a[k];
}

MeasuredPoint TruthPoint(const std::string& id, PointKind kind, PlatePoint p, const PixelPoint& px) {
  MeasuredPoint t;
  t.id = id;
  t.kind = kind;
  t.status = PointStatus::kTruth;
  t.x_px = px.x_px;
  t.y_px = px.y_px;
  t.x_mm = p.x_mm;
  t.y_mm = p.y_mm;
  return t;
}

struct Builder {
  const SimulationSpec& spec;
  SimulatedPlate& plate;

  [[noreturn]] void Fail(const std::string& reason) const { throw Error(spec.origin, reason); }

  void AddMark(SceneMark mark, const std::string& truth_id, PointKind kind, PlatePoint p,
               std::vector<std::string> flags = {}) {
    plate.scene.marks.push_back(std::move(mark));
    MeasuredPoint t = TruthPoint(truth_id, kind, p, plate.scene.marks.back().centre_px);
    t.flags = std::move(flags);
    plate.truth.push_back(std::move(t));
    plate.truth_mark.push_back(static_cast<int>(plate.scene.marks.size()) - 1);
  }
};

StarFieldOptions StarFieldOptionsOf(const SimulationSpec& spec) {
  const SpecStarField& f = spec.star_field;
  constexpr double kDeg = std::numbers::pi / 180.0;
  StarFieldOptions o;
  o.place.site = {f.latitude_deg * kDeg, f.longitude_deg * kDeg, f.height_m};
  // ERFA's standard atmosphere (eraRefco notes): p = 1013.25 exp(-h / (29.3 T)).
  o.place.pressure_hpa = f.pressure_hpa.value_or(1013.25 * std::exp(-f.height_m / (29.3 * (273.15 + f.temperature_degC))));
  o.place.temperature_degC = f.temperature_degC;
  o.place.relative_humidity = f.relative_humidity;
  o.place.wavelength_um = f.wavelength_um;
  o.place.refraction = f.refraction;
  o.place.ut1_minus_utc_s = f.ut1_minus_utc_s;
  try {
    o.start_utc = calib::ParseUtcIso8601(f.start_utc);
  } catch (const Error& e) {
    throw Error(spec.origin, std::string("star_field.start_utc: ") + e.what());
  }
  o.axis_azimuth_deg = f.axis_azimuth_deg;
  o.axis_altitude_deg = f.axis_altitude_deg;
  o.roll_deg = f.roll_deg;
  o.duty_cycle = f.exposure == "duty_cycle";
  o.schedule.leading_dashes = f.leading_dashes;
  o.schedule.break_s = f.break_s;
  o.single_exposure_s = f.exposure_s;
  std::string why;
  if (!o.Check(&why)) throw Error(spec.origin, "star_field: " + why);
  return o;
}

template <typename Saturated>
void AddStarField(const SimulationSpec& spec, const CameraDefinition& camera, const GeometryChain& chain,
                  const Saturated& saturated, SimulatedPlate* plate) {
  const SpecStarField& f = spec.star_field;
  const StarFieldOptions options = StarFieldOptionsOf(spec);
  const PlateLens lens(camera);
  const std::string catalog = f.catalog.empty() ? calib::DefaultStarCatalogPath() : f.catalog;
  const std::vector<calib::CatalogStar> stars =
      LoadFieldStars(options, catalog, f.magnitude_limit, lens, camera.format_width_mm, camera.format_height_mm);
  const StarFieldResult field = ComputeStarImages(options, stars, lens, camera.format_width_mm, camera.format_height_mm);

  const SpecStars& look = spec.stars;
  const double sigma_um = look.fwhm_um / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  for (const StarImage& image : field.images) {
    // The rendered segment runs from the open to the close image, centred on
    // their midpoint; the truth is the image at mid-exposure (docs/simulator.md).
    const PlatePoint centre{0.5 * (image.open_mm.x_mm + image.close_mm.x_mm),
                            0.5 * (image.open_mm.y_mm + image.close_mm.y_mm)};
    SceneMark mark;
    mark.id = image.id;
    mark.kind = image.kind == StarImageKind::kTrailDot    ? MarkKind::kTrailDot
                : image.kind == StarImageKind::kTrailDash ? MarkKind::kTrailDash
                                                          : MarkKind::kStar;
    mark.shape = MarkShapeKind::kSegment;
    SetLocalMap(chain, centre, &mark);
    mark.psf_fwhm_um = look.fwhm_um;
    const double u_um = 1e3 * (image.close_mm.x_mm - image.open_mm.x_mm);
    const double v_um = 1e3 * (image.close_mm.y_mm - image.open_mm.y_mm);
    mark.segment_u_um = u_um;
    mark.segment_v_um = v_um;
    // Flux grows with the exposure: a point image of the reference magnitude
    // exposed reference_exposure_s peaks at reference_peak_dn.
    const double duration_s = image.close_s - image.open_s;
    const double exposure = f.exposure == "single" && duration_s == 0.0 ? 1.0 : duration_s / f.reference_exposure_s;
    const double point_peak_dn =
        look.reference_peak_dn * std::pow(10.0, -0.4 * (image.v_mag - look.reference_magnitude)) * exposure;
    const double area_px2 = 2 * std::numbers::pi * sigma_um * sigma_um *
                            std::abs(mark.px_from_um[0] * mark.px_from_um[3] - mark.px_from_um[1] * mark.px_from_um[2]);
    mark.amplitude_dn = (look.dark ? -1.0 : 1.0) * point_peak_dn * area_px2;
    // Peak of the swept Gaussian (at its centre): point peak x sqrt(2 pi) s / L x erf(L / (2 sqrt 2 s)).
    const double length_um = std::hypot(u_um, v_um);
    const double sweep = length_um > 1e-9 ? std::sqrt(2 * std::numbers::pi) * sigma_um / length_um *
                                                std::erf(length_um / (2 * std::sqrt(2.0) * sigma_um))
                                          : 1.0;
    const double peak_dn = point_peak_dn * sweep;
    plate->scene.marks.push_back(std::move(mark));

    const PointKind kind = image.kind == StarImageKind::kTrailDot    ? PointKind::kTrailDot
                           : image.kind == StarImageKind::kTrailDash ? PointKind::kTrailDash
                                                                     : PointKind::kStar;
    MeasuredPoint t = TruthPoint(image.id, kind, image.mid_mm, chain.PixelFromPlate(image.mid_mm));
    t.star_id = image.star_id;
    if (image.trail > 0) {
      t.trail = "T" + std::to_string(image.trail);
      t.dot = image.index;
    }
    t.mid_time_utc = image.mid_time_utc;
    if (saturated(look.dark ? -peak_dn : peak_dn)) t.flags.push_back("saturated");
    char magnitude[32];
    std::snprintf(magnitude, sizeof magnitude, "mag=%.3f", image.v_mag);
    t.flags.push_back(magnitude);
    plate->truth.push_back(std::move(t));
    plate->truth_mark.push_back(static_cast<int>(plate->scene.marks.size()) - 1);
  }

  nlohmann::ordered_json j;
  j["site"] = {{"latitude_deg", f.latitude_deg}, {"longitude_deg", f.longitude_deg}, {"height_m", f.height_m}};
  j["start_utc"] = calib::FormatUtcIso8601(options.start_utc, 3);
  j["duration_s"] = PlateDuration_s(options);
  j["atmosphere"] = {{"refraction", options.place.refraction},
                     {"pressure_hpa", options.place.pressure_hpa},
                     {"temperature_degC", options.place.temperature_degC},
                     {"relative_humidity", options.place.relative_humidity},
                     {"wavelength_um", options.place.wavelength_um}};
  j["ut1_minus_utc_s"] = options.place.ut1_minus_utc_s;
  j["axis"] = {{"azimuth_deg", options.axis_azimuth_deg}, {"altitude_deg", options.axis_altitude_deg},
               {"roll_deg", options.roll_deg}};
  const Eigen::Matrix3d m = CameraFromEnu(options.axis_azimuth_deg, options.axis_altitude_deg, options.roll_deg);
  j["camera_from_enu"] = {{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}};
  j["lens"] = {{"model", DistortionModelName(lens.model().model())},
               {"principal_distance_mm", lens.principal_distance_mm()},
               {"printed_left_handed", lens.printed_left_handed()}};
  j["exposure"] = f.exposure;
  if (options.duty_cycle) j["leading_dashes"] = f.leading_dashes, j["break_s"] = f.break_s;
  j["catalog"] = catalog;
  j["magnitude_limit"] = f.magnitude_limit;
  j["catalog_stars"] = stars.size();
  j["images"] = field.images.size();
  j["skipped_below_horizon"] = field.skipped_below_horizon;
  j["skipped_outside_format"] = field.skipped_outside;
  j["max_segment_centre_offset_um"] = field.max_arc_offset_um;
  plate->star_field_json = j.dump();
}

}  // namespace

SimulatedPlate BuildSimulatedPlate(const SimulationSpec& spec, const DefinitionRegistry& registry,
                                   const SimulateOptions& options) {
  SimulatedPlate plate;
  Builder b{spec, plate};
  plate.name = spec.name;
  plate.spec_origin = spec.origin;
  plate.camera = spec.camera;
  plate.seed = options.seed.value_or(spec.seed);
  plate.full_size = options.full_size;

  // ---- definitions
  const CameraDefinition* camera = registry.FindCamera(spec.camera);
  if (!camera) {
    std::string known;
    for (const std::string& name : registry.CameraNames()) known += (known.empty() ? "" : ", ") + name;
    b.Fail("unknown camera '" + spec.camera + "' (known: " + known + ")");
  }
  const MasterGrid* grid = camera->grid.empty() ? nullptr : registry.FindGrid(camera->grid);
  const FiducialSet* fiducials = camera->fiducial_set.empty() ? nullptr : registry.FindFiducials(camera->fiducial_set);
  if (!camera->grid.empty() && !grid) b.Fail("camera '" + spec.camera + "' names an unknown grid '" + camera->grid + "'");
  if (!camera->fiducial_set.empty() && !fiducials) {
    b.Fail("camera '" + spec.camera + "' names an unknown fiducial set '" + camera->fiducial_set + "'");
  }

  // ---- pixel size
  if (options.full_size) {
    if (!spec.output.full_size_pixel_size_um) b.Fail("output: --full-size needs full_size_pixel_size_um in the spec");
    plate.pixel_size_um = *spec.output.full_size_pixel_size_um;
  } else {
    plate.pixel_size_um = spec.output.pixel_size_um;
  }
  const double pixel_um = plate.pixel_size_um;

  // ---- geometry chain
  GeometryChain& chain = plate.chain;
  std::optional<double> calibration = spec.thermal.calibration_temperature_degC;
  if (!calibration) calibration = camera->calibration_temperature_degC;
  if (!calibration && grid) calibration = grid->calibration_temperature_degC;
  if (spec.thermal.temperature_degC && !calibration) {
    b.Fail("thermal: camera '" + spec.camera +
           "' has no calibration temperature; give thermal.calibration_temperature_degC");
  }
  chain.thermal.calibration_temperature_degC = calibration.value_or(20.0);
  chain.thermal.temperature_degC = spec.thermal.temperature_degC.value_or(chain.thermal.calibration_temperature_degC);
  chain.thermal.expansion_per_degC = spec.thermal.expansion_per_degC.value_or(camera->glass_expansion_per_degC);

  chain.emulsion.depth_um = spec.emulsion.depth_um;
  chain.emulsion.refractive_index = spec.emulsion.refractive_index;
  double c_mm = camera->nominal_principal_distance_mm;
  if (camera->lens && camera->lens->principal_distance_mm > 0) {
    c_mm = camera->lens->principal_distance_mm;
    // In the plate frame (PlateLens flips seed 001's left-handed values).
    const PlatePoint pp = PlateLens(*camera).PrincipalPoint();
    chain.emulsion.principal_point_mm = {pp.x_mm, pp.y_mm};
  }
  if (spec.emulsion.principal_distance_mm) c_mm = *spec.emulsion.principal_distance_mm;
  if (!(c_mm > 1.0)) b.Fail("emulsion: camera '" + spec.camera + "' has no principal distance; give emulsion.principal_distance_mm");
  chain.emulsion.principal_distance_mm = c_mm;

  chain.film = spec.film;
  if (!spec.film_normalization_given) {
    chain.film.normalization_mm = std::max(camera->format_width_mm, camera->format_height_mm) / 2.0;
    if (!(chain.film.normalization_mm > 0)) chain.film.normalization_mm = 50.0;
  }

  chain.scanner.pixel_size_um = pixel_um;
  chain.scanner.pixel_aspect = spec.scanner.pixel_aspect;
  chain.scanner.rotation_deg = spec.scanner.rotation_deg;
  chain.scanner.non_orthogonality_arcsec = spec.scanner.non_orthogonality_arcsec;
  chain.scanner.orientation_deg = spec.scanner.orientation_deg;
  chain.scanner.mirrored = spec.scanner.mirrored;

  // ---- image size: the format, grid and fiducials plus the margin, through the scanner
  const double half_w = camera->format_width_mm / 2, half_h = camera->format_height_mm / 2;
  double min_x = -half_w, max_x = half_w, min_y = -half_h, max_y = half_h;
  auto extend = [&](double x, double y, double reach_mm) {
    min_x = std::min(min_x, x - reach_mm);
    max_x = std::max(max_x, x + reach_mm);
    min_y = std::min(min_y, y - reach_mm);
    max_y = std::max(max_y, y + reach_mm);
  };
  if (grid) {
    for (const GridPoint& p : grid->points) extend(p.x_mm, p.y_mm, grid->mark.arm_length_um * 1e-3 / 2);
  }
  if (fiducials) {
    for (const FiducialMark& m : fiducials->marks) extend(m.x_mm, m.y_mm, m.mark.arm_length_um * 1e-3 / 2);
  }
  min_x -= spec.output.margin_mm;
  max_x += spec.output.margin_mm;
  min_y -= spec.output.margin_mm;
  max_y += spec.output.margin_mm;
  const Matrix2 m = chain.scanner.PixelPerMm();
  double px_min_x = 1e300, px_max_x = -1e300, px_min_y = 1e300, px_max_y = -1e300;
  for (double x : {min_x, max_x}) {
    for (double y : {min_y, max_y}) {
      const double col = m.a[0] * x + m.a[1] * y, row = m.a[2] * x + m.a[3] * y;
      px_min_x = std::min(px_min_x, col);
      px_max_x = std::max(px_max_x, col);
      px_min_y = std::min(px_min_y, row);
      px_max_y = std::max(px_max_y, row);
    }
  }
  Scene& scene = plate.scene;
  scene.width_px = spec.output.width_px.value_or(static_cast<long>(std::ceil(px_max_x - px_min_x)) + 1);
  scene.height_px = spec.output.height_px.value_or(static_cast<long>(std::ceil(px_max_y - px_min_y)) + 1);
  if (scene.width_px > 1000000 || scene.height_px > 1000000) b.Fail("output: the image would be larger than 1e6 px a side");
  // The plate box's centre at the image centre, then the spec's offset.
  const double box_col = (px_min_x + px_max_x) / 2, box_row = (px_min_y + px_max_y) / 2;
  chain.scanner.origin_px = {(scene.width_px - 1) / 2.0 - box_col + spec.scanner.offset_px[0],
                             (scene.height_px - 1) / 2.0 - box_row + spec.scanner.offset_px[1]};
  std::string why;
  if (!chain.Check(&why)) b.Fail(why);

  // ---- output image
  const double full_scale = spec.output.bits == 8 ? 255.0 : 65535.0;
  plate.image.width_px = scene.width_px;
  plate.image.height_px = scene.height_px;
  plate.image.sample_type = spec.output.bits == 8 ? SampleType::kUint8 : SampleType::kUint16;
  plate.image.tile_size_px = spec.output.tile_size_px;
  plate.image.compression = spec.output.compression;
  plate.image.pixel_size_um = pixel_um;
  if (!plate.image.Check(&why)) b.Fail("output: " + why);

  auto check_dn = [&](double value, const std::string& key) {
    if (value > full_scale) {
      std::ostringstream s;
      s << key << " = " << value << " DN exceeds the " << spec.output.bits << "-bit full scale " << full_scale;
      b.Fail(s.str());
    }
  };
  check_dn(spec.background.level_dn, "background.level_dn");
  // Contrasts only of marks this plate has (a camera without a reseau ignores marks.reseau).
  if (grid) check_dn(spec.reseau.contrast_dn, "marks.reseau.contrast_dn");
  if (fiducials || camera->format_corners_as_fiducials) check_dn(spec.fiducials.contrast_dn, "marks.fiducials.contrast_dn");
  if (spec.passpoints.count > 0 || !spec.passpoints.points.empty()) {
    check_dn(spec.passpoints.contrast_dn, "passpoints.contrast_dn");
  }
  if (spec.stars.count > 0 || !spec.stars.points.empty() || spec.star_field.enabled) check_dn(spec.stars.reference_peak_dn, "stars.reference_peak_dn");
  if (spec.defects.saturation_dn) check_dn(*spec.defects.saturation_dn, "defects.saturation_dn");

  // ---- background and noise
  scene.background.level_dn = spec.background.level_dn;
  scene.background.terrain_amplitude_dn = spec.background.terrain_amplitude_dn;
  scene.background.terrain_scale_px = spec.background.terrain_scale_mm * 1e3 / pixel_um;
  scene.background.vignetting_fraction = spec.background.vignetting_fraction;
  scene.background.optical_centre_px = chain.PixelFromPlate(chain.thermal.Inverse(chain.emulsion.principal_point_mm));
  scene.background.vignetting_radius_px = spec.background.vignetting_radius_mm * 1e3 / pixel_um;
  scene.noise.scanner_blur_sigma_px = spec.noise.blur_sigma_um / pixel_um;
  scene.noise.sensor_sigma_dn = spec.noise.sensor_sigma_dn;
  scene.noise.grain_sigma_dn = spec.noise.grain_sigma_dn;
  scene.noise.quantize = spec.noise.quantize;
  scene.noise.saturation_dn = spec.defects.saturation_dn.value_or(full_scale);
  scene.noise.seed = DeriveSeed(plate.seed, kNoise);

  auto amplitude = [](const SpecMarkLook& look) { return look.dark ? -look.contrast_dn : look.contrast_dn; };
  auto saturated = [&](double amplitude_dn) {
    const double peak = spec.background.level_dn + amplitude_dn;
    return peak <= 0.0 || peak >= scene.noise.saturation_dn;
  };

  // ---- reseau crosses
  std::set<std::string> missing(spec.defects.missing_crosses.begin(), spec.defects.missing_crosses.end());
  std::set<std::string> damaged(spec.defects.damaged_crosses.begin(), spec.defects.damaged_crosses.end());
  auto require_cross = [&](const std::string& id, const std::string& key) {
    if (!grid) b.Fail("defects." + key + ": camera '" + spec.camera + "' has no reseau");
    if (!grid->Find(id)) b.Fail("defects." + key + ": grid '" + grid->name + "' has no cross '" + id + "'");
  };
  for (const std::string& id : missing) require_cross(id, "missing_crosses");
  for (const std::string& id : damaged) require_cross(id, "damaged_crosses");
  for (const SpecFalseMark& f : spec.defects.false_marks) require_cross(f.near, "false_mark.near");

  std::vector<PlatePoint> crosses;
  if (grid) {
    const double line_um = spec.reseau.line_width_um.value_or(grid->mark.line_width_um);
    const double size_um = spec.reseau.size_um.value_or(grid->mark.arm_length_um);
    uint64_t index = 0;
    for (const GridPoint& g : grid->points) {
      const PlatePoint p{g.x_mm, g.y_mm};
      crosses.push_back(p);
      ++index;
      if (missing.count(g.id)) {
        plate.truth.push_back(TruthPoint(g.id, PointKind::kReseau, p, chain.PixelFromPlate(p)));
        plate.truth.back().flags = {"absent"};
        plate.truth_mark.push_back(-1);
        continue;
      }
      SceneMark mark;
      mark.id = g.id;
      mark.kind = MarkKind::kReseauCross;
      mark.shape = ShapeOf(grid->mark.type);
      SetLocalMap(chain, p, &mark);
      mark.line_width_um = line_um;
      mark.size_um = size_um;
      mark.amplitude_dn = amplitude(spec.reseau);
      std::vector<std::string> flags;
      if (damaged.count(g.id)) {
        mark.damage_fraction = spec.defects.damage_fraction;
        mark.seed = DeriveSeed(plate.seed, kDamage * 1000003 + index);
        flags.push_back("damaged");
      }
      if (saturated(mark.amplitude_dn)) flags.push_back("saturated");
      b.AddMark(std::move(mark), g.id, PointKind::kReseau, p, std::move(flags));
    }
  }

  // ---- fiducials: the camera's set, or the format corners (seed 000)
  if (fiducials) {
    for (const FiducialMark& f : fiducials->marks) {
      const PlatePoint p{f.x_mm, f.y_mm};
      SceneMark mark;
      mark.id = f.id;
      mark.kind = MarkKind::kFiducial;
      mark.shape = ShapeOf(f.mark.type);
      SetLocalMap(chain, p, &mark);
      mark.line_width_um = spec.fiducials.line_width_um.value_or(f.mark.line_width_um);
      mark.size_um = spec.fiducials.size_um.value_or(f.mark.arm_length_um);
      mark.amplitude_dn = amplitude(spec.fiducials);
      std::vector<std::string> flags;
      if (saturated(mark.amplitude_dn)) flags.push_back("saturated");
      b.AddMark(std::move(mark), f.id, PointKind::kFiducial, p, std::move(flags));
    }
  }
  if (camera->format_corners_as_fiducials) {
    struct Corner {
      const char* id;
      double sx, sy;
    };
    for (const Corner& c : {Corner{"UL", -1, 1}, Corner{"UR", 1, 1}, Corner{"LL", -1, -1}, Corner{"LR", 1, -1}}) {
      const PlatePoint p{c.sx * half_w, c.sy * half_h};
      SceneMark mark;
      mark.id = c.id;
      mark.kind = MarkKind::kFiducial;
      mark.shape = MarkShapeKind::kCorner;
      SetLocalMap(chain, p, &mark);
      mark.line_width_um = spec.fiducials.line_width_um.value_or(100.0);
      mark.size_um = spec.fiducials.size_um.value_or(3000.0);
      mark.corner_angle_rad = std::atan2(-c.sy, -c.sx);  // the arms run inward along the format edges
      mark.amplitude_dn = amplitude(spec.fiducials);
      b.AddMark(std::move(mark), c.id, PointKind::kFiducial, p);
    }
  }

  // ---- passpoints: explicit, then random inside the format away from crosses and each other
  std::vector<PlatePoint> taken = crosses;
  auto add_passpoint = [&](const std::string& id, PlatePoint p) {
    SceneMark mark;
    mark.id = id;
    mark.kind = MarkKind::kPasspoint;
    mark.shape = spec.passpoints.shape == "ring" ? MarkShapeKind::kRing : MarkShapeKind::kDot;
    SetLocalMap(chain, p, &mark);
    mark.size_um = spec.passpoints.diameter_um;
    mark.line_width_um = spec.passpoints.line_width_um;
    mark.amplitude_dn = spec.passpoints.dark ? -spec.passpoints.contrast_dn : spec.passpoints.contrast_dn;
    b.AddMark(std::move(mark), id, PointKind::kPasspoint, p);
    taken.push_back(p);
  };
  std::set<std::string> passpoint_ids;
  for (const SpecPoint& p : spec.passpoints.points) {
    if (!passpoint_ids.insert(p.id).second) b.Fail("passpoints: duplicate id '" + p.id + "'");
    add_passpoint(p.id, {p.x_mm, p.y_mm});
  }
  {
    std::mt19937_64 random(DeriveSeed(plate.seed, kPasspoints));
    std::uniform_real_distribution<double> ux(-half_w + 1.0, half_w - 1.0), uy(-half_h + 1.0, half_h - 1.0);
    const double clearance = spec.passpoints.clearance_mm;
    for (int n = 1; n <= spec.passpoints.count; ++n) {
      PlatePoint p;
      int attempts = 0;
      while (true) {
        p = {ux(random), uy(random)};
        bool clear = true;
        for (const PlatePoint& q : taken) {
          if (std::hypot(p.x_mm - q.x_mm, p.y_mm - q.y_mm) < clearance) {
            clear = false;
            break;
          }
        }
        if (clear) break;
        if (++attempts > 10000) b.Fail("passpoints: no room for " + std::to_string(spec.passpoints.count) +
                                       " random passpoints at clearance_mm " + std::to_string(clearance));
      }
      char id[16];
      std::snprintf(id, sizeof id, "P%03d", n);
      if (passpoint_ids.count(id)) b.Fail(std::string("passpoints: explicit id '") + id + "' clashes with the random ones");
      add_passpoint(id, p);
    }
  }

  // ---- stars (the sky-marks hook: plate positions and magnitudes)
  {
    std::vector<SpecPoint> stars = spec.stars.points;
    std::set<std::string> ids;
    for (const SpecPoint& s : stars) {
      if (!ids.insert(s.id).second) b.Fail("stars: duplicate id '" + s.id + "'");
    }
    std::mt19937_64 random(DeriveSeed(plate.seed, kStars));
    std::uniform_real_distribution<double> ux(-half_w + 0.5, half_w - 0.5), uy(-half_h + 0.5, half_h - 0.5);
    std::uniform_real_distribution<double> um(spec.stars.magnitude_min, spec.stars.magnitude_max);
    for (int n = 1; n <= spec.stars.count; ++n) {
      char id[16];
      std::snprintf(id, sizeof id, "S%04d", n);
      if (ids.count(id)) b.Fail(std::string("stars: explicit id '") + id + "' clashes with the random ones");
      SpecPoint s;
      s.id = id;
      s.x_mm = ux(random);
      s.y_mm = uy(random);
      s.magnitude = um(random);
      stars.push_back(s);
    }
    const double sigma_um = spec.stars.fwhm_um / (2.0 * std::sqrt(2.0 * std::log(2.0)));
    for (const SpecPoint& s : stars) {
      const PlatePoint p{s.x_mm, s.y_mm};
      SceneMark mark;
      mark.id = s.id;
      mark.kind = MarkKind::kStar;
      mark.shape = MarkShapeKind::kPsf;
      SetLocalMap(chain, p, &mark);
      mark.psf_fwhm_um = spec.stars.fwhm_um;
      // Flux (DN px^2) of a Gaussian whose peak is reference_peak_dn at the reference magnitude.
      const double peak_dn = spec.stars.reference_peak_dn * std::pow(10.0, -0.4 * (s.magnitude - spec.stars.reference_magnitude));
      const double area_px2 = 2 * std::numbers::pi * sigma_um * sigma_um *
                              std::abs(mark.px_from_um[0] * mark.px_from_um[3] - mark.px_from_um[1] * mark.px_from_um[2]);
      mark.amplitude_dn = (spec.stars.dark ? -1.0 : 1.0) * peak_dn * area_px2;
      std::vector<std::string> flags;
      if (saturated(spec.stars.dark ? -peak_dn : peak_dn)) flags.push_back("saturated");
      b.AddMark(std::move(mark), s.id, PointKind::kStar, p, std::move(flags));
      char magnitude[32];
      std::snprintf(magnitude, sizeof magnitude, "mag=%.3f", s.magnitude);
      plate.truth.back().flags.push_back(magnitude);
    }
  }

  // ---- catalog stars: one image per star and exposure (star_field.h)
  if (spec.star_field.enabled) AddStarField(spec, *camera, chain, saturated, &plate);

  // ---- defects that are not in the truth list
  for (size_t i = 0; i < spec.defects.false_marks.size(); ++i) {
    const SpecFalseMark& f = spec.defects.false_marks[i];
    const GridPoint* g = grid->Find(f.near);
    const PlatePoint p{g->x_mm + f.offset_um[0] * 1e-3, g->y_mm + f.offset_um[1] * 1e-3};
    SceneMark mark;
    mark.id = "false-" + std::to_string(i + 1) + "-near-" + f.near;
    mark.kind = MarkKind::kFalseMark;
    mark.shape = MarkShapeKind::kCross;
    SetLocalMap(chain, p, &mark);
    mark.line_width_um = spec.reseau.line_width_um.value_or(grid->mark.line_width_um);
    mark.size_um = spec.reseau.size_um.value_or(grid->mark.arm_length_um);
    mark.amplitude_dn = amplitude(spec.reseau);
    scene.marks.push_back(std::move(mark));
    plate.false_marks.push_back(static_cast<int>(scene.marks.size()) - 1);
  }
  {
    std::mt19937_64 random(DeriveSeed(plate.seed, kDust));
    std::uniform_real_distribution<double> ux(min_x, max_x), uy(min_y, max_y);
    std::uniform_real_distribution<double> ud(spec.defects.dust_diameter_min_um, spec.defects.dust_diameter_max_um);
    for (int n = 1; n <= spec.defects.dust_count; ++n) {
      SceneMark mark;
      mark.id = "dust-" + std::to_string(n);
      mark.kind = MarkKind::kDust;
      mark.shape = MarkShapeKind::kDot;
      SetLocalMap(chain, {ux(random), uy(random)}, &mark);
      mark.size_um = ud(random);
      mark.amplitude_dn = spec.defects.dust_dark ? -spec.defects.dust_contrast_dn : spec.defects.dust_contrast_dn;
      scene.marks.push_back(std::move(mark));
      plate.dust.push_back(static_cast<int>(scene.marks.size()) - 1);
    }
  }
  {
    std::mt19937_64 random(DeriveSeed(plate.seed, kScratches));
    std::uniform_real_distribution<double> ux(min_x, max_x), uy(min_y, max_y), ua(0.0, std::numbers::pi);
    for (int n = 1; n <= spec.defects.scratch_count; ++n) {
      SceneMark mark;
      mark.id = "scratch-" + std::to_string(n);
      mark.kind = MarkKind::kScratch;
      mark.shape = MarkShapeKind::kSegment;
      SetLocalMap(chain, {ux(random), uy(random)}, &mark);
      mark.size_um = spec.defects.scratch_length_mm * 1e3;
      mark.line_width_um = spec.defects.scratch_width_um;
      mark.corner_angle_rad = ua(random);
      mark.amplitude_dn = spec.defects.scratch_dark ? -spec.defects.scratch_contrast_dn : spec.defects.scratch_contrast_dn;
      scene.marks.push_back(std::move(mark));
      plate.scratches.push_back(static_cast<int>(scene.marks.size()) - 1);
    }
  }

  // Points that fall outside the image are still listed, flagged.
  for (MeasuredPoint& t : plate.truth) {
    if (*t.x_px < -0.5 || *t.y_px < -0.5 || *t.x_px > scene.width_px - 0.5 || *t.y_px > scene.height_px - 0.5) {
      t.flags.push_back("outside_image");
    }
  }
  return plate;
}

}  // namespace platemeter::sim
