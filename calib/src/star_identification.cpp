// Star identification from an approximate pointing (star_identification.h):
// the driver, the reference epoch, the sky's rotation, refit and assignment.
#include "platemeter/calib/star_identification.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "star_identification_internal.h"

namespace platemeter {
namespace {

using namespace star_identification_internal;

double SecondsBetween(const calib::UtcInstant& a, const calib::UtcInstant& b) {
  return ((b.jd1 - a.jd1) + (b.jd2 - a.jd2)) * 86400.0;
}

// The epoch around which most stars have an image (within the window).
calib::UtcInstant ReferenceEpoch(const std::vector<DetectedStarImage>& images, double window_s) {
  std::set<std::pair<double, double>> times;
  for (const auto& image : images) times.insert({image.mid_time.jd1, image.mid_time.jd2});
  calib::UtcInstant best = images.front().mid_time;
  size_t best_count = 0;
  for (const auto& [jd1, jd2] : times) {
    const calib::UtcInstant t{jd1, jd2};
    std::set<std::string> stars;
    for (const auto& image : images) {
      if (std::abs(SecondsBetween(t, image.mid_time)) <= window_s) stars.insert(image.star_key);
    }
    if (stars.size() > best_count) best_count = stars.size(), best = t;
  }
  return best;
}

// The catalog stars above the horizon within `radius_rad` of the axis at the epoch.
std::vector<FieldStar> FieldAt(const StellarCatalog& catalog, const calib::ApparentPlaceOptions& place,
                               const calib::UtcInstant& epoch, const Eigen::Vector3d& axis, double radius_rad) {
  const calib::ApparentPlaceCalculator calculator(place, epoch);
  std::vector<FieldStar> field;
  for (const auto& [id, entry] : catalog) {
    const Eigen::Vector3d enu = calculator.Observe(entry.star).enu;
    if (enu.z() > 0.0 && std::acos(std::clamp(enu.dot(axis), -1.0, 1.0)) <= radius_rad)
      field.push_back({id, &entry.star, enu});
  }
  return field;
}

// The sky's turn about the pole as a rate and axis in the local frame: the
// rotation carrying the field's apparent places from `epoch` to `span_s` later.
SkyRotation FitSkyRotation(const std::vector<FieldStar>& field, const calib::ApparentPlaceOptions& place,
                           const calib::UtcInstant& epoch, double span_s) {
  const calib::ApparentPlaceCalculator later(place, epoch.PlusSeconds(span_s));
  Eigen::Matrix3Xd from(3, field.size()), to(3, field.size());
  for (size_t i = 0; i < field.size(); ++i) {
    from.col(i) = field[i].enu;
    to.col(i) = later.Observe(*field[i].star).enu;
  }
  const Eigen::AngleAxisd turn(Eigen::Matrix3d(Eigen::umeyama(from, to, false).topLeftCorner<3, 3>()));
  return {turn.axis(), turn.angle() / span_s};
}

}  // namespace

Eigen::Matrix3d SkyRotation::Over(double seconds) const {
  return Eigen::AngleAxisd(rate_rad_per_s * seconds, axis).toRotationMatrix();
}

bool IdentificationOptions::Check(std::string* why) const {
  if (!(pointing_tolerance_deg > 0 && pointing_tolerance_deg < 90) || !(window_s >= 0) ||
      !(side_tolerance_deg > 0) || !(verify_tolerance_deg > 0) || !(match_tolerance_arcsec > 0) ||
      !(false_alarm > 0 && false_alarm < 1) || neighbours < 2 || max_hypotheses < 1) {
    *why = "identification options out of range (tolerances positive, pointing tolerance below 90 deg, "
           "false_alarm in (0, 1), at least 2 neighbours)";
    return false;
  }
  if (!IsStellarLensModel(lens_model)) {
    *why = "lens_model must be one of " + StellarLensModelNames();
    return false;
  }
  return true;
}

IdentificationResult IdentifyStars(const std::vector<DetectedStarImage>& images, const StellarCatalog& catalog,
                                   const calib::ApparentPlaceOptions& place, const Eigen::Vector3d& axis_enu,
                                   const StellarCamera& camera, const IdentificationOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("star identification", why);
  if (images.empty()) throw Error("star identification", "no star images");
  if (static_cast<int>(camera.size()) != StellarCameraParamCount(options.lens_model))
    throw Error("star identification", fmt::format("the camera does not have the {} values of a {} camera",
                                                   StellarCameraParamCount(options.lens_model),
                                                   DistortionModelName(options.lens_model)));
  if (!(camera[0] > 0)) throw Error("star identification", "the nominal principal distance must be positive");
  IdentificationResult result;
  result.reference_epoch = ReferenceEpoch(images, options.window_s);
  double half_diagonal_mm = 0.0, span_s = 60.0;
  for (const auto& image : images) {
    half_diagonal_mm = std::max(half_diagonal_mm, std::hypot(image.x_mm, image.y_mm));
    span_s = std::max(span_s, std::abs(SecondsBetween(result.reference_epoch, image.mid_time)));
  }
  constexpr double kDeg = M_PI / 180.0;
  // The field: the format's half angle, the pointing's doubt, and the sky's turn over the plate.
  const double radius_rad = std::atan(half_diagonal_mm / camera[0]) + (options.pointing_tolerance_deg + 1.0) * kDeg +
                            span_s * 7.2921e-5;
  const std::vector<FieldStar> field =
      FieldAt(catalog, place, result.reference_epoch, axis_enu.normalized(), radius_rad);
  if (field.size() < 3) throw Error("star identification", "fewer than 3 catalog stars in the field of the pointing");
  const SkyRotation sky = FitSkyRotation(field, place, result.reference_epoch, span_s);
  FieldEpochs epochs;
  const std::vector<PlateStar> stars = GroupImages(images, camera, options.lens_model, result.reference_epoch, &epochs);

  const Hypothesis accepted = FindRotation(stars, field, sky, axis_enu.normalized(), options, &result);
  ObserveField(field, place, &epochs);
  AssignStars(stars, field, epochs, accepted.camera_from_enu, options, &result);
  return result;
}

}  // namespace platemeter
