#pragma once
// Simulated photogrammetric blocks for the self-calibrating bundle adjustment
// (calib/bundle_input.h; docs/bundle-simulator.md). Each generator places
// exposure stations and ground points, projects every point into every frame
// that sees it through the true camera (calib/camera_model.h
// ProjectDirectionT<BrownAffine>: seed 000 eq. 1, the distortion in its
// CORRECTION form, inverted by MeasuredFromIdeal), adds Gaussian noise of the
// stated sigma to the measured coordinates and returns
//   - a BundleInput with the noisy observations, one camera, the frames and the
//     ground points as approximations (truth, or truth perturbed by
//     ApproximationOptions); every camera parameter is left FIXED (the
//     CameraSetup default), every frame free (fixed = false, no priors) and every
//     ground point free (sigmas nullopt): the caller frees, fixes or weights;
//   - a BundleTruth with the true camera, stations, points and the noise-free
//     observations (same order as the noisy ones).
//
// Geometries:
//   SimulateLunarBlock   seed 000 section 4 (Fig. 3, Tables 9 and 10) and the
//                        Apollo 14 case of section 3 (Apollo14Section3Options):
//                        three lunar orbits, three convergent exposures per orbit
//                        aimed at one ground area; moon-centred object frame.
//   SimulatePlanarTarget a flat N x M target field seen from ~15 poses, with the
//                        per-view object points and image points in PIXELS in
//                        OpenCV's convention (calibrateCamera side by side).
//   SimulateAerialBlock  a large aerial block (strips x frames, overlaps in both
//                        directions, convergent tilts, rotated kappa, relief) for
//                        the speed benchmark (bench/bench_bundle.cpp).
//
// Conventions. Plate coordinates mm, x right, y up (DESIGN.md), origin at the
// centre of the format; the principal point is at (xp, yp) in that frame.
// Frame attitudes are seed 000's T matrix (rotations.h, image_from_object, rows
// (A,B,C), (A',B',C'), (D,E,F)); (D,E,F) is the optical axis, pointing from the
// station toward the scene. Object coordinates in metres.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/core/why.h"  // Fail, used by the generators

namespace platemeter::sim {

// The true camera: c, xp, yp and BrownAffine's seven, the bundle's order
// (kBundleCameraParamNames), plus the format. Defaults: a 80 mm Hasselblad
// (55 x 55 mm) with a few tens of micrometres of radial and a few of
// decentering distortion at the corner.
struct BundleCameraTruth {
  double c_mm = 80.0;            // mm; principal distance
  double xp_mm = 0.012;          // mm; principal point in the plate frame
  double yp_mm = -0.008;         // mm
  double k1_per_mm2 = 2.0e-6;    // 1/mm^2; Gaussian radial correction (seed 000 eq. 1)
  double k2_per_mm4 = -4.0e-10;  // 1/mm^4
  double k3_per_mm6 = 0.0;       // 1/mm^6
  double p1_per_mm = 3.6e-6;     // 1/mm; decentering (Table 1's order of magnitude)
  double p2_per_mm = 3.0e-6;     // 1/mm
  double b1 = 0.0;               // -; affinity (x scale)
  double b2 = 0.0;               // -; affinity (non-orthogonality)
  double format_width_mm = 55.0;   // mm; imaged format, centred on the plate origin
  double format_height_mm = 55.0;  // mm

  // In kBundleCameraParamNames order.
  std::array<double, kBundleCameraParams> Values() const;
  bool Check(std::string* why) const;
};

// Starting values written into the BundleInput. All zero (the default): the
// approximations are the truth. Otherwise truth plus Gaussian perturbations
// (seeded by the block's seed), so a solver has to converge.
struct ApproximationOptions {
  double station_sigma_m = 0.0;           // m; per axis, exposure stations
  double angle_sigma_deg = 0.0;           // deg; per angle (phi, omega, kappa)
  double point_sigma_m = 0.0;             // m; per axis, ground points
  double principal_distance_sigma_mm = 0.0;  // mm; c
  double principal_point_sigma_mm = 0.0;  // mm; xp, yp
  bool zero_distortion = false;           // k1..k3, p1, p2, b1, b2 start at 0
  bool Check(std::string* why) const;
};

// One exposure station, true.
struct StationTruth {
  std::string id;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // object frame
  PhiOmegaKappaT angles;                                  // seed 000's T angles
  Eigen::Matrix3d image_from_object = Eigen::Matrix3d::Identity();  // T
  // Rotation of the image about the optical axis against the reference
  // direction (the flight direction, or the target's x axis), deg:
  // T = R3(roll) T0 (rotations.h R3), T0 the attitude whose image +x axis is
  // the reference made perpendicular to the optical axis; the reference then
  // appears in the image at angle -roll from +x (RollAboutAxisDeg).
  double roll_deg = 0.0;
  int group = 0;                   // orbit (lunar), strip (aerial), 0 (planar)
  int index_in_group = 0;          // exposure within the orbit / strip
  Eigen::Vector3d velocity_direction = Eigen::Vector3d::UnitX();  // unit; along track (Gyer's covariance)
  Eigen::Vector3d OpticalAxis() const { return image_from_object.row(2).transpose(); }
};

struct PointTruth {
  std::string id;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

struct BundleTruth {
  BundleCameraTruth camera;
  std::vector<StationTruth> stations;          // same order as BundleInput::frames
  std::vector<PointTruth> points;              // same order as BundleInput::ground_points
  std::vector<ImageObservation> observations;  // noise-free; same order as BundleInput::observations
  double sigma_mm = 0.0;                       // mm; the noise added, per axis
};

struct SimulatedBlock {
  BundleInput input;
  BundleTruth truth;
  std::string summary;  // one line: frames, points, observations, what the geometry is
};

// ---------------------------------------------------------------------------
// a) and b): lunar orbits (seed 000 sections 3 and 4).
//
// Object frame: moon-centred, metres; +Z through the centre G of the common
// ground area (the point beneath the centre frames), +X the flight direction
// at G, +Y = Z x X (across the track). Each orbit is a great circle at radius
// moon_radius + altitude, offset across the track from G by
// (revolution - mean revolution) * track_spacing. Its exposures sit at orbit
// angles spaced so that the optical axes of the orbit's end frames make
// convergence_deg with each other, and EVERY optical axis is aimed at G (the
// end frames by the pitch manoeuvre, the centre frames with the small roll
// the across-track offset needs). Exposure j of an orbit is turned about its
// optical axis by kappa_start + j * kappa_increment (Fig. 3's arrows: 90 deg).
// Passpoints lie at random heights (uniform, +-relief/2) about the sphere,
// spread (farthest-point sampling) over the ground seen by at least
// min_frames_per_point frames, so that they fill the formats.
struct LunarBlockOptions {
  BundleCameraTruth camera;                // true camera (focal length, format, distortion)
  double moon_radius_m = 1737.4e3;         // m
  double altitude_m = 108.5e3;             // m; above the sphere
  // Revolution numbers, one orbit each; consecutive by default (section 4).
  // Apollo 14 (section 3): {27, 28, 30}.
  std::vector<int> revolutions = {1, 2, 3};
  // m; across-track shift of the ground track per revolution: the Moon turns
  // 1.085 deg under a 108.5 km orbit in one period (7117 s of 27.32 d), 32.9 km
  // at the equator, times sin(inclination) for a low inclination of ~15 deg.
  double track_spacing_m = 8.5e3;
  int exposures_per_orbit = 3;             // >= 2
  double convergence_deg = 80.0;           // deg; between the optical axes of an orbit's end frames
  double kappa_start_deg = 0.0;            // deg; roll of the first exposure of every orbit
  double kappa_increment_deg = 90.0;       // deg; roll added from one exposure to the next (0: Apollo 14)
  // true: the rolls carry on from orbit to orbit (exposure k of the whole
  // sequence at kappa_start + k * increment: Fig. 3's "camera is rotated 90 deg
  // between individual exposures", so that frames looking the same way differ
  // in kappa, as section 2.3 asks); false: every orbit starts again at kappa_start.
  bool rolls_continue_across_orbits = false;
  int passpoints = 215;
  int min_frames_per_point = 0;            // frames that must see a passpoint; 0 = all frames (the common area)
  double relief_m = 300.0;                 // m; passpoint heights uniform in +-relief/2 about the sphere
  double format_margin_mm = 0.5;           // mm; passpoints this far inside the format edges
  double sigma_um = 15.0;                  // um; image measurement noise per axis (Table 9: 15, Table 10: 5); 0 = none
  double weight_sigma_um = 0.0;            // um; the sigma written with each observation; 0 = sigma_um
  ApproximationOptions approximations;
  std::vector<std::string> frame_ids;      // optional, one per frame (orbit by orbit); default "R<rev>-E<j>"
  std::uint64_t seed = 1;                  // noise, heights, placement, approximations
  bool Check(std::string* why) const;
};

// Seed 000 section 4, Table 9: a Hasselblad of the given focal length (50, 80,
// 150 or 500 mm) on the 55 x 55 mm format, 15 um, 215 passpoints, the rolls
// carrying on across the orbits (docs/precision-simulation.md: restarting them
// on every orbit gives 3 to 4 times the paper's sigmas in every row).
LunarBlockOptions Seed000Table9Options(double focal_length_mm);
// Seed 000 section 4, Table 10: the metric lunar terrain camera, 76.2 mm on
// 114.3 x 114.3 mm, 5 um, otherwise the same geometry.
LunarBlockOptions Seed000Table10Options();
// Seed 000 section 3 (the Apollo 14 data): revolutions 27, 28 and 30, three
// frames each (the frame numbers of Fig. 1), the SAME kappa for every frame,
// the 500 mm Hasselblad (8 deg across the diagonal), 15 um, ~170 passpoints.
// With this narrow field and no kappa differences xp and yp are not
// recoverable (section 2.3).
LunarBlockOptions Apollo14Section3Options();

SimulatedBlock SimulateLunarBlock(const LunarBlockOptions& options);

// ---------------------------------------------------------------------------
// c) A planar target field seen from varied poses; OpenCV's view of it.
//
// Object frame: the target plane is Z = 0, point (i, j) at (i * spacing,
// j * spacing, 0), i = 0..columns-1, j = 0..rows-1 (ids "B<i>-<j>"); the
// cameras are on the +Z side. Pose k looks at a point near the target's
// centre from a direction tilted from the plane normal by a tilt in
// [min_tilt, max_tilt] toward an azimuth that turns by the golden angle from
// pose to pose, rolled about its axis by a random angle in +-max_roll, from the
// smallest distance (>= min_distance) at which every target point lies inside
// the format (margin included).
//
// Pixels (OpenCV's convention, the same as DESIGN.md's: x = column, y = row,
// centre of the top-left pixel at (0, 0)). The format of width W mm is
// W_px = round(W / pixel) pixels wide; the plate origin (the format centre) is
// at ((W_px - 1)/2, (H_px - 1)/2) and
//   column = x_mm / pixel + (W_px - 1) / 2,   row = y_mm / pixel + (H_px - 1) / 2,
// i.e. plate +y runs DOWN the rows. That way OpenCV's camera frame is seed
// 000's image frame itself, X_cam = (A,B,C).d, Y_cam = (A',B',C').d, Z_cam =
// (D,E,F).d, so R (rvec) = T, a proper rotation, and t = -T * station; the
// pixel image is the plate as seen looking along the optical axis, which is
// DESIGN.md's display mirrored top to bottom. Pinhole intrinsics:
//   fx = fy = c / pixel,  cx = xp / pixel + (W_px - 1)/2,  cy = yp / pixel + (H_px - 1)/2.
// OpenCV's distortion (distortion form, normalized coordinates) is not
// BrownAffine (correction form, mm); to first order k1_cv = -k1 c^2,
// k2_cv = -k2 c^4, k3_cv = -k3 c^6, p1_cv = -p2 c, p2_cv = -p1 c.
struct PixelMapping {
  double pixel_size_um = 5.0;  // um; square pixels
  int width_px = 0;            // round(format width / pixel)
  int height_px = 0;
  Eigen::Vector2d PixelFromPlate(const Eigen::Vector2d& point_mm) const;
  Eigen::Vector2d PlateFromPixel(const Eigen::Vector2d& point_px) const;
};
PixelMapping MakePixelMapping(const BundleCameraTruth& camera, double pixel_size_um);

// The OpenCV pinhole part of a camera (mapping above): fx, fy, cx, cy in pixels.
struct OpenCvIntrinsics {
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0, cy_px = 0.0;
};
OpenCvIntrinsics OpenCvIntrinsicsFromCamera(const BundleCameraTruth& camera, const PixelMapping& pixels);

struct PlanarTargetOptions {
  // True camera; default a 16 mm lens on an 18 x 12 mm sensor.
  BundleCameraTruth camera = DefaultPlanarCamera();
  int columns = 12;                 // target points along X
  int rows = 9;                     // target points along Y
  double spacing_m = 0.04;          // m; between neighbouring points
  int views = 15;                   // poses
  double min_tilt_deg = 10.0;       // deg; from the target's normal
  double max_tilt_deg = 45.0;       // deg
  double max_roll_deg = 90.0;       // deg; about the optical axis, uniform in +-max_roll
  double aim_jitter_m = 0.03;       // m; aim point uniform within this of the target's centre (per axis)
  double min_distance_m = 0.3;      // m; from the aim point; increased until the target fits
  double format_margin_mm = 0.3;    // mm; every point this far inside the format edges
  double pixel_size_um = 6.0;       // um; for the OpenCV views
  double sigma_um = 0.6;            // um; measurement noise per axis (0.1 px); 0 = none
  double weight_sigma_um = 0.0;     // um; the sigma written with each observation; 0 = sigma_um
  ApproximationOptions approximations;
  std::uint64_t seed = 1;
  bool Check(std::string* why) const;
  static BundleCameraTruth DefaultPlanarCamera();
};

// One pose as OpenCV's calibrateCamera takes it (object points in metres, in
// the target's frame; image points in pixels per PixelMapping).
struct PlanarTargetView {
  std::string frame;
  std::vector<std::string> point_ids;
  std::vector<Eigen::Vector3d> object_points_m;
  std::vector<Eigen::Vector2d> image_points_px;       // noisy (= the BundleInput observations)
  std::vector<Eigen::Vector2d> true_image_points_px;  // noise-free
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // OpenCV R (camera from target) = T
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero(); // OpenCV t = -T * station
};

struct PlanarTargetBlock {
  SimulatedBlock block;
  PixelMapping pixels;
  OpenCvIntrinsics intrinsics;  // true pinhole part in OpenCV terms
  std::vector<PlanarTargetView> views;
};

PlanarTargetBlock SimulatePlanarTarget(const PlanarTargetOptions& options);

// ---------------------------------------------------------------------------
// d) A large aerial block for the speed benchmark.
//
// Object frame: local Cartesian, metres, X east (the strips' direction), Y
// north, Z up; the terrain datum is Z = 0. `strips` strips of
// `frames_per_strip` frames, spaced by the overlaps (the footprint of a
// vertical frame on the datum times 1 - overlap); alternate strips are flown
// in opposite directions (flight-direction reference turned by 180 deg).
// Frame k of a strip is rolled by k * kappa_increment and tilted by tilt_deg
// from the vertical toward the azimuth (k mod 4) * 90 deg (forward, left,
// back, right: convergent pairs in both directions). Points: uniform over the
// rectangle of the stations extended by point_area_extension footprints on
// every side (heights uniform in +-relief/2), kept if seen by at
// least min_frames_per_point frames, until `points` are placed; each point is
// observed in every frame whose format (margin included) it falls in.
struct AerialBlockOptions {
  // True camera; default a 153 mm mapping camera on 230 x 230 mm.
  BundleCameraTruth camera = DefaultAerialCamera();
  int strips = 10;
  int frames_per_strip = 20;
  double forward_overlap = 0.8;     // -; of the vertical footprint along the strip
  double side_overlap = 0.8;        // -; across the strips
  double flying_height_m = 1530.0;  // m; above the datum
  double tilt_deg = 15.0;           // deg; from the vertical (convergence)
  double kappa_increment_deg = 90.0;  // deg; roll added from frame to frame
  int points = 20000;
  // -; the points' rectangle extends beyond the stations' rectangle by this
  // fraction of the vertical footprint on every side (0: points under the
  // stations only, ~25 frames each at 80/80 %; 0.3: ~20 on average).
  double point_area_extension = 0.3;
  int min_frames_per_point = 2;
  double relief_m = 200.0;          // m; point heights uniform in +-relief/2
  double format_margin_mm = 1.0;    // mm
  double sigma_um = 3.0;            // um; per axis; 0 = none
  double weight_sigma_um = 0.0;     // um; the sigma written with each observation; 0 = sigma_um
  ApproximationOptions approximations;
  std::uint64_t seed = 1;
  bool Check(std::string* why) const;
  static BundleCameraTruth DefaultAerialCamera();
};

SimulatedBlock SimulateAerialBlock(const AerialBlockOptions& options);

// ---------------------------------------------------------------------------
// Helpers shared by the generators, the tests and the benchmark.

// Measured plate coordinates (mm) of an object point in a frame through the
// true camera, or false if behind the camera or the distortion inverse fails.
bool ProjectPoint(const BundleCameraTruth& camera, const Eigen::Matrix3d& image_from_object,
                  const Eigen::Vector3d& station_m, const Eigen::Vector3d& point_m, Eigen::Vector2d* plate_mm);

// Degrees between the optical axes of two stations.
double ConvergenceAngleDeg(const StationTruth& a, const StationTruth& b);

// The roll (deg, in (-180, 180]) of an image about its optical axis against a
// reference direction in the object frame (StationTruth::roll_deg when the
// reference is the one the generator used).
double RollAboutAxisDeg(const Eigen::Matrix3d& image_from_object, const Eigen::Vector3d& reference);

// ---------------------------------------------------------------------------
// The generators' shared steps (samples/src/bundle_block*.cpp); not an API.
namespace bundle_internal {

enum class Stream : std::uint64_t { kNoise = 1, kPlacement = 2, kApproximations = 3, kPoses = 4 };
std::uint64_t DeriveSeed(std::uint64_t seed, Stream stream);
[[noreturn]] void Throw(const std::string& why);  // platemeter::Error("bundle simulator", why)
bool CheckSigmas(double sigma_um, double weight_sigma_um, std::string* why);
inline double Rad(double deg) { return deg * 0.017453292519943295; }
inline double Deg(double rad) { return rad * 57.29577951308232; }
double WrapDeg(double deg);  // (-180, 180]
// T whose third row is `axis` (normalized) and whose first row is `reference`
// made perpendicular to it, turned by R3(roll).
Eigen::Matrix3d AttitudeFromAxis(const Eigen::Vector3d& axis, const Eigen::Vector3d& reference, double roll_deg);
bool InsideFormat(const BundleCameraTruth& camera, const Eigen::Vector2d& plate_mm, double margin_mm);
bool SeenInFormat(const BundleCameraTruth& camera, const StationTruth& station, const Eigen::Vector3d& point_m,
                  double margin_mm);

struct AssembleInput {
  BundleCameraTruth camera;
  std::string camera_name;
  std::vector<StationTruth> stations;
  std::vector<PointTruth> points;
  std::vector<std::vector<int>> frames_of_point;  // station indices seeing each point
  double sigma_um = 0.0;
  double weight_sigma_um = 0.0;
  ApproximationOptions approximations;
  std::uint64_t seed = 1;
};
// Observations (frame-major, points in order), noise, approximations, truth.
SimulatedBlock Assemble(const AssembleInput& in);

}  // namespace bundle_internal

}  // namespace platemeter::sim
