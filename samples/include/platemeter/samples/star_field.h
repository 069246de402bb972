#pragma once
// Real star fields for the simulator: catalog stars (calib/star_catalog.h) seen
// from a site at the instants of a shutter program (core/duty_cycle.h), with
// apparent places from ERFA (calib/apparent_place.h), rotated into the camera
// frame and projected through the camera's lens model (calib/camera_model.h)
// to plate millimetres. docs/simulator.md, "[star_field]", has the conventions.
//
// Camera frame. The plate frame is calib's collinearity frame (x = c u / w,
// y = c v / w, w > 0 in front): camera_from_enu = MatrixFromOmegaPhiKappa
// (rotations.h, seed 004's sequence) with omega, phi chosen so that its third
// row is the optical axis (azimuth A from north through east, altitude h) and
// kappa = roll. At the zenith with roll 0 the plate +x points to the images of
// eastern stars and +y to northern ones; roll turns the plate x axis from east
// toward north.
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/apparent_place.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/grids/definitions.h"
#include "platemeter/samples/geometry.h"

namespace platemeter::sim {

// Rotation from the site's local frame (x east, y north, z zenith) to the camera frame.
Eigen::Matrix3d CameraFromEnu(double axis_azimuth_deg, double axis_altitude_deg, double roll_deg);

// The camera's lens as the star field uses it: the lens calibration of the
// camera definition (calib's factory), or the nominal principal distance
// without distortion when the definition has none.
//
// Handedness: seed 001 prints the Orbigon calibration (principal point, point
// of symmetry, Phi_T) "in a left-handed coordinate system as viewed on the
// focal plane", i.e. with y flipped against the plate frame. The flip happens
// HERE and only here: for an "orbigon-11" lens the direction is mirrored
// (v -> -v) into the printed frame, projected with the printed values, and the
// result mirrored back (y -> -y). PrincipalPoint() is flipped the same way.
class PlateLens {
 public:
  explicit PlateLens(const CameraDefinition& camera);

  // Plate position (mm, x right, y up) of a direction given in the site's ENU
  // frame; nullopt behind the camera or if the distortion inverse fails.
  std::optional<PlatePoint> Project(const Eigen::Matrix3d& camera_from_enu, const Eigen::Vector3d& enu) const;
  PlatePoint PrincipalPoint() const;   // plate frame
  double principal_distance_mm() const { return model_.interior().principal_distance_mm; }
  bool printed_left_handed() const { return left_handed_; }
  const CameraModel& model() const { return model_; }

 private:
  CameraModel model_;
  bool left_handed_ = false;
};

struct StarFieldOptions {
  calib::ApparentPlaceOptions place;     // site, atmosphere, refraction, UT1-UTC
  calib::UtcInstant start_utc;           // first shutter opening (or the single exposure's opening)
  double axis_azimuth_deg = 0.0;         // deg; optical axis, from north through east
  double axis_altitude_deg = 90.0;       // deg; optical axis above the horizon (90: zenith)
  double roll_deg = 0.0;                 // deg; kappa (see CameraFromEnu)
  bool duty_cycle = true;                // seed 001 capping-shutter program; false: one exposure
  DutyCycleScheduleOptions schedule;     // start_s is ignored (times count from start_utc)
  double single_exposure_s = 1.0;        // s; the one exposure when !duty_cycle (0: a point image)

  bool Check(std::string* why) const;
};

enum class StarImageKind { kStar, kTrailDot, kTrailDash };

// One exposure of one star on the plate.
struct StarImage {
  std::string id;           // "<star>-T<trail>-D<dot>", "<star>-T<trail>-L<dash>", or "<star>" (single)
  std::string star_id;      // "HD<n>" or "KS<record>" (kstars record number)
  double v_mag = 0.0;
  StarImageKind kind = StarImageKind::kStar;
  int trail = 0;            // 1..4 (0: single exposure)
  int index = 0;            // dot 1..25 or dash 1..; 0 for a single exposure
  double open_s = 0.0, close_s = 0.0;  // s after start_utc
  std::string mid_time_utc; // ISO 8601, ms
  PlatePoint open_mm, close_mm;  // image when the shutter opens and closes
  PlatePoint mid_mm;        // image at mid-exposure: the TRUE position
};

struct StarFieldResult {
  std::vector<StarImage> images;  // star by star (input order), exposures in time order
  long skipped_below_horizon = 0; // star-exposures below the horizon at mid-exposure
  long skipped_outside = 0;       // star-exposures outside the format (or behind the camera)
  double max_arc_offset_um = 0.0; // max |mid image - (open + close)/2|: the rendered segment's
                                  // centre against the true position (arc sagitta, projection)
};

// The catalog id used in marks and truth.
std::string StarId(const calib::CatalogStar& star);

// Images of `stars` for every exposure. Skips images whose mid-exposure
// direction is below the horizon or outside the format (|x| > width/2 or
// |y| > height/2, mm, centred on the plate origin). Stars run in parallel.
StarFieldResult ComputeStarImages(const StarFieldOptions& options, const std::vector<calib::CatalogStar>& stars,
                                  const PlateLens& lens, double format_width_mm, double format_height_mm);

// The catalog stars that can reach the format during the plate: a cone around
// the optical axis at mid-plate, wide enough for the half diagonal plus the
// diurnal motion over the plate's duration (plus 2 deg of slack).
std::vector<calib::CatalogStar> LoadFieldStars(const StarFieldOptions& options, const std::string& catalog_path,
                                               double faint_limit_mag, const PlateLens& lens,
                                               double format_width_mm, double format_height_mm);

// Seconds from start_utc to the last shutter closing.
double PlateDuration_s(const StarFieldOptions& options);

}  // namespace platemeter::sim
