#pragma once
// Inside the star identification (star_identification.h).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/star_identification.h"

namespace platemeter::star_identification_internal {

// A catalog star in the field: its apparent direction at the reference epoch.
struct FieldStar {
  std::string id;
  const calib::CatalogStar* star = nullptr;
  Eigen::Vector3d enu;
};

// The sky's turn about the pole in the local frame: Over(dt) carries an
// apparent direction from the reference epoch to dt seconds later.
struct SkyRotation {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double rate_rad_per_s = 0.0;
  Eigen::Matrix3d Over(double seconds) const;
};

// A detected star: its images' camera-frame rays (nominal camera) and times.
struct PlateStar {
  std::string key;
  std::vector<Eigen::Vector3d> rays;
  std::vector<double> dt_s;     // image time minus the reference epoch
  std::vector<int> epoch;       // index of the image's time in FieldEpochs
  int pattern = 0;              // the image nearest the reference epoch
};
// The field stars' apparent directions at each distinct image time (refraction
// and aberration exact, not the rotation's approximation).
struct FieldEpochs {
  std::vector<calib::UtcInstant> times;
  std::vector<std::vector<Eigen::Vector3d>> enu;  // [time][field star]
};
std::vector<PlateStar> GroupImages(const std::vector<DetectedStarImage>& images, const StellarCamera& camera,
                                   DistortionModelId lens, const calib::UtcInstant& reference_epoch,
                                   FieldEpochs* epochs);
void ObserveField(const std::vector<FieldStar>& field, const calib::ApparentPlaceOptions& place, FieldEpochs* epochs);

struct Hypothesis {
  Eigen::Matrix3d camera_from_enu = Eigen::Matrix3d::Identity();
  int matches = 0;
  double probability = 1.0;
};
// Triangles, hypotheses and their verification; throws when none passes.
Hypothesis FindRotation(const std::vector<PlateStar>& stars, const std::vector<FieldStar>& field,
                        const SkyRotation& sky, const Eigen::Vector3d& axis_enu, const IdentificationOptions& options,
                        IdentificationResult* result);
// Refit of the rotation and the star-by-star assignment.
void AssignStars(const std::vector<PlateStar>& stars, const std::vector<FieldStar>& field, const FieldEpochs& epochs,
                 const Eigen::Matrix3d& camera_from_enu, const IdentificationOptions& options,
                 IdentificationResult* result);

// Index of the field star nearest `enu` and the angles (rad) to it and to the second nearest.
struct Nearest {
  int index = -1;
  double angle_rad = 1e9;
  double second_rad = 1e9;
};
Nearest NearestFieldStar(const std::vector<FieldStar>& field, const Eigen::Vector3d& enu);
Nearest NearestOf(const std::vector<Eigen::Vector3d>& directions, const Eigen::Vector3d& enu);

}  // namespace platemeter::star_identification_internal
