#pragma once
// Stellar calibration of one plate (seed 001): identified star images, their
// apparent places at each image's mid-time (apparent_place.h), and the
// camera (by default seed 001's 11-parameter model; seed 004's and seed 000's
// lens models selectable, stellar_lens.h) with 1 to 3 exterior-orientation
// sets and the plate's deformation, adjusted by the engine (adjustment.h).
// docs/stellar.md.
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
// (orbigon-11, a kDistortion lens; for a kCorrection lens, seeds 000 and 004,
// the measured image is corrected instead: (x* - xp) + [lens]x(x* - xp, y* - yp)
// = Cx m/q - (Cy n/q + yp) epsilon, likewise y, stellar_equation.h)
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
#include "platemeter/calib/stellar_lens.h"

namespace platemeter {

// The camera's values: c_mm, xp_mm, yp_mm, then the parameters of the lens
// model (StellarOptions::lens_model, stellar_lens.h), 3 + n values.
using StellarCamera = std::vector<double>;

// The orbigon-11 camera (the default): seed 001's 11 parameters in this order
// (plate frame; xs, ys relative to the principal point, as SlamaDistortion
// takes them).
constexpr int kStellarCameraParams = 11;
inline constexpr std::array<const char*, kStellarCameraParams> kStellarCameraParamNames = {
    "c_mm", "xp_mm", "yp_mm", "xs_mm", "ys_mm", "K1_per_m2", "K2_per_m4", "K3_per_m6", "K4_per_m", "K5_per_m3",
    "Phi_T_rad"};

// A camera model whose lens is one of the stellar lens models as the camera
// values in the plate frame (its own model's parameters). `printed_left_handed`
// says an orbigon-11 model holds seed 001's printed (y-down) values, as the
// builtin Orbigon definition does. Throws platemeter::Error for another lens
// model, or a printed frame for a lens other than orbigon-11.
StellarCamera StellarCameraFromModel(const CameraModel& model, bool printed_left_handed);
// orbigon-11 values in seed 001's printed frame (yp, ys, Phi_T negated).
StellarCamera StellarCameraToPrinted(const StellarCamera& plate_frame);
// The decentering's sign freedom (StellarDecenteringSignOf): results are given
// in the form with the first amplitude >= 0 (orbigon-11: K4 >= 0; smac: J1 >=
// 0) and the angle in [-pi, pi); `matrix` (a covariance or normal matrix of
// the camera values, or empty) is transformed alike (the amplitudes' rows and
// columns change sign). Brown: no change.
void CanonicalDecentering(StellarCamera* camera, Eigen::MatrixXd* matrix,
                          DistortionModelId lens = DistortionModelId::kSlama);
// A distortion-free camera of principal distance c (principal point 0, lens 0).
StellarCamera NominalStellarCamera(double principal_distance_mm, DistortionModelId lens = DistortionModelId::kSlama);

// One measured star image.
struct StarImageObservation {
  std::string image_id;        // e.g. "T2-D17"
  std::string star_id;         // catalog key (StellarCatalog); an id not in the catalog is an unknown star
  calib::UtcInstant mid_time;         // middle of the image's exposure
  double x_mm = 0.0, y_mm = 0.0;             // plate frame
  double sigma_x_mm = 0.0, sigma_y_mm = 0.0; // > 0
  std::string origin;          // file:line, for messages
  std::string trail;           // the trail it belongs to (e.g. "T2"; empty: a single star image); for the plots
  long dot = -1;               // its index within the trail (-1: none)
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
  // The camera's lens model (stellar_lens.h): orbigon-11, smac-radial-decentering or brown-conrady.
  DistortionModelId lens_model = DistortionModelId::kSlama;
  // Camera parameter states by name (StellarCameraParamNames(lens_model)); default free.
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
  StellarCamera camera;              // plate frame, the options' lens model
  StellarCamera camera_sigma;        // scaled; 0 where fixed or not estimable
  std::vector<int> camera_row;       // row in adjustment.cofactor, -1 fixed/not estimable
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
  Eigen::MatrixXd camera_information;  // n x n, n camera values (zero rows for fixed parameters)
};

// Adjusts one plate. `initial` is the camera to start from (the lens's nominal
// values), StellarCameraParamCount(options.lens_model) values; `approx_camera_from_enu`, if given, the pointing to start from
// (else computed from the identified stars). Throws platemeter::Error with a
// one-line reason for unusable input (no images, fewer than 8 catalog stars,
// a non-positive sigma, an unreadable time).
StellarPlateResult RunStellarPlate(const StellarPlate& plate, const StellarCatalog& catalog,
                                   const StellarCamera& initial, const StellarOptions& options,
                                   const std::optional<Eigen::Matrix3d>& approx_camera_from_enu = std::nullopt,
                                   const AdjustmentProgress& progress = {});

}  // namespace platemeter
