// A plate made ready for the adjustment (stellar_internal.h): checks, each
// image's direction, orientation sets by time, and the starting orientation.
#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "stellar_internal.h"

namespace platemeter::stellar_internal {
namespace {

constexpr double kArcsecToRad = M_PI / (180.0 * 3600.0);
constexpr int kMinCatalogStars = 8;         // a rotation and 8 to 11 camera parameters need several stars
constexpr int kMinUnknownStarImages = 3;    // fewer add no redundancy to the camera

double SecondsBetween(const calib::UtcInstant& a, const calib::UtcInstant& b) {
  return ((b.jd1 - a.jd1) + (b.jd2 - a.jd2)) * 86400.0;
}

void CheckImage(const StellarPlate& plate, const StarImageObservation& image) {
  const std::string where = image.origin.empty() ? fmt::format("plate {} image {}", plate.id, image.image_id)
                                                 : image.origin;
  if (!std::isfinite(image.x_mm) || !std::isfinite(image.y_mm))
    throw Error(where, fmt::format("image {} has a non-finite position", image.image_id));
  if (!(image.sigma_x_mm > 0.0) || !(image.sigma_y_mm > 0.0) || !std::isfinite(image.sigma_x_mm) ||
      !std::isfinite(image.sigma_y_mm))
    throw Error(where, fmt::format("image {} needs positive finite sigmas", image.image_id));
  if (image.star_id.empty()) throw Error(where, fmt::format("image {} has no star id", image.image_id));
}

// The camera-frame ray (m, n, q) of a measured image, distortion ignored: a
// starting value only.
Eigen::Vector3d RayOf(const StarImageObservation& image, const StellarCamera& camera) {
  return Eigen::Vector3d((image.x_mm - camera[1]) / camera[0], (image.y_mm - camera[2]) / camera[0], 1.0).normalized();
}

// camera_from_enu by least squares over the catalog stars' images (Umeyama, no scale).
Eigen::Matrix3d RotationFromStars(const std::vector<Eigen::Vector3d>& enu, const std::vector<Eigen::Vector3d>& rays) {
  Eigen::Matrix3Xd from(3, enu.size()), to(3, rays.size());
  for (size_t i = 0; i < enu.size(); ++i) {
    from.col(i) = enu[i].normalized();
    to.col(i) = rays[i];
  }
  return Eigen::umeyama(from, to, false).topLeftCorner<3, 3>();
}

}  // namespace

PreparedPlate PreparePlate(const StellarPlate& plate, const StellarCatalog& catalog, const StellarCamera& initial,
                           const StellarOptions& options, const std::optional<Eigen::Matrix3d>& approx) {
  if (plate.images.empty()) throw Error(fmt::format("plate {}", plate.id), "has no star images");
  std::string why;
  if (!plate.place.Check(&why)) throw Error(fmt::format("plate {}", plate.id), why);
  calib::UtcInstant first = plate.images.front().mid_time;
  double span_s = 0.0;
  std::map<std::string, std::vector<int>> images_of_star;
  for (int i = 0; i < static_cast<int>(plate.images.size()); ++i) {
    const StarImageObservation& image = plate.images[i];
    CheckImage(plate, image);
    if (SecondsBetween(first, image.mid_time) < 0) first = image.mid_time;
    images_of_star[image.star_id].push_back(i);
  }
  for (const StarImageObservation& image : plate.images) span_s = std::max(span_s, SecondsBetween(first, image.mid_time));

  PreparedPlate out;
  out.first_time = first;
  out.span_s = span_s;
  double sum_sigma2 = 0.0;
  // Catalog stars first: their directions give the starting orientation.
  std::vector<const calib::CatalogStar*> stars;
  std::vector<calib::UtcInstant> times;
  std::vector<int> sources;
  for (const auto& [id, members] : images_of_star) {
    auto it = catalog.find(id);
    if (it == catalog.end()) continue;
    out.stars.push_back({id, true, it->second.sigma_arcsec * kArcsecToRad});
    for (int i : members) {
      stars.push_back(&it->second.star);
      times.push_back(plate.images[i].mid_time);
      sources.push_back(i);
    }
  }
  const int catalog_stars = static_cast<int>(out.stars.size());
  if (catalog_stars < kMinCatalogStars)
    throw Error(fmt::format("plate {}", plate.id),
                fmt::format("{} catalog stars identified; at least {} are needed", catalog_stars, kMinCatalogStars));
  std::vector<ImageDirection> directions = ComputeImageDirections(plate.place, stars, times);

  Eigen::Matrix3d m0;
  if (approx) {
    m0 = *approx;
  } else {
    std::vector<Eigen::Vector3d> enu, rays;
    for (size_t k = 0; k < sources.size(); ++k) {
      enu.push_back(directions[k].enu);
      rays.push_back(RayOf(plate.images[sources[k]], initial));
    }
    m0 = RotationFromStars(enu, rays);
  }

  // Unknown stars: a place from the first image through the starting orientation.
  std::vector<calib::CatalogStar> unknown_places;
  unknown_places.reserve(images_of_star.size());
  std::vector<std::pair<std::string, const std::vector<int>*>> unknown;
  for (const auto& [id, members] : images_of_star) {
    if (catalog.count(id)) continue;
    if (static_cast<int>(members.size()) < kMinUnknownStarImages) {
      Warn(fmt::format("plate {}: unknown star {} has {} images (fewer than {}): left out", plate.id, id,
                            members.size(), kMinUnknownStarImages));
      continue;
    }
    const StarImageObservation& image = plate.images[members.front()];
    const calib::ApparentPlaceCalculator calculator(plate.place, image.mid_time);
    unknown_places.push_back(calculator.Unobserve(m0.transpose() * RayOf(image, initial)));
    unknown.emplace_back(id, &members);
  }
  std::vector<const calib::CatalogStar*> unknown_stars;
  std::vector<calib::UtcInstant> unknown_times;
  std::vector<int> unknown_sources;
  for (size_t u = 0; u < unknown.size(); ++u) {
    out.stars.push_back({unknown[u].first, false, 0.0});
    for (int i : *unknown[u].second) {
      unknown_stars.push_back(&unknown_places[u]);
      unknown_times.push_back(plate.images[i].mid_time);
      unknown_sources.push_back(i);
    }
  }
  const std::vector<ImageDirection> unknown_directions =
      ComputeImageDirections(plate.place, unknown_stars, unknown_times);
  directions.insert(directions.end(), unknown_directions.begin(), unknown_directions.end());
  sources.insert(sources.end(), unknown_sources.begin(), unknown_sources.end());

  const int sets = span_s > 0.0 ? options.orientation_sets : 1;
  out.set_m0.assign(sets, m0);
  out.set_span_s.assign(sets, {1e300, -1e300});
  std::map<std::string, int> star_index;
  for (int s = 0; s < static_cast<int>(out.stars.size()); ++s) star_index[out.stars[s].id] = s;
  for (size_t k = 0; k < sources.size(); ++k) {
    const StarImageObservation& image = plate.images[sources[k]];
    PreparedImage p;
    p.source = sources[k];
    const double t_s = SecondsBetween(first, image.mid_time);
    p.time_s = t_s;
    p.set = sets == 1 ? 0 : std::min(sets - 1, static_cast<int>(std::floor(t_s / (span_s / sets))));
    p.star = star_index.at(image.star_id);
    p.equation.x_mm = image.x_mm;
    p.equation.y_mm = image.y_mm;
    p.equation.m0 = m0;
    p.equation.direction = directions[k];
    out.set_span_s[p.set].first = std::min(out.set_span_s[p.set].first, t_s);
    out.set_span_s[p.set].second = std::max(out.set_span_s[p.set].second, t_s);
    sum_sigma2 += image.sigma_x_mm * image.sigma_x_mm + image.sigma_y_mm * image.sigma_y_mm;
    out.images.push_back(std::move(p));
  }
  out.unit_sigma_um = 1000.0 * std::sqrt(sum_sigma2 / (2.0 * out.images.size()));
  return out;
}

void AlignToReference(const PreparedPlate& reference, PreparedPlate* plate) {
  const int sets = static_cast<int>(reference.set_m0.size());
  plate->set_m0 = reference.set_m0;
  plate->set_span_s.assign(sets, {1e300, -1e300});
  const double offset_s = SecondsBetween(reference.first_time, plate->first_time);
  for (PreparedImage& image : plate->images) {
    const double t_s = offset_s + image.time_s;  // after the reference's first image
    image.set = sets == 1 ? 0 : std::clamp(static_cast<int>(std::floor(t_s / (reference.span_s / sets))), 0, sets - 1);
    image.equation.m0 = reference.set_m0[image.set];
    plate->set_span_s[image.set].first = std::min(plate->set_span_s[image.set].first, t_s);
    plate->set_span_s[image.set].second = std::max(plate->set_span_s[image.set].second, t_s);
  }
}

}  // namespace platemeter::stellar_internal
