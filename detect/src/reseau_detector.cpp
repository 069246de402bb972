#include "platemeter/detect/reseau_detector.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "platemeter/detect/overview.h"

#include "median.h"

namespace platemeter {
namespace {

using detect_internal::Median;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double SpacingMm(const MasterGrid& grid) {
  std::vector<double> distances;
  for (const GridPoint& p : grid.points) {
    double best = 1e300;
    for (const GridPoint& q : grid.points)
      if (&p != &q) best = std::min(best, std::hypot(p.x_mm - q.x_mm, p.y_mm - q.y_mm));
    distances.push_back(best);
  }
  return Median(distances);
}

// The cross's contrast over its own sigma (cross_fit.h: gain_sigma_dn).
double MatchedFilterSnr(const CrossFitResult& fit) {
  return std::abs(fit.gain_dn) / std::max(fit.gain_sigma_dn, 1e-300);
}

// Fits one grid point's cross, starting at `start_px`; fills the point and its fit.
void RefineOne(const Image& image, const CrossFitStart& start, const ReseauDetectorOptions& options,
               double max_shift_px, int polarity, DetectedPoint* point, CrossFitResult* fit) {
  const PixelRect wanted = CrossFitWindow(start, options.fit);
  const PixelRect window_rect = image.Clip(wanted);
  point->position_px = start.centre_px;
  if (window_rect.width_px * 2 < wanted.width_px || window_rect.height_px * 2 < wanted.height_px) {
    point->status = PointStatus::kMissing;
    point->reason = "outside_scan";
    return;
  }
  *fit = FitCross(image.ReadWindow(window_rect), start, options.fit);
  // The fit's pixels are the band around the start's arms, wide enough for a
  // start a line width off: a centre found farther away (a candidate that a star
  // image pulled off) is fitted again on the band around itself, so that no
  // arm's tip or background side is cut.
  const double moved_px = std::hypot(fit->centre_px.x_px - start.centre_px.x_px, fit->centre_px.y_px - start.centre_px.y_px);
  if (fit->converged && moved_px > start.line_width_px && moved_px <= max_shift_px) {
    CrossFitStart again = start;
    again.centre_px = fit->centre_px;
    const PixelRect again_wanted = CrossFitWindow(again, options.fit);
    const PixelRect again_rect = image.Clip(again_wanted);
    if (again_rect.width_px == again_wanted.width_px && again_rect.height_px == again_wanted.height_px) {
      CrossFitResult refit = FitCross(image.ReadWindow(again_rect), again, options.fit);
      if (refit.converged) *fit = std::move(refit);
    }
  }
  if (fit->too_many_masked) {
    point->status = PointStatus::kMissing;  // the scan holds no values there
    point->reason = "masked_pixels";
    return;
  }
  if (!fit->converged) {
    point->status = PointStatus::kMissing;
    point->reason = "poor_fit";
    return;
  }
  point->position_px = fit->centre_px;
  point->sigma_x_px = fit->sigma_x_px;
  point->sigma_y_px = fit->sigma_y_px;
  point->correlation_xy = fit->correlation_xy;
  const double shift = std::hypot(fit->centre_px.x_px - start.centre_px.x_px, fit->centre_px.y_px - start.centre_px.y_px);
  const double snr = MatchedFilterSnr(*fit);
  // Too little of a clean cross left is a defect whatever the rest's contrast (a
  // fit on the remnants of a damaged cross has none to speak of).
  if (fit->information_kept < options.fit.min_information_kept) {
    point->status = PointStatus::kRejected;
    point->reason = "defect";
    point->sigma_x_px = point->sigma_y_px = point->correlation_xy = 0.0;  // a fit on remnants: no sigma to state
  } else if ((fit->gain_dn < 0 ? -1 : 1) != polarity || snr < options.min_matched_filter_snr) {
    point->status = PointStatus::kMissing;  // nothing cross-like of the right polarity there
    point->reason = "low_contrast";
  } else if (shift > max_shift_px) {
    point->status = PointStatus::kRejected;
    point->reason = "poor_fit";
  } else {
    point->status = PointStatus::kMeasured;
    point->reason.clear();
  }
}

// Below this matched-filter SNR a cross's own pixels do not pin its shape (two
// widths, length, blur) well enough for the linearised sigma of a free-shape fit:
// 1.21 x the scatter at an SNR of 18 (cross_fit_test.cpp), 1.03 x at 30 to 47
// (bench_reseau faint4). Such crosses are fitted again with the plate's shape held.
constexpr double kFreeShapeMinSnr = 30.0;

// The plate's cross shape: the medians over the crosses measured with a free
// shape (all crosses of a plate share the reseau's lines and the scan's blur).
std::optional<CrossFitStart> PlateCrossShape(const std::vector<DetectedPoint>& points,
                                             const std::vector<CrossFitResult>& fits) {
  std::vector<double> widths, lengths, blurs;
  for (size_t g = 0; g < points.size(); ++g) {
    if (points[g].status != PointStatus::kMeasured) continue;
    widths.push_back(0.5 * (fits[g].width_h_px + fits[g].width_v_px));
    lengths.push_back(fits[g].arm_length_px);
    blurs.push_back(fits[g].blur_sigma_px);
  }
  if (widths.size() < 5) return std::nullopt;  // too few to tell the plate's shape from one cross's
  CrossFitStart shape;
  shape.line_width_px = Median(widths);
  shape.arm_length_px = Median(lengths);
  shape.blur_sigma_px = Median(blurs);
  shape.shape_known = true;
  return shape;
}

// Weighted polynomial fit of pixel positions on plate positions; returns chi2
// and, if residuals != nullptr, the residual (px) of every pair.
struct Pair {
  double x_mm, y_mm, x_px, y_px, sigma_px;
};

// Returns chi2 (and the degrees of freedom in *dof when given), or -1 if there are too few pairs.
double PolynomialChi2(const std::vector<Pair>& pairs, int degree, std::vector<Eigen::Vector2d>* residuals,
                      int* dof = nullptr) {
  std::vector<std::pair<int, int>> powers;
  for (int total = 0; total <= degree; ++total)
    for (int i = total; i >= 0; --i) powers.push_back({i, total - i});
  const int n = static_cast<int>(pairs.size()), m = static_cast<int>(powers.size());
  if (n <= m) return -1.0;
  if (dof) *dof = 2 * (n - m);
  double scale = 1e-12;
  for (const Pair& p : pairs) scale = std::max({scale, std::abs(p.x_mm), std::abs(p.y_mm)});
  Eigen::MatrixXd design(n, m);
  Eigen::MatrixXd target(n, 2);
  for (int k = 0; k < n; ++k) {
    const double w = 1.0 / pairs[k].sigma_px;
    for (int j = 0; j < m; ++j) {
      design(k, j) = w * std::pow(pairs[k].x_mm / scale, powers[j].first) * std::pow(pairs[k].y_mm / scale, powers[j].second);
    }
    target(k, 0) = w * pairs[k].x_px;
    target(k, 1) = w * pairs[k].y_px;
  }
  const Eigen::MatrixXd coefficients = design.colPivHouseholderQr().solve(target);
  const Eigen::MatrixXd weighted_residuals = design * coefficients - target;
  if (residuals) {
    residuals->resize(n);
    for (int k = 0; k < n; ++k) (*residuals)[k] = weighted_residuals.row(k).transpose() * pairs[k].sigma_px;
  }
  return weighted_residuals.squaredNorm();
}

int PolynomialDegreeFor(size_t points) { return points >= 40 ? 3 : 1; }

// Among hypotheses that place the same crosses under different ids, the one
// whose calibrated grid coordinates fit the measured centres best.
size_t ChooseOrientation(const MasterGrid& grid, const std::vector<GridHypothesis>& hypotheses,
                         const std::vector<DetectedPoint>& points, double radius_px, double min_excess_chi2,
                         bool* ambiguous, std::string* evidence) {
  *ambiguous = false;
  if (hypotheses.size() == 1) {
    *evidence = "the only arrangement that fits";
    return 0;
  }
  std::vector<double> chi2(hypotheses.size(), -1.0);
  std::vector<int> dof(hypotheses.size(), 0);
  for (size_t h = 0; h < hypotheses.size(); ++h) {
    std::vector<Pair> pairs;
    for (const DetectedPoint& p : points) {
      if (p.status != PointStatus::kMeasured) continue;
      // The id this hypothesis gives the cross measured at p.
      int best = -1;
      double best_d = radius_px;
      for (size_t g = 0; g < grid.points.size(); ++g) {
        const PixelPoint q = hypotheses[h].plate_to_pixel.Apply(grid.points[g].x_mm, grid.points[g].y_mm);
        const double d = std::hypot(q.x_px - p.position_px.x_px, q.y_px - p.position_px.y_px);
        if (d < best_d) {
          best_d = d;
          best = static_cast<int>(g);
        }
      }
      if (best < 0) continue;
      const double sigma = std::max(std::hypot(p.sigma_x_px, p.sigma_y_px) / std::sqrt(2.0), 1e-4);
      pairs.push_back({grid.points[best].x_mm, grid.points[best].y_mm, p.position_px.x_px, p.position_px.y_px, sigma});
    }
    chi2[h] = PolynomialChi2(pairs, PolynomialDegreeFor(pairs.size()), nullptr, &dof[h]);
  }
  size_t best = 0;
  for (size_t h = 1; h < chi2.size(); ++h)
    if (chi2[h] >= 0 && (chi2[best] < 0 || chi2[h] < chi2[best])) best = h;
  double runner_up = -1;
  for (size_t h = 0; h < chi2.size(); ++h)
    if (h != best && chi2[h] >= 0 && (runner_up < 0 || chi2[h] < runner_up)) runner_up = chi2[h];
  // The runner-up's excess chi2, in units of the best fit's own variance factor
  // (film deformation the polynomial misses inflates both alike).
  const double variance_factor = chi2[best] >= 0 ? std::max(1.0, chi2[best] / std::max(dof[best], 1)) : 1.0;
  const double excess = runner_up >= 0 ? (runner_up - chi2[best]) / variance_factor : 0.0;
  std::ostringstream text;
  text << "calibrated grid deviations: chi2 " << chi2[best] << " (" << dof[best] << " dof) for orientation "
       << hypotheses[best].orientation.Name();
  if (runner_up >= 0) text << ", the next best exceeds it by " << excess << " after scaling";
  *ambiguous = chi2[best] < 0 || (runner_up >= 0 && excess < min_excess_chi2);
  if (*ambiguous) text << ": not decisive";
  *evidence = text.str();
  return best;
}

// Rejects crosses that disagree with the smooth residual field of their neighbours.
void CheckAgainstNeighbours(const MasterGrid& grid, double spacing_mm, double outlier_sigma,
                            std::vector<DetectedPoint>* points) {
  std::vector<Pair> pairs;
  std::vector<size_t> index;
  for (size_t g = 0; g < points->size(); ++g) {
    const DetectedPoint& p = (*points)[g];
    if (p.status != PointStatus::kMeasured) continue;
    const double sigma = std::max(std::hypot(p.sigma_x_px, p.sigma_y_px) / std::sqrt(2.0), 1e-4);
    pairs.push_back({grid.points[g].x_mm, grid.points[g].y_mm, p.position_px.x_px, p.position_px.y_px, sigma});
    index.push_back(g);
  }
  if (pairs.size() < 8) return;
  std::vector<Eigen::Vector2d> residuals;
  if (PolynomialChi2(pairs, 1, &residuals) < 0) return;
  // Each cross's residual against the median of its neighbours' (within 1.5 spacings).
  std::vector<Eigen::Vector2d> deviations(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    std::vector<double> nx, ny;
    for (size_t j = 0; j < pairs.size(); ++j) {
      if (j == k) continue;
      if (std::hypot(pairs[j].x_mm - pairs[k].x_mm, pairs[j].y_mm - pairs[k].y_mm) <= 1.5 * spacing_mm) {
        nx.push_back(residuals[j].x());
        ny.push_back(residuals[j].y());
      }
    }
    deviations[k] = nx.size() >= 2 ? Eigen::Vector2d(residuals[k].x() - Median(nx), residuals[k].y() - Median(ny))
                                    : Eigen::Vector2d(0, 0);
  }
  // The field's own roughness, robustly, beyond the formal sigmas.
  std::vector<double> magnitudes;
  for (const auto& d : deviations) magnitudes.push_back(d.norm());
  const double field_sigma = 1.4826 * Median(magnitudes) / std::sqrt(2.0);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const double combined = std::hypot(pairs[k].sigma_px, field_sigma);
    if (deviations[k].norm() > outlier_sigma * combined) {
      DetectedPoint& p = (*points)[index[k]];
      p.status = PointStatus::kRejected;
      p.reason = "outlier";
    }
  }
}

}  // namespace

bool ReseauDetectorOptions::Check(std::string* why) const {
  if (!(pixel_size_um > 0.0)) return *why = "the scan's pixel size must be given", false;
  if (!(min_matched_filter_snr > 0.0)) return *why = "min_matched_filter_snr must be positive", false;
  if (!(max_shift_fraction > 0.0 && max_shift_fraction < 0.5)) return *why = "max_shift_fraction must be in (0, 0.5)", false;
  if (!(neighbour_outlier_sigma > 1.0)) return *why = "neighbour_outlier_sigma must exceed 1", false;
  if (!(orientation_min_excess_chi2 > 0.0)) return *why = "orientation_min_excess_chi2 must be positive", false;
  return fit.Check(why);
}

ReseauDetection DetectReseau(const Image& image, const MasterGrid& grid, const ReseauDetectorOptions& options_in) {
  ReseauDetection result;
  ReseauDetectorOptions options = options_in;
  std::string why;
  if (!options.Check(&why)) {
    result.summary = why;
    return result;
  }
  const double px_per_um = 1.0 / options.pixel_size_um;
  options.candidates.line_width_px = grid.mark.line_width_um * px_per_um;
  options.candidates.arm_length_px = grid.mark.arm_length_um * px_per_um;
  options.assignment.pixel_size_um = options.pixel_size_um;
  options.assignment.orientation = options.orientation;
  const double spacing_mm = SpacingMm(grid);

  auto clock = std::chrono::steady_clock::now();
  result.overview_factor = OverviewFactorFor(options.candidates.line_width_px,
                                             std::max(image.info().width_px, image.info().height_px));
  const Overview overview = BuildOverview(image, result.overview_factor);
  result.masked_px = overview.masked_px;
  result.seconds_overview = SecondsSince(clock);

  clock = std::chrono::steady_clock::now();
  options.candidates.max_candidates = std::max<int>(options.candidates.max_candidates, 6 * static_cast<int>(grid.points.size()));
  const std::vector<CrossCandidate> candidates = FindCrossCandidates(overview, options.candidates);
  result.candidates = static_cast<int>(candidates.size());
  result.seconds_candidates = SecondsSince(clock);

  clock = std::chrono::steady_clock::now();
  const GridAssignment assignment = AssignGrid(candidates, grid, options.assignment);
  result.seconds_assignment = SecondsSince(clock);
  result.points.resize(grid.points.size());
  result.fits.resize(grid.points.size());
  for (size_t g = 0; g < grid.points.size(); ++g) {
    result.points[g].id = grid.points[g].id;
    result.points[g].kind = PointKind::kReseau;
    result.points[g].status = PointStatus::kMissing;
    result.points[g].reason = "not_found";
  }
  if (!assignment.found) {
    result.summary = assignment.summary;
    result.missing = static_cast<int>(grid.points.size());
    return result;
  }
  result.found = true;
  const GridHypothesis& top = assignment.hypotheses.front();
  result.polarity = top.polarity;

  // Refine every grid point under the top hypothesis: at its candidate, or at
  // its predicted position when it had none (the second search).
  clock = std::chrono::steady_clock::now();
  const double scale_px_per_mm = std::sqrt(std::abs(top.plate_to_pixel.a[0] * top.plate_to_pixel.a[3] -
                                                    top.plate_to_pixel.a[1] * top.plate_to_pixel.a[2]));
  const double rotation_rad = std::atan2(top.plate_to_pixel.a[2], top.plate_to_pixel.a[0]);
  // The arms' angle against the pixel axes, reduced to (-45, 45] degrees.
  const double arm_rotation_rad = rotation_rad - std::round(rotation_rad / (M_PI / 2)) * (M_PI / 2);
  const double max_shift_px = options.max_shift_fraction * spacing_mm * scale_px_per_mm;
  std::vector<CrossFitStart> starts(grid.points.size());
  tbb::parallel_for(size_t{0}, grid.points.size(), [&](size_t g) {
    CrossFitStart& start = starts[g];
    const int c = top.candidate_of_point[g];
    start.centre_px = c >= 0 ? candidates[c].position_px
                             : top.plate_to_pixel.Apply(grid.points[g].x_mm, grid.points[g].y_mm);
    start.rotation_rad = arm_rotation_rad;
    start.line_width_px = grid.mark.line_width_um * scale_px_per_mm / 1000.0;
    start.arm_length_px = grid.mark.arm_length_um * scale_px_per_mm / 1000.0;
    start.polarity = top.polarity;
    start.full_scale_dn = image.info().full_scale_dn;
    RefineOne(image, start, options, max_shift_px, top.polarity, &result.points[g], &result.fits[g]);
  });
  // Faint crosses (measured, or missing for low contrast) again with the plate's
  // shape held: a free shape their pixels cannot pin makes the sigma optimistic.
  // So are the defects: a damaged cross's free shape can bend to its remnants (a
  // bar narrowed to a third of the plate's width beside its line, then taken for
  // missing), the plate's cannot.
  if (const std::optional<CrossFitStart> shape = PlateCrossShape(result.points, result.fits)) {
    tbb::parallel_for(size_t{0}, grid.points.size(), [&](size_t g) {
      const DetectedPoint& p = result.points[g];
      const CrossFitResult& f = result.fits[g];
      // Missing with a converged fit: too faint (low_contrast).
      const bool faint = f.converged && (p.status == PointStatus::kMissing ||
                                         (p.status == PointStatus::kMeasured && MatchedFilterSnr(f) < kFreeShapeMinSnr));
      const bool defect = p.status == PointStatus::kRejected && p.reason == "defect";
      if (!faint && !defect) return;
      CrossFitStart start = starts[g];
      start.line_width_px = shape->line_width_px;
      start.arm_length_px = shape->arm_length_px;
      start.blur_sigma_px = shape->blur_sigma_px;
      start.shape_known = true;
      RefineOne(image, start, options, max_shift_px, top.polarity, &result.points[g], &result.fits[g]);
    });
  }
  result.seconds_refinement = SecondsSince(clock);

  // Orientation: the tied hypotheses give the same crosses other ids.
  const size_t chosen = ChooseOrientation(grid, assignment.hypotheses, result.points,
                                          options.assignment.match_fraction * spacing_mm * scale_px_per_mm,
                                          options.orientation_min_excess_chi2, &result.orientation_ambiguous,
                                          &result.orientation_evidence);
  const GridHypothesis& hypothesis = assignment.hypotheses[chosen];
  result.orientation = hypothesis.orientation;
  result.plate_to_pixel = hypothesis.plate_to_pixel;
  if (chosen != 0) {
    // Re-label: each refined cross goes to the grid point this hypothesis predicts nearest to it.
    std::vector<DetectedPoint> relabelled(grid.points.size());
    std::vector<CrossFitResult> refits(grid.points.size());
    for (size_t g = 0; g < grid.points.size(); ++g) {
      relabelled[g].id = grid.points[g].id;
      relabelled[g].kind = PointKind::kReseau;
      relabelled[g].status = PointStatus::kMissing;
      relabelled[g].reason = "not_found";
    }
    for (size_t k = 0; k < result.points.size(); ++k) {
      const PixelPoint p = result.points[k].position_px;
      size_t best = 0;
      double best_d = 1e300;
      for (size_t g = 0; g < grid.points.size(); ++g) {
        const PixelPoint q = hypothesis.plate_to_pixel.Apply(grid.points[g].x_mm, grid.points[g].y_mm);
        const double d = std::hypot(q.x_px - p.x_px, q.y_px - p.y_px);
        if (d < best_d) {
          best_d = d;
          best = g;
        }
      }
      relabelled[best] = result.points[k];
      relabelled[best].id = grid.points[best].id;
      refits[best] = result.fits[k];
    }
    result.points.swap(relabelled);
    result.fits.swap(refits);
  }

  CheckAgainstNeighbours(grid, spacing_mm, options.neighbour_outlier_sigma, &result.points);
  for (const DetectedPoint& p : result.points) {
    result.measured += p.status == PointStatus::kMeasured;
    result.rejected += p.status == PointStatus::kRejected;
    result.missing += p.status == PointStatus::kMissing;
  }
  std::ostringstream summary;
  summary << result.measured << " of " << grid.points.size() << " crosses measured, " << result.rejected
          << " rejected, " << result.missing << " missing; " << (result.polarity < 0 ? "dark" : "bright")
          << " crosses, orientation " << result.orientation.Name();
  if (result.orientation_ambiguous) summary << " (AMBIGUOUS: " << result.orientation_evidence << ")";
  result.summary = summary.str();
  return result;
}

}  // namespace platemeter
