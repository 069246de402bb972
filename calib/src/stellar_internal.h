#pragma once
// Inside the stellar calibration (stellar_plate.h): each image's apparent
// direction, the observation equation, and the plate's problem as the single
// plate and the combination both build it.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/calib/stellar_plate.h"

namespace platemeter::stellar_internal {

// A star's apparent direction at one image's mid-time in the site's local
// frame, and its derivatives with respect to the star's catalog place moved
// east and north by an arc (radians): direction(e, n) ~ enu + e d_east + n d_north.
struct ImageDirection {
  Eigen::Vector3d enu = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d d_east = Eigen::Vector3d::Zero();
  Eigen::Vector3d d_north = Eigen::Vector3d::Zero();
};

// Directions of `stars[i]` at `times[i]` (one ERFA set-up per distinct time,
// times in parallel).
std::vector<ImageDirection> ComputeImageDirections(const calib::ApparentPlaceOptions& place,
                                                   const std::vector<const calib::CatalogStar*>& stars,
                                                   const std::vector<calib::UtcInstant>& times);

// Seed 001's image equation, model minus measured, mm. Blocks: camera (11,
// kStellarCameraParamNames), orientation set (omega, phi, kappa rad: a small
// rotation after the set's starting rotation m0, seed 004's sequence),
// deformation (s, epsilon_rad), star correction (east_rad, north_rad).
struct StellarImageEquation {
  double x_mm = 0.0, y_mm = 0.0;
  Eigen::Matrix3d m0 = Eigen::Matrix3d::Identity();  // camera_from_enu the set starts from
  ImageDirection direction;

  template <typename T>
  bool operator()(const T* camera, const T* orientation, const T* deformation, const T* star,
                  T* residual_mm) const {
    T r[9];
    OmegaPhiKappaMatrixT(orientation[0], orientation[1], orientation[2], r);
    return Residual(camera, r, deformation, star, residual_mm);
  }
  // The same with the camera's rotation r (row-major) after m0 given.
  template <typename T>
  bool Residual(const T* camera, const T* r, const T* deformation, const T* star, T* residual_mm) const {
    T d[3];
    for (int i = 0; i < 3; ++i) {
      d[i] = T(direction.enu[i]) + T(direction.d_east[i]) * star[0] + T(direction.d_north[i]) * star[1];
    }
    T v[3];
    for (int i = 0; i < 3; ++i) v[i] = T(m0(i, 0)) * d[0] + T(m0(i, 1)) * d[1] + T(m0(i, 2)) * d[2];
    const T m = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    const T n = r[3] * v[0] + r[4] * v[1] + r[5] * v[2];
    const T q = r[6] * v[0] + r[7] * v[1] + r[8] * v[2];
    if (!(q > T(0.0))) return false;
    const T cx = camera[0] * (T(1.0) + deformation[0]);
    const T cy = camera[0] * (T(1.0) - deformation[0]);
    T x, y;
    SlamaImageEquation(camera + 3, cx, cy, camera[1], camera[2], deformation[1], m, n, q, &x, &y);
    residual_mm[0] = x - T(x_mm);
    residual_mm[1] = y - T(y_mm);
    return true;
  }
  static ceres::CostFunction* Create(const StellarImageEquation& equation) {
    return new ceres::AutoDiffCostFunction<StellarImageEquation, 2, kStellarCameraParams, 3, 2, 2>(
        new StellarImageEquation(equation));
  }
};

// An image of a camera interlocked with the reference camera of its exposure
// (stellar_interlock.h): m0 and the orientation set are the reference plate's,
// and the interlock's rotation M = R3(kappa) R2(phi) R1(omega) follows them.
// Blocks: camera, reference orientation set, interlock (omega, phi, kappa
// rad), deformation, star.
struct InterlockedImageEquation {
  StellarImageEquation image;

  template <typename T>
  bool operator()(const T* camera, const T* orientation, const T* interlock, const T* deformation, const T* star,
                  T* residual_mm) const {
    T a[9], b[9], r[9];
    OmegaPhiKappaMatrixT(interlock[0], interlock[1], interlock[2], a);
    OmegaPhiKappaMatrixT(orientation[0], orientation[1], orientation[2], b);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    }
    return image.Residual(camera, r, deformation, star, residual_mm);
  }
  static ceres::CostFunction* Create(const StellarImageEquation& equation) {
    return new ceres::AutoDiffCostFunction<InterlockedImageEquation, 2, kStellarCameraParams, 3, 3, 2, 2>(
        new InterlockedImageEquation{equation});
  }
};

// One plate prepared for adjustment: every usable image with its direction,
// its orientation set and its star.
struct PreparedImage {
  int source = -1;            // index in StellarPlate::images
  int set = 0;                // orientation set 0..k-1
  double time_s = 0.0;        // mid-time, s after the plate's first image
  int star = -1;              // index in PreparedPlate::stars
  StellarImageEquation equation;
};
struct PreparedStar {
  std::string id;
  bool known = false;         // in the catalog (a prior on its correction)
  double sigma_rad = 0.0;     // catalog position sigma
};
struct PreparedPlate {
  std::vector<PreparedImage> images;
  std::vector<PreparedStar> stars;
  std::vector<Eigen::Matrix3d> set_m0;        // per orientation set
  std::vector<std::pair<double, double>> set_span_s;  // per set: first and last image, s after the first
  calib::UtcInstant first_time;               // the plate's first image
  double span_s = 0.0;                        // from the first to the last image
  double unit_sigma_um = 0.0;
};

// Directions, starting orientation (approx, or from the catalog stars by
// Umeyama) and orientation sets; unknown stars get a place from their first
// image. Throws platemeter::Error for unusable input.
PreparedPlate PreparePlate(const StellarPlate& plate, const StellarCatalog& catalog, const StellarCamera& initial,
                           const StellarOptions& options, const std::optional<Eigen::Matrix3d>& approx);

// The plate's blocks in an engine problem: its orientation sets, deformation
// and stars; `camera` is the camera block (shared in a simultaneous solution).
struct PlateBlocks {
  std::vector<int> sets;
  int deformation = -1;
  std::vector<int> stars;
  int first_observation = 0;  // the engine's index of the plate's first image
};
PlateBlocks AddPlateToProblem(const StellarPlate& plate, const PreparedPlate& prepared, const StellarOptions& options,
                              int camera, AdjustmentProblem* problem);
// A plate of an interlocked camera (stellar_interlock.h): its images take the
// reference plate's orientation-set blocks `reference.sets` and the
// `interlock` block; `prepared` must have been aligned (AlignToReference).
PlateBlocks AddInterlockedPlateToProblem(const StellarPlate& plate, const PreparedPlate& prepared,
                                         const StellarOptions& options, int camera, const PlateBlocks& reference,
                                         int interlock, AdjustmentProblem* problem);
// Gives a plate exposed with `reference` the reference's time split into
// orientation sets and its starting rotations (each image's m0).
void AlignToReference(const PreparedPlate& reference, PreparedPlate* plate);
// The camera block with its states (options.camera_states).
int AddCameraBlock(const std::string& label, const StellarCamera& values, const StellarOptions& options,
                   AdjustmentProblem* problem);

// A plate's own parameters outside any engine problem (the combination's
// Gauss-Newton steps): orientation-set angles, deformation, star corrections,
// and which images take part (those the plate's own robust pass kept).
struct PlateState {
  std::vector<Eigen::Vector3d> sets;
  Eigen::Vector2d deformation = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> stars;
  std::vector<bool> used;  // per PreparedPlate image
};
PlateState InitialPlateState(const PreparedPlate& prepared, const StellarPlateResult& single);

// A plate's normal equations at (camera, state), reduced to the camera: each
// star's 2 x 2 block and then the plate's orientation sets and deformation
// eliminated. n = reduced J'PJ, b = reduced J'Pv (v = model - measured),
// vtpv of the used equations; what the back-substitution needs is kept.
// Rows and columns of fixed parameters are zero (options).
struct PlateLinearization {
  Eigen::MatrixXd n;  // 11 x 11
  Eigen::VectorXd b;  // 11
  double vtpv = 0.0;
  // Back-substitution: the star-reduced system of g = (camera | sets | deformation) ...
  Eigen::MatrixXd n_gg;
  Eigen::VectorXd b_g;
  // ... and each star's block.
  std::vector<Eigen::Matrix2d> n_ss_inverse;
  std::vector<Eigen::MatrixXd> n_sg;
  std::vector<Eigen::Vector2d> b_s;
};
PlateLinearization LinearizePlate(const StellarPlate& plate, const PreparedPlate& prepared, const PlateState& state,
                                  const StellarCamera& camera, const StellarOptions& options);
// The plate's own step given the camera's: state += its Gauss-Newton step.
void StepPlate(const PlateLinearization& lin, const Eigen::VectorXd& camera_step, PlateState* state);

// Whether camera parameter i is held fixed by the options.
bool CameraParameterFixed(const StellarOptions& options, int i);

}  // namespace platemeter::stellar_internal
