#pragma once
// The adjustment engine every calibration shares (DESIGN.md "The adjustments"):
// named parameter blocks, observation equations with their covariance, prior
// observations on any parameter (seed 000 eqs. 3-5: sigma 0 = fixed, none =
// free), solved by Ceres; then, from the normal equations reduced by
// eliminating the point blocks (seed 000 section 2.2, a Schur complement),
// what every adjustment reports in one shape (AdjustmentResult): values and
// sigmas, sigma0 with its degrees of freedom, the global chi-square test, the
// covariance of any block (scaled by sigma0^2 and unscaled), correlations, the
// rank report with the null space named in parameter words, and residuals.
//
// Conventions. Observation equations return RAW residuals (model minus
// observation, or the seed's corrected-minus-projected form) in the
// observation's unit; the engine whitens them with the observation's
// covariance. Weights follow the a-priori sigmas: sigma0 a posteriori near 1
// means the sigmas were right.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/bundle_input.h"  // ParameterState

namespace ceres {
class CostFunction;
}

namespace platemeter {

// Point blocks (1 to 3 parameters: a ground point, a star's direction
// correction) are eliminated from the normal equations (seed 000's reduced
// normal equations); the others are carried in the reduced system.
enum class BlockKind { kGlobal, kStation, kPoint };

struct AdjustmentOptions {
  double robust_loss_scale = 0.0;     // sigma units; > 0: a first pass with a Cauchy loss
  // After the robust pass an observation is rejected when a component of its
  // residual / (a-priori sigma x the pass's robust sigma0) exceeds this; 0 =
  // the level a good observation's residual exceeds with probability
  // false_rejection_rate over all the observations (Bonferroni: about 4.7
  // sigma for 4000 components at 1 %).
  double rejection_threshold = 0.0;   // sigma units
  double false_rejection_rate = 0.01; // -; chance that any good observation is rejected (threshold 0)
  int max_iterations = 100;           // per pass: Gauss-Newton steps, or trust-region iterations where Ceres takes over
  // Relative change of v'Pv that ends a pass (the weighted pass: the decrease
  // its quadratic model still promises): at v'Pv = 4e5 (a block of 400 000
  // observations) 1e-10 of it is a step under 0.01 sigma in any direction.
  double function_tolerance = 1e-10;
  // Step that ends a trust-region pass, relative to the norm of all parameters (Ceres'
  // parameter_tolerance): with a principal distance of 80 mm among them, 1e-12
  // stops at steps of 8e-11 mm. Lower both tolerances (1e-16) to drive a
  // solution to its last digits, as a reference solution must.
  double parameter_tolerance = 1e-12;
  // Reference solutions: once v'Pv stops telling better from worse (a step
  // promising under 1e-6 of it), take 8 more full Gauss-Newton steps instead
  // of stopping at function_tolerance (the trust region, where it runs, keeps
  // taking non-monotonic steps until max_iterations); the solution reaches its
  // stationary point to ~1e-11 sigma.
  bool polish = false;
  double correlation_threshold = 0.9; // |rho| named in the report
  double significance_level = 0.05;   // alpha of the chi-square and t/F tests
  double rank_tolerance = 1e-12;      // relative eigenvalue of the scaled reduced normal matrix counted as zero
  // Relative eigenvalue below which a direction is named as poorly determined:
  // a scaled condition number above 1e6, where parameters compensate each
  // other almost perfectly (seed 000 section 2.3's x_p with phi).
  double weak_tolerance = 1e-6;
  int num_threads = 0;                // 0 = every core
  bool Check(std::string* why) const;
};

enum class EstimateStatus {
  kFree,          // adjusted, no prior
  kWeighted,      // adjusted with a prior observation
  kFixed,         // held at its value (sigma 0)
  kNotEstimable,  // in the null space of the normal equations: value arbitrary, no sigma
};
const char* EstimateStatusName(EstimateStatus status);  // "free", "weighted", "fixed", "not-estimable"

struct ParameterEstimate {
  std::string block;  // block label, e.g. "camera hasselblad", "frame 9515"
  std::string group;  // block group, e.g. "camera", "frame", "point"
  std::string name;   // parameter name with unit, e.g. "c_mm"
  double value = 0.0;
  double initial = 0.0;
  EstimateStatus status = EstimateStatus::kFree;
  std::optional<double> sigma;           // a posteriori, scaled by sigma0 (reported); none if fixed / not estimable
  std::optional<double> sigma_unscaled;  // from the a-priori weights alone (sigma0 = 1)
  std::optional<double> prior_sigma;     // the prior observation's sigma (kWeighted)
};

// One direction of the (near-)null space of the reduced normal equations.
struct NullDirection {
  double relative_eigenvalue = 0.0;  // eigenvalue / largest, of the diagonally scaled matrix
  bool exact = false;                // below rank_tolerance (a rank defect), else only poorly determined
  bool datum = false;                // lies in the datum's gauge space (inner constraints), not a defect
  std::string words;                 // e.g. "xp_mm (48 %) with the frames' X_m (41 %)"
  std::vector<std::pair<std::string, double>> shares;  // (parameter or group, share of the direction), largest first
};

struct RankReport {
  int num_parameters = 0;     // adjusted parameters in the reduced system (fixed ones excluded)
  int structural_rank = 0;    // parameters that any observation or prior touches
  int numerical_rank = 0;     // eigenvalues above rank_tolerance
  int datum_defect = 0;       // null directions the datum definition accounts for
  double condition_number = 0.0;  // largest / smallest non-zero eigenvalue (scaled)
  std::vector<std::string> untouched;  // parameters no equation touches
  std::vector<NullDirection> directions;  // exact and weak, weakest first
  int points_undetermined = 0;  // eliminated points whose own 3x3 block is singular
};

struct ChiSquareTest {
  double statistic = 0.0;  // v^T P v (sum of squared whitened residuals)
  double dof = 0.0;
  double lower = 0.0;      // chi2 quantile alpha/2
  double upper = 0.0;      // chi2 quantile 1 - alpha/2
  double p_value = 1.0;    // two-sided
  bool rejected = false;   // statistic outside [lower, upper]
};

// A parameter (or a group) tested against zero.
struct SignificanceTest {
  std::string what;       // e.g. "k1_per_mm2", "p1_per_mm, p2_per_mm"
  double statistic = 0.0; // t (one parameter) or F (a group)
  double critical = 0.0;  // two-sided t or F quantile at alpha
  double p_value = 1.0;
  bool significant = false;
};

enum class ObservationStatus { kUsed, kRejected };

struct ObservationResidual {
  int observation = -1;      // index in order of AddObservation
  std::string label;         // e.g. "frame 9515 point P17"
  std::string group;         // e.g. the frame id (per-group RMS)
  std::string item;          // e.g. the point id
  std::string origin;        // file:line
  ObservationStatus status = ObservationStatus::kUsed;
  std::vector<double> residual;    // raw, observation units
  std::vector<double> normalized;  // residual / a-priori sigma (per component, whitened)
  std::string reason;              // why rejected
};

struct PriorResidual {
  std::string label;
  std::vector<double> residual;  // estimate minus prior value, parameter units
  std::vector<double> normalized;
};

struct AdjustmentResult {
  bool converged = false;
  int iterations = 0;
  std::string summary;  // one paragraph a user can act on
  double sigma0 = 0.0;  // a posteriori standard deviation of unit weight
  double dof = 0.0;     // degrees of freedom: observation rows + prior rows - rank
  long observation_rows = 0;
  long prior_rows = 0;
  long unknowns = 0;    // adjusted parameters (points included)
  ChiSquareTest chi_square;
  std::vector<ParameterEstimate> parameters;  // every non-point parameter, block order
  // Unscaled covariance (cofactor matrix, sigma0 = 1) of the adjusted
  // non-point parameters: row i belongs to parameters[covariance_index[i]].
  Eigen::MatrixXd cofactor;
  std::vector<int> covariance_index;
  std::vector<int> covariance_row;  // parameters index -> row of `cofactor`, -1 if fixed or not estimable
  RankReport rank;
  std::vector<ObservationResidual> residuals;
  std::vector<PriorResidual> prior_residuals;
  int rejected = 0;  // observations rejected by the robust pass
  double solve_seconds = 0.0;
  double covariance_seconds = 0.0;
  // Point blocks: values and (scaled) sigmas.
  struct PointEstimate {
    std::string label;
    Eigen::Vector3d value = Eigen::Vector3d::Zero();  // a block of fewer than 3 parameters: the rest 0
    std::optional<Eigen::Vector3d> sigma;
    int rays = 0;
  };
  std::vector<PointEstimate> points;

  // The index in `parameters` of block/name, -1 if absent.
  int Find(const std::string& block, const std::string& name) const;
  // Scaled (sigma0^2) or unscaled covariance of the given parameters (indices
  // into `parameters`); rows of fixed or non-estimable parameters are zero.
  Eigen::MatrixXd Covariance(const std::vector<int>& parameters, bool scaled = true) const;
  // Correlation matrix of the given parameters (0 where a sigma is missing).
  Eigen::MatrixXd Correlation(const std::vector<int>& parameters) const;
  // Pairs among `parameters` with |rho| >= threshold, largest first.
  std::vector<std::tuple<int, int, double>> HighCorrelations(const std::vector<int>& parameters,
                                                             double threshold) const;
  // t test of one parameter against 0 (scaled sigma, Student t with dof), or
  // the F test of a group (value^T C^-1 value / k against F(k, dof)).
  SignificanceTest Test(const std::vector<int>& parameters, double alpha) const;
};

// Progress of a long adjustment: a stage name and a fraction 0..1.
using AdjustmentProgress = std::function<void(const std::string& stage, double fraction)>;

class AdjustmentProblem {
 public:
  AdjustmentProblem();
  ~AdjustmentProblem();
  AdjustmentProblem(const AdjustmentProblem&) = delete;
  AdjustmentProblem& operator=(const AdjustmentProblem&) = delete;

  // A block of parameters with names (units in the names) and initial values;
  // every parameter starts free. Returns the block's id.
  int AddBlock(const std::string& label, const std::string& group, BlockKind kind,
               const std::vector<std::string>& names, const std::vector<double>& values);
  // State of one parameter: fixed, free, or weighted (a prior observation of
  // its initial value with the given sigma).
  void SetState(int block, int index, const ParameterState& state);
  // A prior observation of several parameters of one block with a full
  // covariance (e.g. a station position from Gyer's in-track / cross-track /
  // radial sigmas). Parameters so observed must be free.
  void AddPrior(int block, const std::vector<int>& indices, const Eigen::VectorXd& values,
                const Eigen::MatrixXd& covariance, const std::string& label);
  // An observation equation: `cost` returns raw residuals (dimension d) of the
  // given blocks' parameters; `covariance` (d x d) is the observation's. The
  // engine takes ownership of `cost`. Returns the observation's index.
  int AddObservation(ceres::CostFunction* cost, const std::vector<int>& blocks,
                     const Eigen::MatrixXd& covariance, const std::string& group,
                     const std::string& item, const std::string& origin);
  // Room for `count` more observations, so that a large problem's equations
  // are not moved again and again as they are added (400 000 in a large block).
  void ReserveObservations(size_t count);
  // A basis of the network's gauge freedom in the non-point parameters
  // (columns, each named, e.g. "the network's scale"; rows ordered as the
  // blocks' parameters, fixed ones included). With `is_datum` the datum leaves
  // these directions free on purpose (free network, inner constraints): the
  // covariance is given with minimum trace over the rows flagged in
  // `trace_rows`. Without it they only name a datum defect in words.
  void SetGauge(const Eigen::MatrixXd& basis, const std::vector<std::string>& names,
                const std::vector<bool>& trace_rows, bool is_datum);

  int NumBlocks() const;
  int BlockSize(int block) const;
  const std::vector<double>& Values(int block) const;
  double* MutableValues(int block);
  // Offset of block's first parameter among all non-point parameters (for SetGauge rows), -1 for points.
  int GlobalOffset(int block) const;
  int NumGlobalParameters() const;

  AdjustmentResult Solve(const AdjustmentOptions& options, const AdjustmentProgress& progress = {});

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace platemeter
