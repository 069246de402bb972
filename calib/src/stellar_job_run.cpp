// RunStellarJob (stellar_job.h): catalog, identification, one adjustment per
// plate, the weighted means.
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "platemeter/calib/stellar_job.h"
#include "platemeter/core/error.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {


StellarCatalog LoadCatalog(const StellarJob& job) {
  calib::StarQueryOptions query;
  query.faint_limit_mag = job.magnitude_limit;
  StellarCatalog catalog;
  for (const calib::CatalogStar& star : calib::LoadStarCatalog(job.catalog_path, query))
    catalog[calib::CatalogStarKey(star)] = {star, job.catalog_sigma_arcsec};
  return catalog;
}

// The approximate optical axis in the site's frame at the plate's first image.
Eigen::Vector3d AxisEnu(const StellarJobPlate& p) {
  if (p.axis_ra_dec_deg) {
    calib::CatalogStar pointing;
    pointing.ra_rad = p.axis_ra_dec_deg->first * kRadPerDeg;
    pointing.dec_rad = p.axis_ra_dec_deg->second * kRadPerDeg;
    return calib::ApparentPlaceCalculator(p.plate.place, p.plate.images.front().mid_time).Observe(pointing).enu;
  }
  const double a = p.axis_azimuth_deg * kRadPerDeg, h = p.axis_altitude_deg * kRadPerDeg;
  return Eigen::Vector3d(std::cos(h) * std::sin(a), std::cos(h) * std::cos(a), std::sin(h));
}

// Identifies the plate's stars whose ids are not catalog keys and renames
// them: catalog key, or "<plate>:<id>" for a star left unknown.
IdentificationResult IdentifyPlate(const StellarJob& job, const StellarJobPlate& p, const StellarCatalog& catalog,
                                   const StellarCamera& camera, StellarPlate* plate) {
  std::vector<DetectedStarImage> images;
  for (const StarImageObservation& o : p.plate.images) {
    if (!catalog.count(o.star_id)) images.push_back({o.star_id, o.mid_time, o.x_mm, o.y_mm});
  }
  IdentificationOptions options = job.identification;
  options.lens_model = job.options.lens_model;
  IdentificationResult r = IdentifyStars(images, catalog, p.plate.place, AxisEnu(p), camera, options);
  for (StarImageObservation& o : plate->images) {
    if (catalog.count(o.star_id)) continue;
    auto it = r.catalog_id.find(o.star_id);
    o.star_id = it != r.catalog_id.end() ? it->second : p.plate.id + ":" + o.star_id;
  }
  return r;
}

// The starting camera in the job's lens model: the definition's lens if it is
// of that model (orbigon-11: in seed 001's printed frame), else its nominal
// principal distance with no distortion.
StellarCamera InitialCamera(const CameraDefinition& camera, DistortionModelId lens, bool* printed_left_handed) {
  *printed_left_handed = false;
  if (camera.lens && camera.lens->model == DistortionModelName(lens)) {
    *printed_left_handed = lens == DistortionModelId::kSlama;  // seed 001's printed frame (docs/stellar.md)
    return StellarCameraFromModel(CameraModelFromLensCalibration(*camera.lens, "camera " + camera.name),
                                  *printed_left_handed);
  }
  if (camera.nominal_principal_distance_mm > 0.0)
    return NominalStellarCamera(camera.nominal_principal_distance_mm, lens);
  throw Error("camera " + camera.name, fmt::format("has neither an {} lens nor a nominal principal distance to start from",
                                                   DistortionModelName(lens)));
}

// The joint adjustment of the cameras over the exposures that show camera 0
// and at least one other camera; nullopt when there is none.
std::optional<StellarInterlockResult> RunInterlock(const StellarJob& job, const StellarJobResult& out,
                                                   const AdjustmentProgress& progress) {
  const size_t cameras = job.cameras.size();
  std::map<std::string, InterlockExposure> by_id;
  for (size_t i = 0; i < job.plates.size(); ++i) {
    if (job.plates[i].exposure.empty()) continue;
    InterlockExposure& e = by_id[job.plates[i].exposure];
    e.id = job.plates[i].exposure;
    e.plates.resize(cameras);
    e.plates[job.plates[i].camera] = out.plates[i];
  }
  std::vector<InterlockExposure> exposures;
  for (auto& [id, e] : by_id) {
    int others = 0;
    for (size_t k = 1; k < cameras; ++k) others += e.plates[k].images.empty() ? 0 : 1;
    if (!e.plates[0].images.empty() && others > 0) exposures.push_back(std::move(e));
  }
  if (exposures.empty()) return std::nullopt;
  if (progress) progress("interlock", 0.0);
  std::vector<std::string> names;
  for (const CameraDefinition& c : job.cameras) names.push_back(c.name);
  return RunStellarInterlock(names, out.initial, exposures, out.catalog, job.options, progress);
}

void CombinePlates(const StellarJob& job, const AdjustmentProgress& progress, StellarJobResult* out) {
  for (size_t camera = 0; camera < job.cameras.size(); ++camera) {
    const std::string suffix = job.cameras.size() > 1 ? " of " + job.cameras[camera].name : "";
    std::map<std::string, std::vector<int>> groups;
    std::vector<int> all;
    for (int i = 0; i < static_cast<int>(out->plates.size()); ++i) {
      if (job.plates[i].camera != static_cast<int>(camera)) continue;
      groups[out->plates[i].group].push_back(i);
      all.push_back(i);
    }
    auto combine = [&](const std::string& name, const std::vector<int>& members) {
      if (progress) progress("combination " + name, 0.0);
      std::vector<StellarPlate> plates;
      std::vector<StellarPlateResult> singles;
      for (int i : members) plates.push_back(out->plates[i]), singles.push_back(out->singles[i]);
      out->combinations.push_back(CombineStellarPlates(name, plates, singles, out->catalog, job.options));
      out->combination_camera.push_back(static_cast<int>(camera));
    };
    for (const auto& [group, members] : groups) {
      if (members.size() >= 2 && groups.size() > 1) combine((group.empty() ? "(no group)" : group) + suffix, members);
    }
    if (all.size() >= 2) combine("all plates" + suffix, all);
  }
}

}  // namespace

StellarJobResult RunStellarJob(const StellarJob& job, const AdjustmentProgress& progress) {
  StellarJobResult out;
  for (const CameraDefinition& camera : job.cameras) {
    bool printed = false;
    out.initial.push_back(InitialCamera(camera, job.options.lens_model, &printed));
    out.printed_left_handed.push_back(printed);
  }
  out.catalog = LoadCatalog(job);
  for (const StellarJobPlate& p : job.plates) {
    const StellarCamera& initial = out.initial[p.camera];
    StellarPlate plate = p.plate;
    std::optional<Eigen::Matrix3d> pointing;
    std::optional<IdentificationResult> identification;
    bool all_known = true;
    for (const StarImageObservation& o : plate.images) all_known = all_known && out.catalog.count(o.star_id);
    if (job.identify && !all_known) {
      if (progress) progress("identification " + plate.id, 0.0);
      identification = IdentifyPlate(job, p, out.catalog, initial, &plate);
      pointing = identification->camera_from_enu;
    }
    if (progress) progress("plate " + plate.id, 0.0);
    out.singles.push_back(RunStellarPlate(plate, out.catalog, initial, job.options, pointing, progress));
    out.plates.push_back(std::move(plate));
    out.identification.push_back(std::move(identification));
  }
  CombinePlates(job, progress, &out);
  out.interlock = RunInterlock(job, out, progress);
  return out;
}

}  // namespace platemeter
