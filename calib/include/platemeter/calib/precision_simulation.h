#pragma once
// The precision simulation of seed 000 section 4 (Tables 9 and 10): the
// a-priori standard deviations of the inner cone that a PLANNED photographic
// geometry would give, before any image exists (docs/precision-simulation.md).
//
// A plan (TOML, ReadPrecisionPlan) describes the geometry as seed 000 does:
// lunar orbits (altitude, number, spacing of the ground tracks), exposures per
// orbit, the convergence angle between an orbit's end frames, the kappa
// increments between exposures, the camera (focal length, format, the true lens
// the block is projected with), the error budget (image sigma), the passpoints
// (number, which frames must see them, relief), the adjustment (which inner
// cone parameters are free, the datum, optional a-priori station constraints
// after Gyer) and what to report (the radial balance, the profile radii, the
// published sigmas to print beside the prediction).
//
// The block itself is simulated NOISE-FREE by the lunar block simulator
// (samples/bundle_block.h; calib cannot include samples, so the caller builds
// the PrecisionBlock: cli/cmd_calibrate_simulate.h SimulatePrecisionBlock),
// every observation carrying the plan's image sigma as its weight. Then
// EvaluatePrecision runs the self-calibrating bundle adjustment
// (bundle_adjustment.h) on it -- from the true values, so it stops at once --
// and reports the UNSCALED covariance (sigma0 = 1: the a-priori sigmas the
// error budget implies; a noise-free block has no residuals to scale by):
//   - sigma of xp, yp and c (and of every free camera parameter),
//   - the calibrated focal length c' and the radial function delta_r' (eq. 14)
//     balanced as the plan says, and the decentering profile P(r) (eq. 15), with
//     propagated sigmas (distortion_profile.h), at the corner of the format and
//     at the plan's radii,
//   - sigma0's degrees of freedom, the rank report (datum defect, null and weak
//     directions in parameter words), the inner cone's high correlations.
//
// What the sigmas of seed 000's tables are (docs/precision-simulation.md):
// Table 9's c' and delta_r' are seed 000's balanced quantities as its program
// printed them (Table 2's sigmas follow sigma(k0') and sigma(k1') taken as
// uncorrelated); for a lens simulated without distortion k0' = 0, so c' = c and
// sigma(delta_r'(r)) = r^3 sigma(k1): the balance "as-given" (the default). A
// rigorous balance (zero at a radius, equal lobes) is available and propagates
// every correlation; it is a different quantity and says so in the report.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/adjustment.h"
#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/distortion_profile.h"

namespace platemeter {

// How the rolls about the optical axis step through the exposures.
enum class KappaSequence {
  kContinuous,  // exposure k of the whole sequence (orbit by orbit) has kappa_start + k * increment (seed 000 Fig. 3)
  kPerOrbit,    // every orbit starts again: exposure j of any orbit has kappa_start + j * increment
};
const char* KappaSequenceName(KappaSequence sequence);  // "continuous", "per-orbit"
bool ParseKappaSequence(const std::string& name, KappaSequence* sequence);

// How the datum of the planned adjustment is fixed.
enum class PrecisionDatum {
  kAuto,              // a-priori station positions if the plan has any, else inner constraints
  kInnerConstraints,  // free network (pure self-calibration; seed 000 section 4)
  kStations,          // the a-priori station constraints alone (requires [[station_constraints]])
};
const char* PrecisionDatumName(PrecisionDatum datum);  // "auto", "inner-constraints", "stations"
bool ParsePrecisionDatum(const std::string& name, PrecisionDatum* datum);

// A-priori observations of exposure stations (seed 000 section 3.3, Gyer's
// in-track / cross-track / radial covariance; StationCovarianceFromTrack).
struct StationConstraint {
  std::vector<int> orbits;           // 1-based orbit numbers in the plan's order; empty = every orbit
  double sigma_in_track_m = 0.0;     // m; > 0
  double sigma_cross_track_m = 0.0;  // m; > 0
  double sigma_radial_m = 0.0;       // m; > 0
  std::optional<double> sigma_angle_deg;  // deg; phi, omega, kappa each; none = attitudes free
};

// The published sigmas to print beside the prediction (optional; um).
struct PrecisionReference {
  std::string source;  // e.g. "seed 000 Table 9, 80 mm"
  std::optional<double> xp_um, yp_um, c_prime_um, radial_corner_um, decentering_corner_um;
};

struct PrecisionPlan {
  std::string title;   // one line for the report
  std::string source;  // the file it was read from ("" if made in memory)

  // [camera]
  double focal_length_mm = 80.0;   // mm; the principal distance c
  double format_width_mm = 55.0;   // mm; imaged format, centred on the plate origin
  double format_height_mm = 55.0;  // mm
  // The true lens the block is projected with (seed 000 eq. 1, correction
  // form). The covariance hardly depends on it; the default is a lens without
  // distortion and the principal point at the format's centre.
  double xp_mm = 0.0, yp_mm = 0.0;                               // mm
  double k1_per_mm2 = 0.0, k2_per_mm4 = 0.0, k3_per_mm6 = 0.0;   // 1/mm^2, 1/mm^4, 1/mm^6
  double p1_per_mm = 0.0, p2_per_mm = 0.0;                       // 1/mm

  // [orbits]
  double body_radius_km = 1737.4;     // km; the Moon
  double altitude_km = 108.5;         // km; above the sphere (seed 000 section 4)
  int orbits = 3;                     // consecutive orbits (seed 000: three)
  // km; across-track distance between the ground tracks of consecutive orbits
  // (the Moon turns 1.085 deg under a 108.5 km orbit in one period: 32.9 km at
  // the equator, times sin(inclination); 8.5 km for a low inclination of 15 deg).
  double track_spacing_km = 8.5;
  std::vector<int> revolutions;       // optional revolution numbers (e.g. 27, 28, 30); empty = 1..orbits
  int exposures_per_orbit = 3;        // seed 000: three
  double convergence_deg = 80.0;      // deg; between the optical axes of an orbit's end frames
  double kappa_start_deg = 0.0;       // deg; roll of the first exposure
  double kappa_increment_deg = 90.0;  // deg; roll added from one exposure to the next (Fig. 3: 90)
  KappaSequence kappa_sequence = KappaSequence::kContinuous;

  // [passpoints]
  int passpoints = 215;               // seed 000: 215
  int min_frames_per_point = 0;       // frames that must see a passpoint; 0 = all (the common area)
  double relief_m = 300.0;            // m; heights uniform in +-relief/2
  double format_margin_mm = 0.5;      // mm; passpoints this far inside the format edges

  // [errors]
  double image_sigma_um = 15.0;       // um; per image coordinate (seed 000: 15 Hasselblad, 5 terrain camera)

  // [adjustment]
  // Free camera parameters (kBundleCameraParamNames order); the others are
  // held at their true values. Default: c, xp, yp, k1, p1, p2 (seed 000
  // section 3.2's set plus the principal point; section 4 frees xp, yp).
  std::array<bool, kBundleCameraParams> free = {true, true, true, true, false, false, true, true, false, false};
  PrecisionDatum datum = PrecisionDatum::kAuto;
  std::vector<StationConstraint> station_constraints;

  // [report]
  RadialBalance balance = RadialBalance::kAsGiven;  // of c' and delta_r'
  double balance_radius_mm = 30.0;   // mm; kZeroAtRadius (seed 000: 30 mm)
  std::vector<double> radii_mm;      // mm; profile rows; empty = 0 to the corner (DefaultProfileRadii_mm)
  double correlation_threshold = 0.9;  // |rho| of the inner cone named in the report
  PrecisionReference reference;

  // [simulation]
  std::uint64_t seed = 1;             // passpoint placement and heights

  // Corner of the format (its half diagonal), mm.
  double CornerRadius_mm() const;
  bool Check(std::string* why) const;
};

// The plan file (docs/precision-simulation.md). Every key is checked against
// its table's list: a misspelt key is an error with its line. Throws
// platemeter::Error(source or path, "line N: ...").
PrecisionPlan ParsePrecisionPlan(const std::string& toml_text, const std::string& source);
PrecisionPlan ReadPrecisionPlan(const std::string& path);

// The simulated block the caller hands over (cli/cmd_calibrate_simulate.h
// builds it with samples/bundle_block.h).
struct PrecisionBlock {
  // Noise-free observations weighted by the plan's image sigma; one camera
  // whose values are the true lens; frames and ground points at their true
  // values. Camera states are set by EvaluatePrecision from the plan.
  BundleInput input;
  std::vector<int> frame_orbit;                  // per frame, 0-based orbit index (station constraints)
  std::vector<Eigen::Vector3d> frame_velocity;   // per frame, along the track (Gyer's covariance)
  std::vector<double> frame_roll_deg;            // per frame, the roll about the optical axis
  std::string summary;                           // one line: what the geometry is
};

// A camera parameter's a-priori sigma.
struct PrecisionParameter {
  std::string name;             // kBundleCameraParamNames
  double value = 0.0;           // the true value
  EstimateStatus status = EstimateStatus::kFixed;
  std::optional<double> sigma;  // unscaled (sigma0 = 1), the parameter's unit; none if fixed / not estimable
};

struct PrecisionSimulationResult {
  PrecisionPlan plan;
  std::string geometry;      // the block's summary
  std::string datum_words;   // e.g. "inner constraints (free network): ..."
  int frames = 0, points = 0;
  int observations = 0;      // image points (each an x and a y row)
  std::vector<double> frame_roll_deg;

  std::vector<PrecisionParameter> camera;  // kBundleCameraParamNames order
  // The headline numbers, um (none when the parameter is fixed or not estimable).
  std::optional<double> xp_um, yp_um, c_um;
  double corner_radius_mm = 0.0;
  ValueWithSigma calibrated_focal_length_mm;  // c' (balance per plan.balance)
  double radial_corner_sigma_um = 0.0;        // sigma of delta_r' at the corner
  double decentering_corner_sigma_um = 0.0;   // sigma of P(r) at the corner
  DistortionProfile profile;                  // rows at plan.radii_mm (or the defaults), the corner last

  // The adjustment's statistics.
  double dof = 0.0;            // sigma0's degrees of freedom: observation rows + prior rows - rank
  long observation_rows = 0;
  long prior_rows = 0;
  long unknowns = 0;
  RankReport rank;
  std::vector<std::string> correlation_names;  // the free inner cone parameters
  Eigen::MatrixXd correlation;                 // their correlation matrix
  std::vector<std::tuple<std::string, std::string, double>> high_correlations;  // |rho| >= threshold
  double seconds = 0.0;
  std::string summary;  // one paragraph
};

// Runs the adjustment on the block with the plan's parameter states, datum and
// station constraints, and collects the a-priori sigmas. Throws
// platemeter::Error("precision simulation", why) for a plan that fails Check,
// a block that does not match it, or an adjustment that cannot run.
PrecisionSimulationResult EvaluatePrecision(const PrecisionPlan& plan, const PrecisionBlock& block);

// The report: the headline sigmas (beside the plan's reference values, with
// their ratios, when given), the profile table, the statistics and the rank
// report. Text for people, JSON for programs.
std::string FormatPrecisionText(const PrecisionSimulationResult& result);
std::string FormatPrecisionJson(const PrecisionSimulationResult& result);
// precision.json and precision.txt in `dir` (created if needed), atomically;
// returns the paths written.
std::vector<std::string> WritePrecisionOutputs(const std::string& dir, const PrecisionSimulationResult& result);

}  // namespace platemeter
