// Catalog stars -> plate images for every exposure of the shutter program.
#include "platemeter/samples/star_field.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/parallel_for.h>

#include "platemeter/calib/rotations.h"
#include "platemeter/core/error.h"
#include "platemeter/core/why.h"

namespace platemeter::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

CameraModel ModelOf(const CameraDefinition& camera) {
  if (camera.lens) return CameraModelFromLensCalibration(*camera.lens, "camera " + camera.name);
  if (!(camera.nominal_principal_distance_mm > 0.0)) {
    throw Error("camera " + camera.name, "no lens calibration and no nominal principal distance for the star field");
  }
  return CameraModel(InteriorOrientation{camera.nominal_principal_distance_mm, 0.0, 0.0}, DistortionModelId::kNone,
                     {});
}

// Seed 001 is the source of the only "orbigon-11" calibration and prints it in
// its left-handed focal-plane frame (see the header).
bool PrintedLeftHanded(const CameraDefinition& camera) { return camera.lens && camera.lens->model == "orbigon-11"; }

struct Exposure {
  double open_s = 0.0, close_s = 0.0;
  StarImageKind kind = StarImageKind::kStar;
  int trail = 0, index = 0;
};

std::vector<Exposure> Exposures(const StarFieldOptions& options) {
  std::vector<Exposure> out;
  if (!options.duty_cycle) {
    out.push_back({0.0, options.single_exposure_s, StarImageKind::kStar, 0, 0});
    return out;
  }
  DutyCycleScheduleOptions schedule = options.schedule;
  schedule.start_s = 0.0;
  for (const ShutterExposure& e : BuildShutterSchedule(schedule)) {
    const bool dot = e.kind == ExposureKind::kDot;
    out.push_back({e.open_s, e.close_s, dot ? StarImageKind::kTrailDot : StarImageKind::kTrailDash, e.trail,
                   dot ? e.dot_index : e.dash_index});
  }
  return out;
}

}  // namespace

Eigen::Matrix3d CameraFromEnu(double axis_azimuth_deg, double axis_altitude_deg, double roll_deg) {
  const double a = axis_azimuth_deg * kDeg, h = axis_altitude_deg * kDeg;
  // Third row of seed 004's M = (sin phi, -sin omega cos phi, cos omega cos phi) = the axis in ENU.
  const double east = std::sin(a) * std::cos(h), north = std::cos(a) * std::cos(h), up = std::sin(h);
  const double phi = std::asin(std::clamp(east, -1.0, 1.0));
  const double omega = std::atan2(-north, up);
  return MatrixFromOmegaPhiKappa({omega, phi, roll_deg * kDeg});
}

PlateLens::PlateLens(const CameraDefinition& camera) : model_(ModelOf(camera)), left_handed_(PrintedLeftHanded(camera)) {}

std::optional<PlatePoint> PlateLens::Project(const Eigen::Matrix3d& camera_from_enu, const Eigen::Vector3d& enu) const {
  const double flip = left_handed_ ? -1.0 : 1.0;
  Eigen::Matrix3d m = camera_from_enu;
  m.row(1) *= flip;  // into the printed (left-handed) frame: v -> -v
  const std::optional<Eigen::Vector2d> p = model_.ProjectDirection(m, enu);
  if (!p) return std::nullopt;
  return PlatePoint{(*p)(0), flip * (*p)(1)};  // and back: y -> -y
}

PlatePoint PlateLens::PrincipalPoint() const {
  const double flip = left_handed_ ? -1.0 : 1.0;
  return {model_.interior().principal_point_x_mm, flip * model_.interior().principal_point_y_mm};
}

bool StarFieldOptions::Check(std::string* why) const {
  if (!place.Check(why)) return false;
  if (!(axis_altitude_deg > 0.0 && axis_altitude_deg <= 90.0)) return Fail(why, "axis altitude must lie in (0, 90] deg");
  if (!std::isfinite(axis_azimuth_deg) || !std::isfinite(roll_deg)) return Fail(why, "axis azimuth and roll must be finite");
  if (duty_cycle) {
    if (!schedule.Check(why)) return false;
  } else if (!(single_exposure_s >= 0.0 && single_exposure_s <= 86400.0)) {
    return Fail(why, "single exposure time must lie in 0..86400 s");
  }
  return true;
}

std::string StarId(const calib::CatalogStar& star) { return calib::CatalogStarKey(star); }

double PlateDuration_s(const StarFieldOptions& options) {
  double end = 0.0;
  for (const Exposure& e : Exposures(options)) end = std::max(end, e.close_s);
  return end;
}

StarFieldResult ComputeStarImages(const StarFieldOptions& options, const std::vector<calib::CatalogStar>& stars,
                                  const PlateLens& lens, double format_width_mm, double format_height_mm) {
  std::string why;
  if (!options.Check(&why)) throw Error("star field", why);
  const std::vector<Exposure> exposures = Exposures(options);
  // One ERFA set-up per instant (open, mid, close of every exposure).
  const size_t n = exposures.size();
  std::vector<std::optional<calib::ApparentPlaceCalculator>> at(3 * n);
  tbb::parallel_for(size_t{0}, 3 * n, [&](size_t k) {
    const Exposure& e = exposures[k / 3];
    const double t = k % 3 == 0 ? e.open_s : k % 3 == 1 ? 0.5 * (e.open_s + e.close_s) : e.close_s;
    at[k].emplace(options.place, options.start_utc.PlusSeconds(t));
  });
  std::vector<std::string> mid_times(n);
  for (size_t i = 0; i < n; ++i) {
    mid_times[i] = calib::FormatUtcIso8601(options.start_utc.PlusSeconds(0.5 * (exposures[i].open_s + exposures[i].close_s)), 3);
  }
  const Eigen::Matrix3d camera_from_enu =
      CameraFromEnu(options.axis_azimuth_deg, options.axis_altitude_deg, options.roll_deg);
  const double half_w = format_width_mm / 2, half_h = format_height_mm / 2;

  struct PerStar {
    std::vector<StarImage> images;
    long below = 0, outside = 0;
    double arc_um = 0.0;
  };
  std::vector<PerStar> per_star(stars.size());
  tbb::parallel_for(size_t{0}, stars.size(), [&](size_t s) {
    const calib::CatalogStar& star = stars[s];
    PerStar& out = per_star[s];
    const std::string star_id = StarId(star);
    for (size_t i = 0; i < n; ++i) {
      const calib::ObservedPlace mid = at[3 * i + 1]->Observe(star);
      if (!(mid.altitude_rad > 0.0)) {
        ++out.below;
        continue;
      }
      const std::optional<PlatePoint> p_mid = lens.Project(camera_from_enu, mid.enu);
      if (!p_mid || std::abs(p_mid->x_mm) > half_w || std::abs(p_mid->y_mm) > half_h) {
        ++out.outside;
        continue;
      }
      const std::optional<PlatePoint> p_open = lens.Project(camera_from_enu, at[3 * i]->Observe(star).enu);
      const std::optional<PlatePoint> p_close = lens.Project(camera_from_enu, at[3 * i + 2]->Observe(star).enu);
      if (!p_open || !p_close) {
        ++out.outside;
        continue;
      }
      const Exposure& e = exposures[i];
      StarImage image;
      image.star_id = star_id;
      image.v_mag = star.v_mag;
      image.kind = e.kind;
      image.trail = e.trail;
      image.index = e.index;
      switch (e.kind) {
        case StarImageKind::kStar: image.id = star_id; break;
        case StarImageKind::kTrailDot: image.id = star_id + "-T" + std::to_string(e.trail) + "-D" + std::to_string(e.index); break;
        case StarImageKind::kTrailDash: image.id = star_id + "-T" + std::to_string(e.trail) + "-L" + std::to_string(e.index); break;
      }
      image.open_s = e.open_s;
      image.close_s = e.close_s;
      image.mid_time_utc = mid_times[i];
      image.open_mm = *p_open;
      image.close_mm = *p_close;
      image.mid_mm = *p_mid;
      const double arc_um = 1e3 * std::hypot(p_mid->x_mm - 0.5 * (p_open->x_mm + p_close->x_mm),
                                             p_mid->y_mm - 0.5 * (p_open->y_mm + p_close->y_mm));
      out.arc_um = std::max(out.arc_um, arc_um);
      out.images.push_back(std::move(image));
    }
  });
  StarFieldResult result;
  for (PerStar& p : per_star) {
    for (StarImage& image : p.images) result.images.push_back(std::move(image));
    result.skipped_below_horizon += p.below;
    result.skipped_outside += p.outside;
    result.max_arc_offset_um = std::max(result.max_arc_offset_um, p.arc_um);
  }
  return result;
}

std::vector<calib::CatalogStar> LoadFieldStars(const StarFieldOptions& options, const std::string& catalog_path,
                                               double faint_limit_mag, const PlateLens& lens,
                                               double format_width_mm, double format_height_mm) {
  // The axis at mid-plate in equatorial coordinates, roughly (mean sidereal
  // time, no precession: the cone's slack covers both).
  const double duration_s = PlateDuration_s(options);
  const calib::UtcInstant mid = options.start_utc.PlusSeconds(0.5 * duration_s);
  const double jd = mid.jd1 + mid.jd2;
  const double gmst_deg = 280.46061837 + 360.98564736629 * (jd - 2451545.0);
  const double lst = gmst_deg * kDeg + options.place.site.longitude_rad;
  const double lat = options.place.site.latitude_rad;
  const double a = options.axis_azimuth_deg * kDeg, h = options.axis_altitude_deg * kDeg;
  const double sin_dec = std::sin(lat) * std::sin(h) + std::cos(lat) * std::cos(h) * std::cos(a);
  const double dec = std::asin(std::clamp(sin_dec, -1.0, 1.0));
  // Hour angle (west positive) from the local frame: east = -cos(dec) sin(H).
  const double east = std::cos(h) * std::sin(a);
  const double north = std::cos(h) * std::cos(a), up = std::sin(h);
  const double hour_angle = std::atan2(-east, std::cos(lat) * up - std::sin(lat) * north);
  calib::StarQueryOptions query;
  query.faint_limit_mag = faint_limit_mag;
  query.whole_sky = false;
  query.center_ra_rad = std::remainder(lst - hour_angle, 2 * kPi);
  if (query.center_ra_rad < 0) query.center_ra_rad += 2 * kPi;
  query.center_dec_rad = dec;
  const double half_diagonal_mm = 1.05 * std::hypot(format_width_mm, format_height_mm) / 2;
  const double field_rad = std::atan(half_diagonal_mm / lens.principal_distance_mm());
  const double drift_rad = 0.5 * duration_s * 15.0411 / 3600.0 * kDeg;
  query.radius_rad = std::min(kPi, field_rad + drift_rad + 2.0 * kDeg);
  return calib::LoadStarCatalog(catalog_path, query);
}

}  // namespace platemeter::sim
