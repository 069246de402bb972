#pragma once
// What the self-calibrating bundle adjustment (seed 000, sections 2.1-2.3)
// takes in, as plain values: image observations, ground points, cameras with
// their a-priori knowledge, frames with approximate or a-priori exterior
// orientation, distances. Readers and checks: bundle_input_io.h; the
// adjustment: bundle_adjustment.h; the job file: docs/bundle-job.md.
//
// A-priori knowledge of a parameter follows seed 000 eqs. (3)-(5): an
// observation of the parameter with a standard deviation. ParameterState says
// how a parameter enters: free (no prior), fixed (sigma 0) or weighted.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/rotations.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

// One measured image point: camera frame, x right, y up, in mm from the frame's
// origin (the principal point is at (xp, yp) in this frame).
struct ImageObservation {
  std::string frame;     // frame id
  std::string point_id;  // ground / tie point id
  double x_mm = 0.0;
  double y_mm = 0.0;
  double sigma_x_mm = 0.0;  // mm; > 0
  double sigma_y_mm = 0.0;  // mm; > 0
  std::string origin;       // "file:line" it was read from, for messages ("" if made in memory)
};

// A ground point with a-priori coordinates. Per axis: sigma nullopt = free
// (an approximation only), 0 = fixed, > 0 = weighted. Points seen in the
// images but not listed are free tie points.
struct GroundPoint {
  std::string id;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  std::array<std::optional<double>, 3> sigma_m;  // m; X, Y, Z
  std::string origin;
};

// How one parameter enters the adjustment.
struct ParameterState {
  enum class Kind { kFree, kFixed, kWeighted };
  Kind kind = Kind::kFixed;
  double sigma = 0.0;  // the parameter's unit; > 0 for kWeighted
  static ParameterState Free() { return {Kind::kFree, 0.0}; }
  static ParameterState Fixed() { return {Kind::kFixed, 0.0}; }
  static ParameterState Weighted(double sigma) { return {Kind::kWeighted, sigma}; }
};

// The bundle's camera: c, xp, yp and BrownAffine's seven (distortion_models.h),
// in this order. Names as the models spell them.
constexpr int kBundleCameraParams = 10;
inline constexpr std::array<const char*, kBundleCameraParams> kBundleCameraParamNames = {
    "c_mm", "xp_mm", "yp_mm", "k1_per_mm2", "k2_per_mm4", "k3_per_mm6", "p1_per_mm", "p2_per_mm", "b1", "b2"};

struct CameraSetup {
  std::string name = "camera";
  // Initial (or a-priori) values in kBundleCameraParamNames order.
  std::array<double, kBundleCameraParams> values{};
  // Default: every parameter fixed at its value; the job frees or weights them.
  std::array<ParameterState, kBundleCameraParams> states{};
  double format_width_mm = 0.0;   // mm; the imaged format (profiles, plots, corner sigmas); 0 if unknown
  double format_height_mm = 0.0;  // mm
  // The camera definition it started from, if any: the calibrated camera keeps
  // its grid, fiducials and format (so that measure can load it) with the new lens.
  std::optional<CameraDefinition> definition;
};

// One frame (photograph). Exterior orientation in seed 000's T matrix
// (rotations.h PhiOmegaKappaT) and the exposure station in the object frame.
struct FrameSetup {
  std::string id;
  std::string camera;  // CameraSetup::name
  // Approximations; computed (resection, relative orientation) when absent.
  std::optional<Eigen::Vector3d> position_m;
  std::optional<PhiOmegaKappaT> angles;
  // A-priori observations of the station (seed 000 eq. 4): a full 3x3
  // covariance (e.g. Gyer's in-track / cross-track / radial, see
  // StationCovarianceFromTrack) and/or per-angle sigmas. Requires position_m /
  // angles as the a-priori values.
  std::optional<Eigen::Matrix3d> position_covariance_m2;
  std::optional<Eigen::Vector3d> angle_sigma_rad;  // phi, omega, kappa
  bool fixed = false;  // position and attitude held at the given values
};

// A measured distance between two points or two stations (ids; a station is
// named by its frame id), e.g. the scale of a datum by a fixed frame plus a distance.
struct DistanceObservation {
  std::string from;
  std::string to;
  double distance_m = 0.0;
  double sigma_m = 0.0;  // m; 0 = exact (enforced with a tiny sigma, 1e-9 of the distance)
};

struct BundleInput {
  std::vector<CameraSetup> cameras;
  std::vector<FrameSetup> frames;
  std::vector<ImageObservation> observations;
  std::vector<GroundPoint> ground_points;
  std::vector<DistanceObservation> distances;
};

// Gyer (1970), seed 000 section 3.3: the covariance of a station position from
// standard deviations along the track (the velocity direction made
// perpendicular to the radial), across it, and radially (from the body's
// centre, the object frame's origin), in the object frame. m^2.
Eigen::Matrix3d StationCovarianceFromTrack(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity,
                                           double sigma_in_track_m, double sigma_cross_track_m,
                                           double sigma_radial_m);

}  // namespace platemeter
