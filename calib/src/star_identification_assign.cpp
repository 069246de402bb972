// The identified rotation refitted to every matched image, and each detected
// star assigned the catalog star all its images agree on (star_identification.h).
#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "platemeter/calib/distortion_models.h"
#include "star_identification_internal.h"

namespace platemeter::star_identification_internal {
namespace {

constexpr double kArcsecToRad = M_PI / (180.0 * 3600.0);
constexpr double kAgreeingShare = 0.8;  // of a star's images on one catalog star
constexpr double kFloorSigmaArcsec = 5.0;  // the images' scatter is never taken below this

struct Assignment {
  std::map<int, int> star_of;       // plate star -> field star
  std::vector<std::string> ambiguous;
  std::vector<std::string> unknown;
};

// Each plate star gets the catalog star most of its images fall nearest to
// (within `tolerance_rad`), when the images prefer it to the next nearest
// catalog star by a log-likelihood ratio of at least `min_log_ratio`
// (Gaussian errors of `sigma_rad`); otherwise it stays unknown (ambiguous when
// a second catalog star was the reason).
Assignment Assign(const std::vector<PlateStar>& stars, const FieldEpochs& epochs, const Eigen::Matrix3d& m, double tolerance_rad, double sigma_rad, double min_log_ratio) {
  Assignment out;
  for (int s = 0; s < static_cast<int>(stars.size()); ++s) {
    std::map<int, int> votes;
    std::map<int, double> log_ratio;  // per catalog star: sum of (second^2 - nearest^2) / (2 sigma^2)
    for (size_t i = 0; i < stars[s].rays.size(); ++i) {
      const Nearest n = NearestOf(epochs.enu[stars[s].epoch[i]], m.transpose() * stars[s].rays[i]);
      if (n.angle_rad > tolerance_rad) continue;
      ++votes[n.index];
      log_ratio[n.index] += (n.second_rad * n.second_rad - n.angle_rad * n.angle_rad) / (2 * sigma_rad * sigma_rad);
    }
    auto best = std::max_element(votes.begin(), votes.end(),
                                 [](const auto& a, const auto& b) { return a.second < b.second; });
    const bool agreed = best != votes.end() && best->second >= kAgreeingShare * stars[s].rays.size();
    const bool distinct = agreed && log_ratio[best->first] >= min_log_ratio;
    if (distinct) {
      out.star_of[s] = best->first;
    } else {
      out.unknown.push_back(stars[s].key);
      if (agreed) out.ambiguous.push_back(stars[s].key);
    }
  }
  return out;
}

// camera_from_enu from every image of the assigned stars (each at its own time).
Eigen::Matrix3d Refit(const std::vector<PlateStar>& stars, const FieldEpochs& epochs, const std::map<int, int>& star_of, double* rms_rad, const Eigen::Matrix3d& m_old) {
  std::vector<Eigen::Vector3d> from, to;
  for (const auto& [s, f] : star_of) {
    for (size_t i = 0; i < stars[s].rays.size(); ++i) {
      from.push_back(epochs.enu[stars[s].epoch[i]][f]);
      to.push_back(stars[s].rays[i]);
    }
  }
  if (from.size() < 3) return m_old;
  Eigen::Matrix3Xd a(3, from.size()), b(3, to.size());
  for (size_t k = 0; k < from.size(); ++k) a.col(k) = from[k], b.col(k) = to[k];
  const Eigen::Matrix3d m = Eigen::umeyama(a, b, false).topLeftCorner<3, 3>();
  *rms_rad = std::sqrt((m * a - b).colwise().squaredNorm().mean());
  return m;
}

// The camera-frame ray of a measured image, the lens's distortion undone: a
// correction lens (seeds 000, 004) in closed form, seed 001's distortion by
// fixed-point iteration (it is a few tens of um on an 80 mm lens: 4 steps reach 1e-9 mm).
Eigen::Vector3d RayOf(const DetectedStarImage& image, const StellarCamera& camera, DistortionModelId lens) {
  const double xb = image.x_mm - camera[1], yb = image.y_mm - camera[2];
  double x = xb, y = yb;
  VisitStellarLens(lens, [&](auto model) {
    using Lens = decltype(model);
    double dx = 0.0, dy = 0.0;
    if constexpr (Lens::kDirection == DistortionDirection::kCorrection) {
      Lens::Apply(camera.data() + 3, xb, yb, &dx, &dy);
      x = xb + dx;
      y = yb + dy;
    } else {
      for (int k = 0; k < 4; ++k) {
        Lens::Apply(camera.data() + 3, x, y, &dx, &dy);
        x = xb - dx;
        y = yb - dy;
      }
    }
  });
  return Eigen::Vector3d(x / camera[0], y / camera[0], 1.0).normalized();
}

}  // namespace

std::vector<PlateStar> GroupImages(const std::vector<DetectedStarImage>& images, const StellarCamera& camera,
                                   DistortionModelId lens, const calib::UtcInstant& reference_epoch,
                                   FieldEpochs* epochs) {
  std::map<std::pair<double, double>, int> epoch_index;
  std::map<std::string, int> index;
  std::vector<PlateStar> stars;
  for (const DetectedStarImage& image : images) {
    auto [it, added] = index.emplace(image.star_key, static_cast<int>(stars.size()));
    if (added) stars.push_back({image.star_key, {}, {}, {}, 0});
    auto [e, new_epoch] = epoch_index.emplace(std::pair{image.mid_time.jd1, image.mid_time.jd2},
                                              static_cast<int>(epochs->times.size()));
    if (new_epoch) epochs->times.push_back(image.mid_time);
    PlateStar& star = stars[it->second];
    star.rays.push_back(RayOf(image, camera, lens));
    star.epoch.push_back(e->second);
    star.dt_s.push_back(((image.mid_time.jd1 - reference_epoch.jd1) + (image.mid_time.jd2 - reference_epoch.jd2)) *
                        86400.0);
    if (std::abs(star.dt_s.back()) < std::abs(star.dt_s[star.pattern])) star.pattern = static_cast<int>(star.dt_s.size()) - 1;
  }
  return stars;
}

void ObserveField(const std::vector<FieldStar>& field, const calib::ApparentPlaceOptions& place, FieldEpochs* epochs) {
  epochs->enu.assign(epochs->times.size(), {});
  tbb::parallel_for(size_t{0}, epochs->times.size(), [&](size_t t) {
    const calib::ApparentPlaceCalculator calculator(place, epochs->times[t]);
    epochs->enu[t].reserve(field.size());
    for (const FieldStar& f : field) epochs->enu[t].push_back(calculator.Observe(*f.star).enu);
  });
}

void AssignStars(const std::vector<PlateStar>& stars, const std::vector<FieldStar>& field, const FieldEpochs& epochs,
                 const Eigen::Matrix3d& camera_from_enu, const IdentificationOptions& options,
                 IdentificationResult* result) {
  const double tolerance = options.match_tolerance_arcsec * kArcsecToRad;
  // First with the hypothesis' looser tolerance (its rotation is from three stars), then refit and tighten.
  Eigen::Matrix3d m = camera_from_enu;
  const double min_log_ratio = std::log(1.0 / options.false_alarm);
  double tolerance_used = options.verify_tolerance_deg * M_PI / 180.0;
  double rms_rad = tolerance_used / 3.0;
  Assignment a = Assign(stars, epochs, m, tolerance_used, rms_rad, min_log_ratio);
  for (int pass = 0; pass < 3; ++pass) {
    m = Refit(stars, epochs, a.star_of, &rms_rad, m);
    // Images scatter about the refitted rotation by rms (nominal camera, refraction):
    // never tighter than that allows, never looser than the option.
    rms_rad = std::max(rms_rad, kFloorSigmaArcsec * kArcsecToRad);
    tolerance_used = std::min(tolerance, 6.0 * rms_rad);
    a = Assign(stars, epochs, m, tolerance_used, rms_rad, min_log_ratio);
  }
  m = Refit(stars, epochs, a.star_of, &rms_rad, m);
  result->camera_from_enu = m;
  result->rms_arcsec = rms_rad / kArcsecToRad;
  for (const auto& [s, f] : a.star_of) result->catalog_id[stars[s].key] = field[f].id;
  result->unknown = a.unknown;
  result->ambiguous = a.ambiguous;
}

}  // namespace platemeter::star_identification_internal
