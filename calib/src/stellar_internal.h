#pragma once
// Inside the stellar calibration (stellar_plate.h): each image's apparent
// direction (the observation equation is in stellar_equation.h), and the
// plate's problem as the single plate and the combination both build it.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "platemeter/calib/stellar_plate.h"
#include "stellar_equation.h"

namespace platemeter::stellar_internal {

// Directions of `stars[i]` at `times[i]` (one ERFA set-up per distinct time,
// times in parallel).
std::vector<ImageDirection> ComputeImageDirections(const calib::ApparentPlaceOptions& place,
                                                   const std::vector<const calib::CatalogStar*>& stars,
                                                   const std::vector<calib::UtcInstant>& times);

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
  Eigen::MatrixXd n;  // n x n, n camera values
  Eigen::VectorXd b;  // n
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

// The inverse of the symmetric matrix's block over `rows` (the estimable
// parameters), zero elsewhere: cofactor <-> information of a camera block.
Eigen::MatrixXd InverseOverRows(const Eigen::MatrixXd& matrix, const std::vector<int>& rows);
// Throws platemeter::Error(subject, ...) unless `camera` has the options'
// lens model's count of finite values and a positive principal distance.
void CheckCamera(const StellarCamera& camera, const StellarOptions& options, const std::string& subject);

}  // namespace platemeter::stellar_internal
