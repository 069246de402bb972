#pragma once
// Several cameras exposed together on the stars, adjusted jointly (seed 004's
// SMAC, "Simultaneous Multi-frame Analytical Calibration ... arrays of up to
// five cameras"): each camera keeps its own parameters (stellar_plate.h; the
// options' lens model, the same for every camera),
// each plate its own deformation and star corrections, and the cameras of one
// exposure share ONE exterior orientation: camera k's orientation is camera
// 0's times a fixed relative orientation (the interlock)
//   camera_k_from_enu = M_k camera_0_from_enu,   M_k = R3(kappa) R2(phi) R1(omega)
// (seed 004 Table A.6: "a transformation from the Terrain Camera to the
// Stellar Camera", the rotations applied to the stellar camera's axes; the
// convention of rotations.h). M_k is constant over the exposures; the
// exposures' orientations (1 to 3 sets each, split by camera 0's time) are free.
// The angles are the adjustment's parameters, so their covariance is the
// engine's (scaled by sigma0^2): Table A.6's "Covariance Matrix" and
// standard deviations (interlock.h gives the matrix elements' covariance).
// docs/stellar.md, "Several cameras".
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/interlock.h"
#include "platemeter/calib/stellar_plate.h"

namespace platemeter {

// One exposure: the plates the cameras took together. plates[k] is camera
// k's plate; camera 0 (the reference of every interlock) must be present,
// the others may be missing (an empty plate id).
struct InterlockExposure {
  std::string id;                     // e.g. "2", "6 PRE"
  std::vector<StellarPlate> plates;   // one per camera, in the cameras' order
};

struct InterlockCameraResult {
  std::string name;
  StellarCamera camera;               // plate frame, the options' lens model
  StellarCamera camera_sigma;         // scaled; 0 where fixed
  int plates = 0, stars = 0, images = 0, rejected_images = 0;
  double rms_residual_um = 0.0;       // unweighted, per coordinate, of the used images (seed 004's "mean error")
};

struct CameraInterlockResult {
  std::string from, to;               // camera 0 and camera k
  Eigen::Matrix3d matrix = Eigen::Matrix3d::Identity();  // camera_k_from_camera_0
  Matrix9d element_covariance = Matrix9d::Zero();        // of m11 .. m33, scaled
  InterlockAngles angles;             // omega, phi, kappa with covariance and sigmas (scaled)
};

struct StellarInterlockResult {
  std::vector<InterlockCameraResult> cameras;
  std::vector<CameraInterlockResult> interlocks;  // camera 0 -> camera k, k = 1 ..
  AdjustmentResult adjustment;        // the joint adjustment (sigma0, dof, chi-square, rank report)
  int exposures = 0;
};

// `names[k]`, `initial[k]`: camera k's name and starting values. Plates are
// prepared as in RunStellarPlate (same catalog, options for every camera;
// options.camera_states apply to every camera). Throws platemeter::Error for
// fewer than two cameras, an exposure without camera 0's plate or with a
// plate count different from the cameras', a camera that no exposure shows,
// and whatever RunStellarPlate refuses.
StellarInterlockResult RunStellarInterlock(const std::vector<std::string>& names,
                                           const std::vector<StellarCamera>& initial,
                                           const std::vector<InterlockExposure>& exposures,
                                           const StellarCatalog& catalog, const StellarOptions& options,
                                           const AdjustmentProgress& progress = {});

}  // namespace platemeter
