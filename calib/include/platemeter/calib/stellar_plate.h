#pragma once
// Stellar calibration of one plate (seed 001): identified star images, their
// apparent places at each image's mid-time (apparent_place.h), and the
// 11-parameter camera model with 1 to 3 exterior-orientation sets and the
// plate's deformation, adjusted by the engine (adjustment.h). docs/stellar.md.
//
// Frame. Everything here is in platemeter's plate frame (x right, y up,
// DESIGN.md). Seed 001 prints its values "in a left-handed coordinate system as
// viewed on the focal plane" (y down): yp, ys, epsilon and Phi_T change sign
// between the two (StellarCameraFromModel / StellarCameraToPrinted).
//
// Model, per image (seed 001's equation, SlamaImageEquation):
//   (m, n, q) = M_j (X, Y, Z)     X, Y, Z: the star's apparent direction in the
//                                 site's local frame (x east, y north, z up)
//   x* = Cx m/q + xp + [lens]x - (Cy n/q + yp) epsilon,  y* = Cy n/q + yp + [lens]y
// with M_j the orientation set of the image's time, Cx = C (1 + s),
// Cy = C (1 - s) (s: the plate's differential scale, seed 001's "differential
// scalars"; C their mean), epsilon the non-orthogonality of the axes.
// Each star's direction carries a two-parameter correction (east-of-catalog
// and north-of-catalog arc, radians) observed a priori with the catalog's
// position sigma (seed 001: 0.3" FK4, 0.4" others); a star with no catalog
// position has the same two parameters free (seed 001's "unknown stars").
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/adjustment.h"
#include "platemeter/calib/apparent_place.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/star_catalog.h"

namespace platemeter {

// The 11 camera parameters of seed 001, in this order (plate frame; xs, ys
// relative to the principal point, as SlamaDistortion takes them).
constexpr int kStellarCameraParams = 11;
inline constexpr std::array<const char*, kStellarCameraParams> kStellarCameraParamNames = {
    "c_mm", "xp_mm", "yp_mm", "xs_mm", "ys_mm", "K1_per_m2", "K2_per_m4", "K3_per_m6", "K4_per_m", "K5_per_m3",
    "Phi_T_rad"};
using StellarCamera = std::array<double, kStellarCameraParams>;

// A camera model with an "orbigon-11" lens (camera_model.h) as the 11 values in
// the plate frame; `printed_left_handed` says the model holds seed 001's printed
// (y-down) values, as the builtin Orbigon definition does. Throws
// platemeter::Error for another lens model.
StellarCamera StellarCameraFromModel(const CameraModel& model, bool printed_left_handed);
// The same values in seed 001's printed frame (yp, ys, Phi_T negated).
StellarCamera StellarCameraToPrinted(const StellarCamera& plate_frame);
// Seed 001's decentering term (K4 + K5 d^2)(... cos Phi_T ... sin Phi_T) is the
// same for (K4, K5, Phi_T) and (-K4, -K5, Phi_T + pi): the adjustment may land
// on either. Results are given in the form with K4 >= 0 and Phi_T in
// [-pi, pi); `matrix` (a covariance or normal matrix of the 11, or empty) is
// transformed alike (the K4 and K5 rows and columns change sign).
void CanonicalDecentering(StellarCamera* camera, Eigen::MatrixXd* matrix);
// A distortion-free camera of principal distance c (xs = ys = 0, K = 0).
StellarCamera NominalStellarCamera(double principal_distance_mm);

// One measured star image.
struct StarImageObservation {
  std::string image_id;        // e.g. "T2-D17"
  std::string star_id;         // catalog key (StellarCatalog); an id not in the catalog is an unknown star
  calib::UtcInstant mid_time;         // middle of the image's exposure
  double x_mm = 0.0, y_mm = 0.0;             // plate frame
  double sigma_x_mm = 0.0, sigma_y_mm = 0.0; // > 0
  std::string origin;          // file:line, for messages
};

struct CatalogEntry {
  calib::CatalogStar star;
  double sigma_arcsec = 0.4;   // position sigma per coordinate (seed 001: 0.3" FK4, 0.4" others)
};
using StellarCatalog = std::map<std::string, CatalogEntry>;

struct StellarPlate {
  std::string id;                    // e.g. "1320"
  std::string group;                 // e.g. the aperture "f/3.5" (combinations per group)
  calib::ApparentPlaceOptions place;        // site, atmosphere, refraction
  std::vector<StarImageObservation> images;
};

struct StellarOptions {
  int orientation_sets = 3;          // 1..3 exterior orientations, the plate's time span split evenly
  bool deformation = true;           // the plate's s and epsilon (seed 001: always)
  // Camera parameter states by name (kStellarCameraParamNames); default free.
  std::map<std::string, ParameterState> camera_states;
  AdjustmentOptions adjustment;
  bool Check(std::string* why) const;
};

// An orientation set's result: the camera axis and roll (deg) with sigmas (arcsec).
struct OrientationSetResult {
  int index = 0;                     // 1..3
  double start_s = 0.0, end_s = 0.0; // its images' time span, s after the plate's first image
  int images = 0;
  Eigen::Matrix3d camera_from_enu = Eigen::Matrix3d::Identity();
  double axis_azimuth_deg = 0.0, axis_altitude_deg = 0.0, roll_deg = 0.0;
  std::array<double, 3> sigma_arcsec{};  // about the camera's x, y, z axes
};

struct StellarPlateResult {
  std::string plate_id;
  std::string group;
  AdjustmentResult adjustment;       // the engine's full result (stars' corrections included)
  StellarCamera camera{};            // plate frame
  StellarCamera camera_sigma{};      // scaled; 0 where fixed or not estimable
  std::array<int, kStellarCameraParams> camera_row{};  // row in adjustment.cofactor, -1 fixed/not estimable
  // Deformation: Cx, Cy (mm), epsilon (rad), with scaled sigmas.
  double cx_mm = 0.0, cy_mm = 0.0, epsilon_rad = 0.0;
  double cx_sigma_mm = 0.0, cy_sigma_mm = 0.0, epsilon_sigma_rad = 0.0;
  std::vector<OrientationSetResult> orientation_sets;
  double largest_motion_arcsec = 0.0;  // largest rotation between two orientation sets
  int catalog_stars = 0, unknown_stars = 0, images = 0, rejected_images = 0;
  // Seed 001 Table 2: m_o, the a-posteriori standard error of unit weight
  // (sigma0); m_p, the standard error of an image of unit weight in um
  // (sigma0 times the images' rms a-priori sigma).
  double m_o = 0.0;
  double m_p_um = 0.0;
  double unit_sigma_um = 0.0;          // rms a-priori image sigma per coordinate
  // The plate's reduced normal matrix of the camera parameters (unscaled,
  // sigma0 = 1): the inverse of their cofactor block, Pope's Sigma_Xi^-1.
  Eigen::MatrixXd camera_information;  // 11 x 11 (zero rows for fixed parameters)
};

// Adjusts one plate. `initial` is the camera to start from (the lens's nominal
// values); `approx_camera_from_enu`, if given, the pointing to start from
// (else computed from the identified stars). Throws platemeter::Error with a
// one-line reason for unusable input (no images, fewer than 8 catalog stars,
// a non-positive sigma, an unreadable time).
StellarPlateResult RunStellarPlate(const StellarPlate& plate, const StellarCatalog& catalog,
                                   const StellarCamera& initial, const StellarOptions& options,
                                   const std::optional<Eigen::Matrix3d>& approx_camera_from_enu = std::nullopt,
                                   const AdjustmentProgress& progress = {});

}  // namespace platemeter
