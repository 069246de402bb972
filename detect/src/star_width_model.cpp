// The plate's star-image width model (star_width_model.h): a clipped least-squares polynomial.
#include "platemeter/detect/star_width_model.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "platemeter/detect/star_detector.h"
#include "median.h"

namespace platemeter {
namespace {

constexpr double kClipSigmas = 3.0;
constexpr int kClipRounds = 4;

struct WidthSample {
  double u, v, sigma_px;
};

int Terms(int degree) { return degree == 2 ? 6 : degree == 1 ? 3 : 1; }

// At most 6 terms, on the stack (SigmaAt runs once per image).
using BasisVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;
BasisVector Basis(int degree, double u, double v) {
  BasisVector b(Terms(degree));
  b(0) = 1.0;
  if (degree >= 1) b(1) = u, b(2) = v;
  if (degree >= 2) b(3) = u * u, b(4) = u * v, b(5) = v * v;
  return b;
}

bool IsModelStar(const DetectedStar& s, const StarWidthModel& reference) {
  constexpr unsigned kExcluded =
      kStarSaturated | kStarBlended | kStarTruncated | kStarElongated | kStarDefect | kStarCrowded;
  return s.point.status == PointStatus::kMeasured && (s.flags & kExcluded) == 0 && s.length_px == 0 &&
         s.snr >= kWidthModelMinSnr && s.fwhm_px > 0 &&
         std::abs(std::log(s.fwhm_px / kFwhmPerSigma /
                           reference.SigmaAt(s.point.position_px.x_px, s.point.position_px.y_px))) <=
             std::log(kWidthModelSpread);
}

}  // namespace

double StarWidthModel::SigmaAt(double x_px, double y_px) const {
  if (coefficients.empty()) return min_sigma_px;
  const double u = (x_px - centre_x_px) / half_width_px, v = (y_px - centre_y_px) / half_height_px;
  const BasisVector b = Basis(degree, u, v);
  const double sigma = b.dot(Eigen::Map<const Eigen::VectorXd>(coefficients.data(), b.size()));
  return std::clamp(sigma, min_sigma_px, max_sigma_px);
}

StarWidthModel StartWidthModel(long width_px, long height_px, double start_sigma_px) {
  StarWidthModel model;
  model.centre_x_px = 0.5 * (width_px - 1), model.centre_y_px = 0.5 * (height_px - 1);
  model.half_width_px = std::max(1.0, 0.5 * width_px), model.half_height_px = std::max(1.0, 0.5 * height_px);
  model.min_sigma_px = model.max_sigma_px = start_sigma_px;
  return model;
}

StarWidthModel SettleStarWidthModel(const std::vector<DetectedStar>& stars, StarWidthModel reference, int rounds) {
  for (int round = 0; round < rounds; ++round) {
    StarWidthModel next = FitStarWidthModel(stars, reference);
    const bool same = next.stars_used == reference.stars_used && next.coefficients == reference.coefficients;
    reference = std::move(next);
    if (same) break;
  }
  return reference;
}

StarWidthModel FitStarWidthModel(const std::vector<DetectedStar>& stars, const StarWidthModel& reference) {
  StarWidthModel model = reference;
  std::vector<WidthSample> samples;
  std::vector<double> misfits;  // the model stars' profile_misfit
  for (const DetectedStar& s : stars) {
    if (!IsModelStar(s, reference)) continue;
    samples.push_back({(s.point.position_px.x_px - model.centre_x_px) / model.half_width_px,
                       (s.point.position_px.y_px - model.centre_y_px) / model.half_height_px,
                       s.fwhm_px / kFwhmPerSigma});
    misfits.push_back(s.profile_misfit);
  }
  const long n = static_cast<long>(samples.size());
  if (n < 3) return reference;
  model.degree = n >= 60 ? 2 : n >= 15 ? 1 : 0;
  const int terms = Terms(model.degree);
  // Start from the median (robust to the dust and blends among the bright images), then refit on the
  // widths within kClipSigmas robust sigmas of the current model.
  std::vector<double> widths;
  for (const WidthSample& s : samples) widths.push_back(s.sigma_px);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(terms);
  c(0) = detect_internal::Median(widths);
  std::vector<double> residuals(n);
  double scatter = 0;
  std::vector<const WidthSample*> kept;
  for (int round = 0; round <= kClipRounds; ++round) {
    std::vector<double> abs_residuals;
    for (long i = 0; i < n; ++i) {
      residuals[i] = samples[i].sigma_px - Basis(model.degree, samples[i].u, samples[i].v).dot(c);
      abs_residuals.push_back(std::abs(residuals[i]));
    }
    scatter = std::max(1.4826 * detect_internal::Median(abs_residuals), 1e-3 * c(0));
    kept.clear();
    for (long i = 0; i < n; ++i)
      if (std::abs(residuals[i]) <= kClipSigmas * scatter) kept.push_back(&samples[i]);
    if (round == kClipRounds || static_cast<int>(kept.size()) < 2 * terms) break;
    Eigen::MatrixXd a(kept.size(), terms);
    Eigen::VectorXd y(kept.size());
    for (size_t k = 0; k < kept.size(); ++k) {
      a.row(k) = Basis(model.degree, kept[k]->u, kept[k]->v).transpose();
      y(k) = kept[k]->sigma_px;
    }
    c = a.colPivHouseholderQr().solve(y);
  }
  model.coefficients.assign(c.data(), c.data() + terms);
  model.stars_used = static_cast<long>(kept.size());
  model.scatter_px = scatter;
  model.min_sigma_px = 1e300, model.max_sigma_px = 0;
  for (const WidthSample* s : kept)
    model.min_sigma_px = std::min(model.min_sigma_px, s->sigma_px), model.max_sigma_px = std::max(model.max_sigma_px, s->sigma_px);
  if (kept.empty()) model.min_sigma_px = model.max_sigma_px = c(0);
  model.profile_misfit = detect_internal::Median(misfits);
  return model;
}

}  // namespace platemeter
