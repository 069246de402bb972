#include "platemeter/detect/cross_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "centre_information.h"
#include "cross_foreign.h"
#include "cross_model.h"

namespace platemeter {
namespace {

using enum internal::CrossParam;
using internal::CentreInformation;
using internal::CrossCost;
using internal::ForeignImageStart;
using internal::kImageL11;
using internal::kImageL21;
using internal::kImageL22;
using internal::kImageX;
using internal::kImageY;
using internal::kNumImageParams;
using enum internal::GapParam;
using internal::MissingPieceStart;
using internal::SceneLayout;
using internal::SceneModel;
using Sample = internal::CrossSample;

// The fitted model: the cross's parameters, then those of its foreign images, then its missing pieces'.
struct Scene {
  std::vector<double> p = std::vector<double>(kNumCrossParams, 0.0);
  std::vector<ForeignImageStart> images;  // where each was started (its bounds)
  std::vector<MissingPieceStart> gaps;    // likewise, the arms' missing pieces
  int image_count() const { return static_cast<int>(images.size()); }
  SceneLayout layout() const {
    SceneLayout l;
    l.images = image_count();
    for (const MissingPieceStart& g : gaps) l.gap_arms.push_back(g.arm);
    return l;
  }
};

// Pixels near the arms (within the start's uncertainty), plus a margin of background;
// the region's masked pixels are left out and counted in *masked.
std::vector<Sample> SelectSamples(const ImageWindow& window, const CrossFitStart& start, const CrossFitOptions& options,
                                  int* masked) {
  const double c = std::cos(start.rotation_rad), sn = std::sin(start.rotation_rad);
  const double band = 0.5 * start.line_width_px + 4.0 * start.blur_sigma_px + options.margin_px + start.line_width_px;
  const double reach = 0.5 * start.arm_length_px + 4.0 * start.blur_sigma_px + options.margin_px;
  std::vector<Sample> samples;
  for (long row = window.rect.y0_px; row < window.rect.y_end_px(); ++row) {
    for (long col = window.rect.x0_px; col < window.rect.x_end_px(); ++col) {
      const double dx = col - start.centre_px.x_px, dy = row - start.centre_px.y_px;
      const double u = c * dx + sn * dy, v = -sn * dx + c * dy;
      const bool on_u_arm = std::abs(v) <= band && std::abs(u) <= reach;
      const bool on_v_arm = std::abs(u) <= band && std::abs(v) <= reach;
      if (!on_u_arm && !on_v_arm) continue;
      const float value = window.at(col, row);
      if (std::isfinite(value)) {
        samples.push_back({static_cast<double>(col), static_cast<double>(row), static_cast<double>(value)});
      } else {
        ++*masked;
      }
    }
  }
  return samples;
}

// What a solve holds at its current values.
enum class Held {
  kShape,         // rotation, widths, length, blur: a first pass that cannot wander off into a
                  // thin-line degeneracy while the position is still rough
  kNothing,       // every parameter free
  kWidthsAndBlur  // widths, length, blur (CrossFitStart::shape_known): the rotation free
};

// Bounds on the cross's shape for a free fit: plausible ranges around the
// definition, so a bad pixel patch cannot turn the cross into something else.
void BoundShape(const CrossFitStart& start, const CrossFitOptions& options, double* p, ceres::Problem* problem) {
  const double w = start.line_width_px;
  for (int k : {kWidthH, kWidthV}) {
    problem->SetParameterLowerBound(p, k, 0.2 * w);
    problem->SetParameterUpperBound(p, k, 3.0 * w + 1.0);
  }
  problem->SetParameterLowerBound(p, kLength, 0.7 * start.arm_length_px);
  problem->SetParameterUpperBound(p, kLength, 1.3 * start.arm_length_px + 2.0);
  problem->SetParameterLowerBound(p, kSigma, options.min_blur_sigma_px);
  problem->SetParameterUpperBound(p, kSigma, 2.0 * w + 3.0);
}

// Each missing piece stays near where it was seen (its ends within 3 px).
void BoundMissingPieces(const Scene& scene, double* p, ceres::Problem* problem) {
  const SceneLayout layout = scene.layout();
  for (int k = 0; k < layout.gaps(); ++k) {
    const int base = layout.FirstGapParam() + kNumGapParams * k;
    const MissingPieceStart& start = scene.gaps[static_cast<size_t>(k)];
    constexpr double kReachPx = 3.0;
    problem->SetParameterLowerBound(p, base + kGapMiddle, start.middle_px - kReachPx);
    problem->SetParameterUpperBound(p, base + kGapMiddle, start.middle_px + kReachPx);
    problem->SetParameterLowerBound(p, base + kGapLength, 0.5);
    problem->SetParameterUpperBound(p, base + kGapLength, start.length_px + 2.0 * kReachPx);
  }
}

// Each foreign image stays near where its pixels were (so it cannot wander onto
// the cross's own lines) and keeps a star image's width.
void BoundImages(const Scene& scene, double* p, ceres::Problem* problem) {
  for (int k = 0; k < scene.image_count(); ++k) {
    const int base = kNumCrossParams + kNumImageParams * k;
    const ForeignImageStart& start = scene.images[static_cast<size_t>(k)];
    constexpr double kReachPx = 2.0;
    problem->SetParameterLowerBound(p, base + kImageX, start.x_px - kReachPx);
    problem->SetParameterUpperBound(p, base + kImageX, start.x_px + kReachPx);
    problem->SetParameterLowerBound(p, base + kImageY, start.y_px - kReachPx);
    problem->SetParameterUpperBound(p, base + kImageY, start.y_px + kReachPx);
    for (int axis : {kImageL11, kImageL22}) {
      problem->SetParameterLowerBound(p, base + axis, 0.5);
      problem->SetParameterUpperBound(p, base + axis, 6.0);
    }
    problem->SetParameterLowerBound(p, base + kImageL21, -6.0);
    problem->SetParameterUpperBound(p, base + kImageL21, 6.0);
  }
}

bool Solve(const std::vector<Sample>& samples, double xc, double yc, const CrossFitOptions& options,
           const CrossFitStart& start, Held held, Scene* scene, std::string* message) {
  double* p = scene->p.data();
  const SceneLayout layout = scene->layout();
  const int n = layout.Params();
  ceres::Problem problem;
  problem.AddResidualBlock(new CrossCost(&samples, layout, xc, yc), nullptr, p);
  // The start is within about a line width; a fit that wants to leave this box has found something else.
  const double reach_px = 2.0 * start.line_width_px + 2.0;
  problem.SetParameterLowerBound(p, kX0, start.centre_px.x_px - reach_px);
  problem.SetParameterUpperBound(p, kX0, start.centre_px.x_px + reach_px);
  problem.SetParameterLowerBound(p, kY0, start.centre_px.y_px - reach_px);
  problem.SetParameterUpperBound(p, kY0, start.centre_px.y_px + reach_px);
  if (held == Held::kShape) {
    problem.SetManifold(p, new ceres::SubsetManifold(n, {kTheta, kWidthH, kWidthV, kLength, kSigma}));
  } else {
    problem.SetParameterLowerBound(p, kTheta, start.rotation_rad - 0.1);
    problem.SetParameterUpperBound(p, kTheta, start.rotation_rad + 0.1);
  }
  if (held == Held::kWidthsAndBlur) {
    problem.SetManifold(p, new ceres::SubsetManifold(n, {kWidthH, kWidthV, kLength, kSigma}));
  } else if (held == Held::kNothing) {
    BoundShape(start, options, p, &problem);
  }
  if (start.polarity > 0) problem.SetParameterLowerBound(p, kGain, 0.0);
  if (start.polarity < 0) problem.SetParameterUpperBound(p, kGain, 0.0);
  BoundImages(*scene, p, &problem);
  BoundMissingPieces(*scene, p, &problem);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 11 parameters (and 6 per image), thousands of residuals
  // With foreign images, two images sharing one drawn-out star crawl along their
  // common flux long after the cross has settled: on the trail benchmark's
  // crosses 20 iterations measured them as well as 50 did, in 0.6 x the time.
  constexpr int kJointIterations = 20;
  solver.max_num_iterations = layout.Params() == kNumCrossParams ? options.max_iterations
                                                                  : std::min(options.max_iterations, kJointIterations);
  // Converged when a step moves the centre by far less than its sigma.
  solver.function_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-9;
  solver.gradient_tolerance = 1e-12;
  solver.num_threads = 1;  // crosses are fitted in parallel one level up
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  *message = summary.message;
  return summary.IsSolutionUsable();
}

// Formal errors of a converged fit, scaled by its own residual variance.
struct FormalErrors {
  Eigen::Matrix2d centre_covariance;
  double gain_variance = 0.0;         // place and shape held, plane background free
  double sigma0_sq = 0.0;
};

// The normal matrix of the fit at p over the samples (and, when rss != nullptr,
// the residual sum of squares); a held shape's rows and columns are zero.
Eigen::MatrixXd NormalMatrix(const std::vector<Sample>& samples, const std::vector<double>& p, const SceneLayout& layout,
                             double xc, double yc, bool shape_held, double* rss) {
  const int n = layout.Params();
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd gradient(n);
  for (const Sample& s : samples) {
    const double residual = SceneModel(p.data(), layout, xc, yc, s, gradient.data()) - s.value_dn;
    normal.selfadjointView<Eigen::Lower>().rankUpdate(gradient);
    if (rss) *rss += residual * residual;
  }
  normal = normal.selfadjointView<Eigen::Lower>();
  if (shape_held) {
    for (int k : {kWidthH, kWidthV, kLength, kSigma}) {
      normal.row(k).setZero();
      normal.col(k).setZero();
    }
  }
  return normal;
}

// The centre's covariance from its information, and the gain's variance.
FormalErrors ComputeFormalErrors(const std::vector<Sample>& samples, const Scene& scene, double xc, double yc,
                                 bool shape_held) {
  double rss = 0.0;
  const Eigen::MatrixXd normal = NormalMatrix(samples, scene.p, scene.layout(), xc, yc, shape_held, &rss);
  const int free_params = scene.layout().Params() - (shape_held ? 4 : 0);
  FormalErrors errors;
  errors.sigma0_sq = rss / std::max(static_cast<int>(samples.size()) - free_params, 1);
  errors.centre_covariance = errors.sigma0_sq * CentreInformation(normal).inverse();
  // |gain| / sqrt(gain_variance) is the matched-filter SNR of the fitted cross.
  const Eigen::Matrix4d gain_block = normal.block<4, 4>(kGain, kGain);
  errors.gain_variance = errors.sigma0_sq * gain_block.inverse()(0, 0);
  return errors;
}

// The share of the centre's information (1 / variance, the worse axis) that the
// kept pixels hold, with the foreign images fitted, of what the whole region
// would with a clean cross.
double InformationKept(const std::vector<Sample>& all, const std::vector<Sample>& kept, const Scene& scene, double xc,
                       double yc, bool shape_held) {
  if (kept.size() == all.size() && scene.layout().Params() == kNumCrossParams) return 1.0;
  const Eigen::Matrix2d all_covariance =
      CentreInformation(NormalMatrix(all, scene.p, SceneLayout{}, xc, yc, shape_held, nullptr)).inverse();
  const Eigen::Matrix2d kept_covariance =
      CentreInformation(NormalMatrix(kept, scene.p, scene.layout(), xc, yc, shape_held, nullptr)).inverse();
  return std::min(all_covariance(0, 0) / kept_covariance(0, 0), all_covariance(1, 1) / kept_covariance(1, 1));
}

// Where the fit stands on the region's pixels.
struct PixelSplit {
  std::vector<char> clipped;  // per sample of the region: at the scan's clip level (never fitted)
  std::vector<char> dropped;  // the clipped and those found foreign
  std::vector<Sample> kept;
  std::vector<char> foreign;  // the last round's outliers before their margin
};

// The samples a foreign image drove to the scan's clip level on the side away
// from the cross (0 under a bright cross, full scale under a dark one): their
// true value is unknown, so they are never fitted; its wings are.
std::vector<char> ClippedSamples(const std::vector<Sample>& all, const CrossFitStart& start) {
  std::vector<char> clipped(all.size(), 0);
  if (start.polarity == 0 || !(start.full_scale_dn > 0.0)) return clipped;
  for (size_t i = 0; i < all.size(); ++i)
    clipped[i] = start.polarity > 0 ? all[i].value_dn <= 0.0 : all[i].value_dn >= start.full_scale_dn;
  return clipped;
}

std::vector<char> Or(std::vector<char> a, const std::vector<char>& b) {
  for (size_t i = 0; i < a.size(); ++i) a[i] = a[i] || b[i];
  return a;
}

// The first split: with the cross's polarity known, the pixels beyond the
// background on the other side (5 noise sigmas: no cross of that polarity
// reaches there) left out with the margin, before any fit can bend to them.
PixelSplit FirstSplit(const std::vector<Sample>& all, const PixelRect& rect, const CrossFitStart& start,
                      const CrossFitOptions& options) {
  PixelSplit split;
  constexpr double kOppositeSideSigmas = 5.0;
  const long margin_px = std::max(1L, std::lround(options.foreign_margin_blurs * start.blur_sigma_px));
  split.clipped = ClippedSamples(all, start);
  split.foreign = Or(internal::FlagOppositeSide(all, start.polarity, kOppositeSideSigmas), split.clipped);
  split.dropped = internal::GrowFlags(all, split.foreign, rect, margin_px);
  split.kept = internal::Kept(all, split.dropped);
  if (split.kept.size() < all.size() / 2) {  // too few left: fit what is not clipped, the rounds sort it out
    split.dropped = split.foreign = split.clipped;
    split.kept = internal::Kept(all, split.dropped);
  }
  return split;
}

// Drops the pixels that do not belong to the scene's model and solves again
// without them, so the final fit is plain least squares: first the outliers of
// the fit on the split's kept pixels; then, afresh, those of the fit without them (the
// first fit, bent toward the foreign pixels, also misfits some of the cross's
// own), with a margin around each (their blurred edges still pull) of
// foreign_margin_blurs x the fit's blur. The scene comes fitted on the split's
// kept pixels.
bool DropForeignPixels(const std::vector<Sample>& all, const PixelRect& rect, double xc, double yc,
                       const CrossFitOptions& options, const CrossFitStart& start, Held held, Scene* scene,
                       PixelSplit* split, std::string* message) {
  for (int round = 0; round < 2; ++round) {
    std::vector<char> flags = internal::FlagOutliers(all, split->dropped, scene->p, scene->layout(), xc, yc,
                                                     options.outlier_threshold, options.min_outlier_contrast);
    for (size_t i = 0; i < flags.size(); ++i) flags[i] = flags[i] && !split->clipped[i];  // no margin: the wings are good
    const long margin_px = std::lround(options.foreign_margin_blurs * scene->p[kSigma]);
    std::vector<char> next = Or(round == 0 ? flags : internal::GrowFlags(all, flags, rect, margin_px), split->clipped);
    split->foreign = Or(flags, split->clipped);
    if (next == split->dropped) break;
    split->dropped.swap(next);
    split->kept = internal::Kept(all, split->dropped);
    if (split->kept.size() < static_cast<size_t>(4 * scene->layout().Params())) {
      *message = "too few clean pixels left";
      return false;
    }
    if (!Solve(split->kept, xc, yc, options, start, held, scene, message)) return false;
  }
  return true;
}

// The scene with new foreign elements (`joint`) fitted on every pixel that is
// not clipped (an element whose pixels are left out has nothing to fit), the
// pixels it still misses dropped as before. False when the fit fails.
bool FitJointly(const std::vector<Sample>& all, const PixelRect& rect, double xc, double yc,
                const CrossFitOptions& options, const CrossFitStart& start, Held held, const PixelSplit& split,
                Scene* joint, PixelSplit* joint_split) {
  joint_split->clipped = joint_split->dropped = joint_split->foreign = split.clipped;
  joint_split->kept = internal::Kept(all, joint_split->dropped);
  std::string message;
  return Solve(joint_split->kept, xc, yc, options, start, held, joint, &message) &&
         DropForeignPixels(all, rect, xc, yc, options, start, held, joint, joint_split, &message);
}

// The foreign pixels (star images, a trail's dots, dust specks) fitted with the
// cross as elliptical Gaussian images, one started at each peak of their
// residuals. Keeps the scene as it was when there is nothing to model or the
// joint fit fails.
void FitForeignImages(const std::vector<Sample>& all, const PixelRect& rect, double xc, double yc,
                      const CrossFitOptions& options, const CrossFitStart& start, Held held, Scene* scene,
                      PixelSplit* split) {
  std::vector<double> residuals(all.size());
  for (size_t i = 0; i < all.size(); ++i)
    residuals[i] = SceneModel(scene->p.data(), scene->layout(), xc, yc, all[i], nullptr) - all[i].value_dn;
  const std::vector<ForeignImageStart> starts = internal::ForeignImageStarts(
      all, split->foreign, residuals, options.min_foreign_image_separation_px, options.max_foreign_images);
  if (starts.empty()) return;
  Scene joint = *scene;
  std::vector<double> image_params;
  for (const ForeignImageStart& image : starts) {
    joint.images.push_back(image);
    image_params.insert(image_params.end(), {image.x_px, image.y_px, image.flux_dn, image.sigma_px, 0.0, image.sigma_px});
  }
  // The images' parameters go before the missing pieces' (SceneLayout).
  joint.p.insert(joint.p.begin() + scene->layout().FirstGapParam(), image_params.begin(), image_params.end());
  PixelSplit joint_split;
  if (!FitJointly(all, rect, xc, yc, options, start, held, *split, &joint, &joint_split)) return;
  *scene = std::move(joint);
  *split = std::move(joint_split);
}

// The arms' missing pieces (a damaged cross: the line etched or scratched away
// over stretches), each started where an arm shows the background instead of
// the line, fitted as the arm's own profile taken out over the stretch, then
// the foreign images on what is still foreign; `plain` is the cross-only fit.
// Kept when the centre's information is larger than with the images alone
// (*scene): on the damaged crosses of bench_reseau (30 % of the arms' length
// missing), Gaussian images fitted into the gaps left 3.5 to 41 % of the
// centre's information (and one centre 0.76 px off); with the pieces the
// sigmas come within 5 % of the simulator's bound for the damaged cross.
void FitMissingPieces(const std::vector<Sample>& all, const PixelRect& rect, double xc, double yc,
                      const CrossFitOptions& options, const CrossFitStart& start, Held held, const Scene& plain,
                      const PixelSplit& plain_split, Scene* scene, PixelSplit* split) {
  constexpr double kMinPieceLengthPx = 2.0;
  const std::vector<MissingPieceStart> starts =
      internal::MissingPieceStarts(all, plain_split.clipped, plain.p, xc, yc, kMinPieceLengthPx);
  if (starts.empty()) return;
  Scene joint = plain;
  for (const MissingPieceStart& piece : starts) {
    joint.gaps.push_back(piece);
    joint.p.insert(joint.p.end(), {piece.middle_px, piece.length_px});
  }
  PixelSplit joint_split;
  if (!FitJointly(all, rect, xc, yc, options, start, held, plain_split, &joint, &joint_split)) return;
  if (std::find(joint_split.foreign.begin(), joint_split.foreign.end(), 1) != joint_split.foreign.end())
    FitForeignImages(all, rect, xc, yc, options, start, held, &joint, &joint_split);
  if (InformationKept(all, joint_split.kept, joint, xc, yc, start.shape_known) <=
      InformationKept(all, split->kept, *scene, xc, yc, start.shape_known))
    return;
  *scene = std::move(joint);
  *split = std::move(joint_split);
}

// The start of the fit: the place, rotation and shape from the start; the
// background from the median of the pixels; the contrast from the tail of their
// values on the side away from the background (dark or bright crosses). Returns
// false when the pixels show no contrast.
bool StartScene(const std::vector<Sample>& samples, const CrossFitStart& start, const CrossFitOptions& options,
                Scene* scene) {
  std::vector<double> values;
  values.reserve(samples.size());
  for (const Sample& s : samples) values.push_back(s.value_dn);
  std::sort(values.begin(), values.end());
  const double background = values[values.size() / 2];
  const size_t tail = std::max<size_t>(3, values.size() / 40);
  double low = 0, high = 0;
  for (size_t i = 0; i < tail; ++i) {
    low += values[i] / tail;
    high += values[values.size() - 1 - i] / tail;
  }
  const bool dark = start.polarity != 0 ? start.polarity < 0 : background - low > high - background;
  const double gain = dark ? low - background : high - background;
  std::vector<double>& p = scene->p;
  p[kX0] = start.centre_px.x_px;
  p[kY0] = start.centre_px.y_px;
  p[kTheta] = start.rotation_rad;
  p[kWidthH] = p[kWidthV] = start.line_width_px;
  p[kLength] = start.arm_length_px;
  // A generous blur widens the basin of the first pass (thin lines, rough start).
  p[kSigma] = start.shape_known ? start.blur_sigma_px
                                : std::max({start.blur_sigma_px, options.min_blur_sigma_px, 0.5 * start.line_width_px + 0.5});
  p[kGain] = gain / std::min(1.0, start.line_width_px);  // a sub-pixel line covers only part of a pixel
  p[kB0] = background;
  return gain != 0.0;
}

}  // namespace

bool CrossFitOptions::Check(std::string* why) const {
  if (!(margin_px >= 0.0)) return *why = "margin_px must be >= 0", false;
  if (!(min_blur_sigma_px > 0.0)) return *why = "min_blur_sigma_px must be > 0", false;
  if (!(outlier_threshold > 1.0)) return *why = "outlier_threshold must be > 1", false;
  if (!(min_information_kept > 0.0 && min_information_kept <= 1.0)) {
    return *why = "min_information_kept must be in (0, 1]", false;
  }
  if (!(foreign_margin_blurs >= 0.0)) return *why = "foreign_margin_blurs must be >= 0", false;
  if (!(max_masked_fraction >= 0.0 && max_masked_fraction < 1.0)) {
    return *why = "max_masked_fraction must be in [0, 1)", false;
  }
  if (max_foreign_images < 0) return *why = "max_foreign_images must be >= 0", false;
  if (!(min_foreign_image_separation_px >= 1.0)) return *why = "min_foreign_image_separation_px must be >= 1", false;
  if (max_iterations < 1) return *why = "max_iterations must be >= 1", false;
  return true;
}

PixelRect CrossFitWindow(const CrossFitStart& start, const CrossFitOptions& options) {
  const double half = 0.5 * start.arm_length_px + 4.0 * start.blur_sigma_px + options.margin_px + start.line_width_px;
  const long x0 = static_cast<long>(std::floor(start.centre_px.x_px - half));
  const long y0 = static_cast<long>(std::floor(start.centre_px.y_px - half));
  const long x1 = static_cast<long>(std::ceil(start.centre_px.x_px + half));
  const long y1 = static_cast<long>(std::ceil(start.centre_px.y_px + half));
  return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

CrossFitResult FitCross(const ImageWindow& window, const CrossFitStart& start, const CrossFitOptions& options) {
  CrossFitResult result;
  const std::vector<Sample> all = SelectSamples(window, start, options, &result.pixels_masked);
  const size_t region_px = all.size() + static_cast<size_t>(result.pixels_masked);
  result.masked_fraction = region_px > 0 ? static_cast<double>(result.pixels_masked) / static_cast<double>(region_px) : 0.0;
  if (result.masked_fraction > options.max_masked_fraction) {
    result.too_many_masked = true;
    result.summary = std::to_string(result.pixels_masked) + " of the cross's " + std::to_string(region_px) +
                     " px are masked (no value in the scan): too few left to fit it";
    return result;
  }
  if (all.size() < 4 * kNumCrossParams) {
    result.summary = "too few pixels around the cross to fit it";
    return result;
  }
  Scene scene;
  if (!StartScene(all, start, options, &scene)) {
    result.summary = "no contrast between the arms and the background";
    return result;
  }
  const double xc = start.centre_px.x_px, yc = start.centre_px.y_px;
  std::string message;
  const Held final_pass = start.shape_known ? Held::kWidthsAndBlur : Held::kNothing;
  PixelSplit split = FirstSplit(all, window.rect, start, options);
  bool usable = Solve(split.kept, xc, yc, options, start, Held::kShape, &scene, &message) &&
                Solve(split.kept, xc, yc, options, start, final_pass, &scene, &message) &&
                DropForeignPixels(all, window.rect, xc, yc, options, start, final_pass, &scene, &split, &message);
  if (usable && std::find(split.foreign.begin(), split.foreign.end(), 1) != split.foreign.end()) {
    const Scene plain = scene;
    const PixelSplit plain_split = split;
    FitForeignImages(all, window.rect, xc, yc, options, start, final_pass, &scene, &split);
    // A defect with the images fitted: perhaps a damaged cross, whose missing
    // pieces no image describes (crosses that keep enough are left as they are:
    // on the trail plates, star images' edges on an arm also show stretches of
    // background, and pieces fitted there measured worse).
    if (InformationKept(all, split.kept, scene, xc, yc, start.shape_known) < options.min_information_kept)
      FitMissingPieces(all, window.rect, xc, yc, options, start, final_pass, plain, plain_split, &scene, &split);
  }
  if (!usable) {
    result.summary = "the cross fit did not converge (" + message + ")";
    return result;
  }
  const std::vector<Sample>& kept = split.kept;
  result.outlier_fraction = 1.0 - static_cast<double>(kept.size()) / static_cast<double>(all.size());
  result.information_kept = InformationKept(all, kept, scene, xc, yc, start.shape_known);
  result.foreign_images = scene.image_count();
  result.missing_pieces = static_cast<int>(scene.gaps.size());

  const FormalErrors errors = ComputeFormalErrors(kept, scene, xc, yc, start.shape_known);
  const Eigen::Matrix2d& covariance = errors.centre_covariance;
  const std::vector<double>& p = scene.p;
  result.converged = true;
  result.centre_px = {p[kX0], p[kY0]};
  result.sigma_x_px = std::sqrt(std::max(covariance(0, 0), 0.0));
  result.sigma_y_px = std::sqrt(std::max(covariance(1, 1), 0.0));
  result.correlation_xy = covariance(0, 1) / std::max(result.sigma_x_px * result.sigma_y_px, 1e-300);
  result.rotation_rad = p[kTheta];
  result.width_h_px = p[kWidthH];
  result.width_v_px = p[kWidthV];
  result.arm_length_px = p[kLength];
  result.blur_sigma_px = p[kSigma];
  result.gain_dn = p[kGain];
  result.background_dn = p[kB0];
  result.residual_sigma_dn = std::sqrt(errors.sigma0_sq);
  result.gain_sigma_dn = std::sqrt(std::max(errors.gain_variance, 0.0));
  result.pixels_used = static_cast<int>(kept.size());
  std::ostringstream summary;
  summary << "fitted on " << kept.size() << " px (" << static_cast<int>(100.0 * result.outlier_fraction + 0.5)
          << "% dropped as outliers";
  if (result.missing_pieces > 0) summary << ", " << result.missing_pieces << " missing arm pieces fitted";
  if (result.foreign_images > 0) summary << ", " << result.foreign_images << " foreign images fitted with it";
  if (result.pixels_masked > 0) summary << ", " << result.pixels_masked << " masked left out";
  summary << "), residual sigma " << result.residual_sigma_dn << " DN";
  result.summary = summary.str();
  return result;
}

}  // namespace platemeter
