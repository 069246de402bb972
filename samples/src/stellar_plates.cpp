// Simulated stellar-calibration plates (stellar_plates.h).
#include "platemeter/samples/stellar_plates.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/core/angles.h"

namespace platemeter::sim {
namespace {

constexpr uint64_t kSelectionSeed = 20261126;  // the selection is part of the plate, not of the noise

}  // namespace

bool StellarPlateSimulation::Check(std::string* why) const {
  if (!(magnitude_limit > -2.0 && magnitude_limit < 12.0)) {
    *why = "magnitude_limit must be in (-2, 12)";
    return false;
  }
  if (!(cell_mm > 0.0) || images_per_cell_per_trail < 1 || !(format_margin_mm >= 0.0)) {
    *why = "cell_mm and images_per_cell_per_trail must be positive, format_margin_mm not negative";
    return false;
  }
  return field.Check(why);
}

StellarTruthPlate SimulateStellarTruth(const StellarPlateSimulation& options, const CameraDefinition& camera) {
  std::string why;
  if (!options.Check(&why)) throw Error("stellar simulation", why);
  const PlateLens lens(camera);
  const std::string path = options.catalog_path.empty() ? calib::DefaultStarCatalogPath() : options.catalog_path;
  const std::vector<calib::CatalogStar> stars = LoadFieldStars(
      options.field, path, options.magnitude_limit, lens, camera.format_width_mm, camera.format_height_mm);
  const StarFieldResult field =
      ComputeStarImages(options.field, stars, lens, camera.format_width_mm, camera.format_height_mm);

  StellarTruthPlate truth;
  truth.plate.id = options.plate_id;
  truth.plate.group = options.group;
  truth.plate.place = options.field.place;
  truth.camera = StellarCameraFromModel(lens.model(), lens.printed_left_handed());
  truth.camera_from_enu = CameraFromEnu(options.field.axis_azimuth_deg, options.field.axis_altitude_deg,
                                        options.field.roll_deg);
  truth.duration_s = PlateDuration_s(options.field);
  std::map<std::string, const calib::CatalogStar*> by_id;
  for (const calib::CatalogStar& star : stars) by_id[StarId(star)] = &star;

  // Seed 001's selection: per cell and trail at most N dots, chosen at random.
  std::map<std::tuple<int, int, int>, std::vector<const StarImage*>> cells;
  const double half_w = 0.5 * camera.format_width_mm - options.format_margin_mm;
  const double half_h = 0.5 * camera.format_height_mm - options.format_margin_mm;
  for (const StarImage& image : field.images) {
    if (image.kind != StarImageKind::kTrailDot) continue;
    if (std::abs(image.mid_mm.x_mm) > half_w || std::abs(image.mid_mm.y_mm) > half_h) continue;
    cells[{static_cast<int>(std::floor(image.mid_mm.x_mm / options.cell_mm)),
           static_cast<int>(std::floor(image.mid_mm.y_mm / options.cell_mm)), image.trail}]
        .push_back(&image);
  }
  std::mt19937_64 random(kSelectionSeed);
  for (auto& [cell, members] : cells) {
    std::shuffle(members.begin(), members.end(), random);
    members.resize(std::min<size_t>(members.size(), options.images_per_cell_per_trail));
    for (const StarImage* image : members) {
      StarImageObservation o;
      o.image_id = image->id;
      o.star_id = image->star_id;
      o.mid_time = calib::ParseUtcIso8601(image->mid_time_utc);
      o.x_mm = image->mid_mm.x_mm;
      o.y_mm = image->mid_mm.y_mm;
      truth.plate.images.push_back(std::move(o));
      truth.catalog[image->star_id] = CatalogEntry{*by_id.at(image->star_id), 0.0};
    }
  }
  std::sort(truth.plate.images.begin(), truth.plate.images.end(),
            [](const StarImageObservation& a, const StarImageObservation& b) { return a.image_id < b.image_id; });
  return truth;
}

NoisyStellarPlate Noisy(const StellarTruthPlate& truth, const StellarNoise& noise) {
  if (!(noise.image_sigma_um > 0.0) || !(noise.catalog_sigma_arcsec > 0.0))
    throw Error("stellar simulation", "the image and catalog sigmas must be positive");
  std::mt19937_64 random(noise.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  NoisyStellarPlate out;
  out.plate = truth.plate;
  const double sigma_mm = noise.image_sigma_um * 1e-3;
  for (StarImageObservation& image : out.plate.images) {
    image.x_mm += sigma_mm * normal(random);
    image.y_mm += sigma_mm * normal(random);
    image.sigma_x_mm = sigma_mm;
    image.sigma_y_mm = sigma_mm;
  }
  const double sigma_rad = noise.catalog_sigma_arcsec * kRadPerArcsec;
  for (const auto& [id, entry] : truth.catalog) {
    CatalogEntry e = entry;
    e.star.ra_rad += sigma_rad * normal(random) / std::cos(e.star.dec_rad);
    e.star.dec_rad += sigma_rad * normal(random);
    e.sigma_arcsec = noise.catalog_sigma_arcsec;
    out.catalog[id] = e;
  }
  return out;
}

std::map<std::string, std::string> WriteStellarMeasurementFile(const StellarPlate& plate, const std::string& path,
                                                               bool anonymous) {
  MeasurementFile file;
  file.header.plate_id = plate.id;
  file.header.camera = "orbigon";
  file.header.extra.push_back({"note", "simulated stellar plate (samples/stellar_plates.h): trail dots at mid-exposure"});
  std::map<std::string, std::string> key_of, catalog_of;
  for (const StarImageObservation& o : plate.images) {
    auto [it, added] = key_of.emplace(o.star_id, anonymous ? "S" + std::to_string(key_of.size() + 1) : o.star_id);
    catalog_of[it->second] = o.star_id;
    MeasuredPoint p;
    p.id = it->second + "-" + o.image_id.substr(o.image_id.find('-') + 1);  // "<key>-T2-D17"
    p.kind = PointKind::kTrailDot;
    p.x_mm = o.x_mm;
    p.y_mm = o.y_mm;
    p.sigma_x_mm = o.sigma_x_mm;
    p.sigma_y_mm = o.sigma_y_mm;
    p.star_id = it->second;
    const size_t t = o.image_id.find("-T");
    p.trail = t == std::string::npos ? "" : o.image_id.substr(t + 1, o.image_id.find('-', t + 1) - t - 1);
    p.mid_time_utc = calib::FormatUtcIso8601(o.mid_time, 3);
    file.points.push_back(std::move(p));
  }
  WriteMeasurementFile(path, file);
  return catalog_of;
}

}  // namespace platemeter::sim
