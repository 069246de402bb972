// ReadStellarJob (stellar_job.h): the stellar job file, TOML
// (docs/stellar-job.md), and the plates' measurement files.
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "platemeter/calib/stellar_job.h"
#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "platemeter/measure/measurement_file.h"
#include "toml_job_reader.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {

using job_toml::JobReader;
using job_toml::Join;
using job_toml::LineOf;

constexpr double kRobustScaleSigma = 3.0;  // Cauchy scale of the first pass

// The site and atmosphere of [site], overridden per plate by the same keys.
void ReadPlace(const JobReader& r, const toml::table& t, const std::string& prefix, calib::ApparentPlaceOptions* place,
               bool site_keys) {
  if (site_keys) {
    if (const toml::node* n = t.get("latitude_deg")) place->site.latitude_rad = r.Number(*n, prefix + "latitude_deg", -90, 90) * kRadPerDeg;
    if (const toml::node* n = t.get("longitude_deg")) place->site.longitude_rad = r.Number(*n, prefix + "longitude_deg", -180, 360) * kRadPerDeg;
    if (const toml::node* n = t.get("height_m")) place->site.height_m = r.Number(*n, prefix + "height_m", -500, 9000);
  }
  if (const toml::node* n = t.get("pressure_hpa")) place->pressure_hpa = r.Number(*n, prefix + "pressure_hpa", 0, 1500);
  if (const toml::node* n = t.get("temperature_degC")) place->temperature_degC = r.Number(*n, prefix + "temperature_degC", -150, 200);
  if (const toml::node* n = t.get("relative_humidity")) place->relative_humidity = r.Number(*n, prefix + "relative_humidity", 0, 1);
  if (const toml::node* n = t.get("wavelength_um")) place->wavelength_um = r.Number(*n, prefix + "wavelength_um", 0.1, 1e6);
  if (const toml::node* n = t.get("ut1_minus_utc_s")) place->ut1_minus_utc_s = r.Number(*n, prefix + "ut1_minus_utc_s", -1, 1);
  if (const toml::node* n = t.get("refraction")) place->refraction = r.Bool(*n, prefix + "refraction");
}

// Star images and trail dots of a measurement file (status measured), with their times and sigmas.
std::vector<StarImageObservation> ReadPlateImages(const std::string& path, const std::vector<PointKind>& kinds) {
  const MeasurementFile file = ReadMeasurementFile(path);
  std::vector<StarImageObservation> out;
  long untagged = 0;
  for (const MeasuredPoint& p : file.points) {
    if (p.status != PointStatus::kMeasured) continue;
    if (std::find(kinds.begin(), kinds.end(), p.kind) == kinds.end()) continue;
    const std::string where = path + ": point " + p.id;
    if (!p.x_mm || !p.y_mm || !p.sigma_x_mm || !p.sigma_y_mm)
      throw Error(where, "needs x_mm, y_mm, sigma_x_mm and sigma_y_mm (run measure on the scan first)");
    if (p.mid_time_utc.empty() || p.star_id.empty()) {  // a dot the trail decoder could not tag
      ++untagged;
      continue;
    }
    StarImageObservation o;
    o.image_id = p.id;
    o.star_id = p.star_id;
    if (p.mid_time_utc.size() > 64) throw Error(where, "mid_time_utc is longer than 64 characters (not an ISO 8601 time)");
    try {
      o.mid_time = calib::ParseUtcIso8601(p.mid_time_utc);
    } catch (const Error& e) {
      throw Error(where, std::string("mid_time_utc: ") + e.what());
    }
    o.x_mm = *p.x_mm;
    o.y_mm = *p.y_mm;
    o.sigma_x_mm = *p.sigma_x_mm;
    o.sigma_y_mm = *p.sigma_y_mm;
    o.origin = path + ": point " + p.id;
    o.trail = p.trail;
    o.dot = p.dot.value_or(-1);
    out.push_back(std::move(o));
  }
  if (untagged > 0)
    Warn(path + ": " + std::to_string(untagged) + " images without a star_id or mid_time_utc (not decoded) left out");
  if (out.empty())
    throw Error(path, "no measured star images or trail dots of the selected kinds with a star_id and mid_time_utc");
  return out;
}

// A camera definition by name: its index in job->cameras (added when new).
int CameraIndex(const JobReader& r, const toml::node& node, const std::string& key, const DefinitionRegistry& registry,
                StellarJob* job) {
  const std::string name = r.String(node, key);
  for (size_t k = 0; k < job->cameras.size(); ++k) {
    if (job->cameras[k].name == name) return static_cast<int>(k);
  }
  const CameraDefinition* definition = registry.FindCamera(name);
  if (!definition) r.Fail(&node, "unknown camera '" + name + "' (known: " + Join(registry.CameraNames()) + ")");
  job->cameras.push_back(*definition);
  return static_cast<int>(job->cameras.size()) - 1;
}

StellarJobPlate ReadPlate(const JobReader& r, const toml::table& t, const calib::ApparentPlaceOptions& site,
                          const std::vector<PointKind>& kinds, const DefinitionRegistry& registry, StellarJob* job) {
  r.CheckKeys(t, "plate.", {"id", "group", "measurements", "camera", "exposure", "axis_azimuth_deg", "axis_altitude_deg", "ra_deg", "dec_deg",
                            "pressure_hpa", "temperature_degC", "relative_humidity", "wavelength_um",
                            "ut1_minus_utc_s", "refraction"});
  StellarJobPlate p;
  const toml::node* id = t.get("id");
  const toml::node* measurements = t.get("measurements");
  if (!id || !measurements) r.Fail(&t, "a [[plate]] needs 'id' and 'measurements'");
  p.plate.id = r.String(*id, "plate.id");
  if (const toml::node* n = t.get("group")) p.plate.group = r.String(*n, "plate.group");
  if (const toml::node* n = t.get("camera")) p.camera = CameraIndex(r, *n, "plate.camera", registry, job);
  if (const toml::node* n = t.get("exposure")) p.exposure = r.String(*n, "plate.exposure");
  p.plate.place = site;
  ReadPlace(r, t, "plate.", &p.plate.place, false);
  if (const toml::node* n = t.get("axis_azimuth_deg")) p.axis_azimuth_deg = r.Number(*n, "plate.axis_azimuth_deg", -360, 360);
  if (const toml::node* n = t.get("axis_altitude_deg")) p.axis_altitude_deg = r.Number(*n, "plate.axis_altitude_deg", 0, 90, false);
  const toml::node* ra = t.get("ra_deg");
  const toml::node* dec = t.get("dec_deg");
  if ((ra == nullptr) != (dec == nullptr)) r.Fail(&t, "give both 'ra_deg' and 'dec_deg', or neither");
  if (ra && (t.get("axis_azimuth_deg") || t.get("axis_altitude_deg")))
    r.Fail(ra, "give the pointing as azimuth/altitude or as ra/dec, not both");
  if (ra) p.axis_ra_dec_deg = {r.Number(*ra, "plate.ra_deg", 0, 360), r.Number(*dec, "plate.dec_deg", -90, 90)};
  p.source = r.Path(r.String(*measurements, "plate.measurements"));
  p.plate.images = ReadPlateImages(p.source, kinds);
  return p;
}

void ReadOptions(const JobReader& r, const toml::table& root, StellarJob* job) {
  if (const toml::node* n = root.get("orientation_sets")) job->options.orientation_sets = static_cast<int>(r.Integer(*n, "orientation_sets", 1, 3));
  if (const toml::node* n = root.get("deformation")) job->options.deformation = r.Bool(*n, "deformation");
  // Data snooping (a robust first pass, Bonferroni rejection) unless switched off.
  const bool robust = root.get("robust") ? r.Bool(*root.get("robust"), "robust") : true;
  job->options.adjustment.robust_loss_scale = robust ? kRobustScaleSigma : 0.0;
  if (const toml::node* n = root.get("lens_model")) {
    const std::string name = r.String(*n, "lens_model");
    if (!ParseStellarLensModel(name, &job->options.lens_model))
      r.Fail(n, "lens_model: '" + name + "' is not one of " + StellarLensModelNames());
  }
  // The names of the chosen model (read after lens_model).
  if (const toml::node* n = root.get("fixed")) {
    const std::vector<std::string> names = StellarCameraParamNames(job->options.lens_model);
    for (const auto& [name, node] : r.Strings(*n, "fixed")) {
      if (std::find(names.begin(), names.end(), name) == names.end())
        r.Fail(node, "unknown " + std::string(DistortionModelName(job->options.lens_model)) + " camera parameter '" +
                         name + "' (known: " + Join(names) + ")");
      job->options.camera_states[name] = ParameterState::Fixed();
    }
  }
  if (const toml::node* n = root.get("pointing_tolerance_deg"))
    job->identification.pointing_tolerance_deg = r.Number(*n, "pointing_tolerance_deg", 0, 30, false);
}

}  // namespace

StellarJob ReadStellarJob(const std::string& path, const DefinitionRegistry& registry) {
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw Error(path, "line " + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  const JobReader r(path, "docs/stellar-job.md");
  r.CheckKeys(root, "", {"title", "camera", "catalog", "magnitude_limit", "catalog_sigma_arcsec", "identify",
                         "orientation_sets", "deformation", "robust", "lens_model", "fixed", "kinds", "pointing_tolerance_deg",
                         "site", "plate"});
  StellarJob job;
  job.path = path;
  const toml::node* camera = root.get("camera");
  if (!camera) r.Fail(nullptr, "the job needs 'camera' (a camera definition, `platemeter cameras list`)");
  CameraIndex(r, *camera, "camera", registry, &job);
  const std::string camera_name = job.cameras[0].name;
  job.title = root.get("title") ? r.String(*root.get("title"), "title") : "Stellar calibration: " + camera_name;
  job.catalog_path = root.get("catalog") ? r.Path(r.String(*root.get("catalog"), "catalog"))
                                         : calib::DefaultStarCatalogPath();
  if (const toml::node* n = root.get("magnitude_limit")) job.magnitude_limit = r.Number(*n, "magnitude_limit", -2, 12);
  if (const toml::node* n = root.get("catalog_sigma_arcsec")) job.catalog_sigma_arcsec = r.Number(*n, "catalog_sigma_arcsec", 0, 60, false);
  if (const toml::node* n = root.get("identify")) job.identify = r.Bool(*n, "identify");
  ReadOptions(r, root, &job);
  std::vector<PointKind> kinds = {PointKind::kTrailDot, PointKind::kStar};
  if (const toml::node* n = root.get("kinds")) {
    kinds.clear();
    for (const auto& [name, node] : r.Strings(*n, "kinds")) {
      PointKind kind;
      if (!ParsePointKind(name, &kind) || (kind != PointKind::kTrailDot && kind != PointKind::kTrailDash && kind != PointKind::kStar))
        r.Fail(node, "kinds: '" + name + "' is not star, trail_dot or trail_dash");
      kinds.push_back(kind);
    }
  }
  calib::ApparentPlaceOptions site;
  const toml::table* site_table = r.Table(root, "site");
  if (!site_table) r.Fail(nullptr, "the job needs a [site] table (latitude_deg, longitude_deg, height_m)");
  r.CheckKeys(*site_table, "site.", {"latitude_deg", "longitude_deg", "height_m", "pressure_hpa", "temperature_degC",
                                     "relative_humidity", "wavelength_um", "ut1_minus_utc_s", "refraction"});
  if (!site_table->get("latitude_deg") || !site_table->get("longitude_deg"))
    r.Fail(site_table, "[site] needs latitude_deg and longitude_deg");
  ReadPlace(r, *site_table, "site.", &site, true);
  if (!site_table->get("pressure_hpa"))  // ERFA's standard atmosphere for the height (eraRefco notes)
    site.pressure_hpa = 1013.25 * std::exp(-site.site.height_m / (29.3 * (273.15 + site.temperature_degC)));
  const toml::array* plates = r.Tables(root, "plate");
  if (!plates || plates->empty()) r.Fail(nullptr, "the job needs at least one [[plate]]");
  for (const toml::node& node : *plates) {
    StellarJobPlate plate = ReadPlate(r, *node.as_table(), site, kinds, registry, &job);
    for (const StellarJobPlate& other : job.plates) {
      if (other.plate.id == plate.plate.id) r.Fail(&node, "plate id '" + plate.plate.id + "' is used twice");
      if (!plate.exposure.empty() && other.exposure == plate.exposure && other.camera == plate.camera)
        r.Fail(&node, "exposure '" + plate.exposure + "' has two plates of camera " + job.cameras[plate.camera].name);
    }
    job.plates.push_back(std::move(plate));
  }
  std::string why;
  if (!job.options.Check(&why)) r.Fail(nullptr, why);
  return job;
}

}  // namespace platemeter
