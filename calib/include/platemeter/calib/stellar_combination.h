#pragma once
// Several stellar plates combined into one camera (seed 001, "Multiple-plate
// calibration results", Table 3): Pope's generalized weighted mean
//   X = (sum N_i)^-1 sum N_i X_i,   N_i = Sigma_Xi^-1 (the plate's reduced
//   normal matrix of the camera parameters: seed 001's 11, or the n of the
//   options' lens model, stellar_lens.h),
//   m_0^2 = (sum v_i'P v_i + sum (X_i - X)' N_i (X_i - X)) / nu,
//   Sigma_X = m_0^2 (sum N_i)^-1,
// in which each plate's orientation sets, deformation and stars take new values
// without being carried in the combined system.
//
// Seed 001 says the weighted mean "produces results identical to a grand
// simultaneous least squares solution". That holds for a linear model; the
// image equations are not linear, and Pope's one step from the plates' own
// solutions differs from the simultaneous solution by second-order terms
// (reported as one_step_offset_sigma). So the combination goes on from there:
// each plate's normal equations are formed at the current camera and the
// plate's own current parameters and reduced to the camera (matrix and
// right-hand side); their sum gives a Gauss-Newton step of the camera, and
// each plate's orientation sets, deformation and stars follow by
// back-substitution -- no plate is adjusted again. Repeated until the step is
// below 1e-10 sigma, or below 1e-7 sigma and no longer halving (the rounding
// floor of plates with ~10 000 images, ~5e-10 sigma). The result IS the simultaneous solution (same stationary
// point, same reduced normal matrix).
//
// Independence. Like seed 001, each plate carries its own stars' catalog
// corrections: the catalog error of a star seen on two plates is treated as
// independent between them (the simultaneous reference does the same).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/stellar_plate.h"

namespace platemeter {

// A plate tested against the combination: d = X_i - X has the cofactor
// Q_i - Q under the hypothesis that the plate measures the same camera;
// F = d'(Q_i - Q)^+ d / (k m_0^2) against F(k, nu).
struct PlateConsistency {
  std::string plate_id;
  double f_statistic = 0.0;
  int k = 0;                  // rank of Q_i - Q
  double p_value = 1.0;
  bool rejected = false;      // at the options' significance level
};

struct StellarCombination {
  std::string name;                   // e.g. "f/3.5", "combined"
  std::vector<std::string> plate_ids;
  StellarCamera camera;               // plate frame, the options' lens model
  StellarCamera camera_sigma;         // scaled by m_0
  Eigen::MatrixXd cofactor;           // n x n, (sum N_i)^-1 (zero rows for fixed parameters)
  double m_0 = 0.0;                   // standard error of unit weight of the combination
  double dof = 0.0;                   // nu
  double vtpv = 0.0;                  // sum of the plates' v'Pv at the combined camera
  double m_p_um = 0.0;                // pooled standard error of an image of unit weight before combination
  double m_p_after_um = 0.0;          // the same at the combined camera (seed 001's m_p^a)
  double one_step_offset_sigma = 0.0; // largest |Pope's one-step mean - final| / sigma
  int relinearizations = 0;           // Gauss-Newton steps taken
  std::vector<PlateConsistency> consistency;
};

// Combines plates already adjusted one by one (`singles[i]` from
// RunStellarPlate(plates[i], ...) with the same catalog and options).
// Throws platemeter::Error if the plates' summed normal matrix is singular.
StellarCombination CombineStellarPlates(const std::string& name, const std::vector<StellarPlate>& plates,
                                        const std::vector<StellarPlateResult>& singles,
                                        const StellarCatalog& catalog, const StellarOptions& options);

// The grand simultaneous adjustment of the same plates in one problem (one
// camera, each plate's own orientation sets, deformation and stars): the
// reference the combination is tested against, and the engine's full result.
AdjustmentResult SolveStellarPlatesSimultaneously(const std::vector<StellarPlate>& plates,
                                                  const StellarCatalog& catalog, const StellarCamera& initial,
                                                  const StellarOptions& options);

}  // namespace platemeter
