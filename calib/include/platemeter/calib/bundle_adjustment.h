#pragma once
// The self-calibrating bundle adjustment of seed 000 (sections 2.1-2.3): the
// collinearity equations (1) augmented with the inner cone (c, xp, yp, k1..k3,
// p1, p2, and the image frame's affinity b1, b2) shared by the frames of a
// camera, the exterior orientation of every frame in seed 000's T matrix
// (phi, omega, kappa) and the ground points, with a-priori observations on any
// of them (eqs. 3-5), solved by the adjustment engine (adjustment.h) with the
// ground points eliminated (the reduced normal equations of section 2.2).
//
// Object frame: metres, right-handed, any origin (a body-centred frame for
// orbital photography; Gyer's station covariances take the body's centre at
// the origin). Image frame: mm, x right, y up (bundle_input.h).
//
// Initial values are computed where the input gives none: resection from
// known points (OpenCV solvePnP), relative orientation of the best pair of
// frames where nothing is known (OpenCV essential matrix), forward
// intersection of the points, repeated until every frame is oriented; a
// network built in an arbitrary frame is moved onto the control points by a
// similarity transform.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/adjustment.h"
#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_options.h"

namespace platemeter {

// The frame parameters in their block: X_m, Y_m, Z_m, phi_rad, omega_rad, kappa_rad.
inline constexpr std::array<const char*, 6> kBundleFrameParamNames = {"X_m",     "Y_m",       "Z_m",
                                                                      "phi_rad", "omega_rad", "kappa_rad"};

struct BundleCameraResult {
  std::string name;
  std::array<double, kBundleCameraParams> values{};
  std::array<std::optional<double>, kBundleCameraParams> sigmas;  // scaled; none if fixed or not estimable
  std::array<EstimateStatus, kBundleCameraParams> status{};
  std::vector<int> parameter_index;  // into adjustment.parameters, kBundleCameraParamNames order
  double format_width_mm = 0.0;   // mm; as given, or from the observations' extent
  double format_height_mm = 0.0;  // mm
  bool format_from_observations = false;  // no format was given: the extent of the observations
  std::optional<CameraDefinition> definition;  // the definition it started from (CameraSetup::definition)
  // Significance tests (t for each radial term, F for the decentering pair and
  // the affinity pair), only for adjusted terms.
  std::vector<SignificanceTest> tests;
};

struct BundleFrameResult {
  std::string id;
  std::string camera;
  std::string initial_values;  // "given", "resection", "relative orientation", "fixed"
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  PhiOmegaKappaT angles;
  std::array<std::optional<double>, 6> sigmas;  // X, Y, Z m; phi, omega, kappa rad
  int observations = 0;       // used
  double rms_x_um = 0.0;      // residual RMS of the used observations
  double rms_y_um = 0.0;
};

struct BundlePointResult {
  std::string id;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  std::optional<Eigen::Vector3d> sigma_m;
  int rays = 0;
  bool control = false;  // had a prior
  double rms_um = 0.0;   // residual RMS over its rays (x and y)
};

struct BundleResult {
  BundleOptions options;  // as run
  AdjustmentResult adjustment;
  DatumKind datum = DatumKind::kAuto;  // the datum used (never kAuto)
  std::string datum_words;             // e.g. "control: 12 points", "frame 9565 held fixed"
  std::vector<BundleCameraResult> cameras;
  std::vector<BundleFrameResult> frames;
  std::vector<BundlePointResult> points;
  double initial_seconds = 0.0;  // computing approximations
};

// Runs the adjustment. Throws platemeter::Error for input it cannot use (an
// observation of an unknown frame, a frame of an unknown camera, a frame that
// cannot be oriented, all frames at one station); run the checks of
// bundle_input_io.h first for warnings instead of errors.
BundleResult RunBundleAdjustment(const BundleInput& input, const BundleOptions& options,
                                 const AdjustmentProgress& progress = {});

// Approximations only (exposed for tests): fills every frame's position and
// angles and returns the points' approximate coordinates by id, with what each
// frame's initial values came from.
struct BundleApproximations {
  std::vector<FrameSetup> frames;  // input order, position_m and angles set
  std::vector<std::string> method;  // per frame
  std::vector<std::pair<std::string, Eigen::Vector3d>> points;
};
BundleApproximations ComputeBundleApproximations(const BundleInput& input);

}  // namespace platemeter
