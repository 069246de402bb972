#include "cross_foreign.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "median.h"

namespace platemeter::internal {

std::vector<char> FlagOutliers(const std::vector<CrossSample>& samples, const std::vector<char>& dropped,
                               const std::vector<double>& p, const SceneLayout& layout, double xc, double yc, double threshold,
                               double min_contrast) {
  std::vector<double> abs_residuals(samples.size()), kept_residuals;
  for (size_t i = 0; i < samples.size(); ++i) {
    abs_residuals[i] = std::abs(SceneModel(p.data(), layout, xc, yc, samples[i], nullptr) - samples[i].value_dn);
    if (!dropped[i]) kept_residuals.push_back(abs_residuals[i]);
  }
  const double robust_sigma = 1.4826 * detect_internal::Median(kept_residuals);
  // The floor keeps a nearly noise-free scan from losing pixels to tiny model
  // differences; real defects deviate by a large part of the contrast.
  const double limit = std::max(threshold * robust_sigma, min_contrast * std::abs(p[kGain]));
  std::vector<char> flags(samples.size(), 0);
  for (size_t i = 0; i < samples.size(); ++i) flags[i] = abs_residuals[i] > limit;
  return flags;
}

std::vector<char> FlagOppositeSide(const std::vector<CrossSample>& samples, int polarity, double threshold) {
  std::vector<char> flags(samples.size(), 0);
  if (polarity == 0 || samples.empty()) return flags;
  std::vector<double> values(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) values[i] = samples[i].value_dn;
  const double background = detect_internal::Median(values);
  for (double& v : values) v = std::abs(v - background);
  const double noise = 1.4826 * detect_internal::Median(values);
  for (size_t i = 0; i < samples.size(); ++i)
    flags[i] = polarity * (samples[i].value_dn - background) < -threshold * noise;
  return flags;
}

std::vector<char> GrowFlags(const std::vector<CrossSample>& samples, const std::vector<char>& flags,
                            const PixelRect& rect, long margin_px) {
  if (margin_px <= 0) return flags;
  std::vector<char> grid(static_cast<size_t>(rect.width_px * rect.height_px), 0);  // one cell per window pixel
  auto cell = [&](long col, long row) -> char& {
    return grid[static_cast<size_t>((row - rect.y0_px) * rect.width_px + (col - rect.x0_px))];
  };
  for (size_t i = 0; i < samples.size(); ++i) {
    if (!flags[i]) continue;
    const long col = static_cast<long>(samples[i].x_px), row = static_cast<long>(samples[i].y_px);
    for (long r = std::max(rect.y0_px, row - margin_px); r <= std::min(rect.y_end_px() - 1, row + margin_px); ++r)
      for (long c = std::max(rect.x0_px, col - margin_px); c <= std::min(rect.x_end_px() - 1, col + margin_px); ++c)
        cell(c, r) = 1;
  }
  std::vector<char> grown(samples.size(), 0);
  for (size_t i = 0; i < samples.size(); ++i)
    grown[i] = cell(static_cast<long>(samples[i].x_px), static_cast<long>(samples[i].y_px));
  return grown;
}

std::vector<CrossSample> Kept(const std::vector<CrossSample>& samples, const std::vector<char>& dropped) {
  std::vector<CrossSample> kept;
  kept.reserve(samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    if (!dropped[i]) kept.push_back(samples[i]);
  return kept;
}

std::vector<ForeignImageStart> ForeignImageStarts(const std::vector<CrossSample>& samples,
                                                  const std::vector<char>& flags, const std::vector<double>& residuals,
                                                  double min_separation_px, int max_images) {
  // Greedy non-maximum suppression: the flagged samples by |value - model|,
  // each a new image unless one already started lies within the separation.
  std::vector<size_t> order;
  for (size_t i = 0; i < samples.size(); ++i)
    if (flags[i]) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return std::abs(residuals[a]) > std::abs(residuals[b]); });
  std::vector<ForeignImageStart> starts;
  constexpr double kStartSigmaPx = 1.0;
  const double flux_per_peak = 2.0 * std::numbers::pi * kStartSigmaPx * kStartSigmaPx;
  for (size_t i : order) {
    if (starts.size() >= static_cast<size_t>(max_images)) break;
    const bool near = std::any_of(starts.begin(), starts.end(), [&](const ForeignImageStart& s) {
      return std::max(std::abs(s.x_px - samples[i].x_px), std::abs(s.y_px - samples[i].y_px)) < min_separation_px;
    });
    if (!near) starts.push_back({samples[i].x_px, samples[i].y_px, -residuals[i] * flux_per_peak, kStartSigmaPx});
  }
  return starts;
}

std::vector<MissingPieceStart> MissingPieceStarts(const std::vector<CrossSample>& samples,
                                                  const std::vector<char>& clipped, const std::vector<double>& p,
                                                  double xc, double yc, double min_length_px) {
  const double c = std::cos(p[kTheta]), sn = std::sin(p[kTheta]);
  const int steps = static_cast<int>(std::ceil(0.5 * p[kLength]));
  if (steps <= 0) return {};
  // Per arm and step: sums of signal x (value - background) and signal^2, the signal being the
  // cross's model above its background.
  std::vector<double> signal_value(4 * static_cast<size_t>(steps), 0.0), signal_signal(signal_value.size(), 0.0);
  for (size_t i = 0; i < samples.size(); ++i) {
    if (clipped[i]) continue;
    const CrossSample& s = samples[i];
    const double dx = s.x_px - p[kX0], dy = s.y_px - p[kY0];
    const double u = c * dx + sn * dy, v = -sn * dx + c * dy;
    const bool on_u = std::abs(v) <= std::max(0.5 * p[kWidthH], 0.5);  // an arm's core (a thin line's middle pixel)
    const bool on_v = std::abs(u) <= std::max(0.5 * p[kWidthV], 0.5);
    if (on_u == on_v) continue;  // off the arms, or on both (the centre)
    const double along = on_u ? u : v;
    const int step = static_cast<int>(std::abs(along));
    if (step >= steps) continue;
    const size_t bin = static_cast<size_t>(((on_u ? 0 : 1) + (along < 0 ? 2 : 0)) * steps + step);
    const double background = p[kB0] + p[kBx] * (s.x_px - xc) + p[kBy] * (s.y_px - yc);
    const double signal = CrossModel(p.data(), xc, yc, s, nullptr) - background;
    signal_value[bin] += signal * (s.value_dn - background);
    signal_signal[bin] += signal * signal;
  }
  std::vector<MissingPieceStart> starts;
  for (int arm = 0; arm < 4; ++arm) {
    const double other_half_width = 0.5 * p[arm % 2 == 0 ? kWidthV : kWidthH];
    int best_first = 0, best_count = 0, count = 0;
    for (int step = 0; step < steps; ++step) {
      const size_t bin = static_cast<size_t>(arm * steps + step);
      const bool missing = step >= other_half_width && signal_signal[bin] > 0.0 &&
                           std::abs(signal_value[bin] / signal_signal[bin]) < 0.5;
      count = missing ? count + 1 : 0;
      if (count > best_count) best_count = count, best_first = step - count + 1;
    }
    if (best_count >= min_length_px) starts.push_back({arm, best_first + 0.5 * best_count, static_cast<double>(best_count)});
  }
  return starts;
}

}  // namespace platemeter::internal
