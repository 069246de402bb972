#include "platemeter/detect/cross_candidates.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace platemeter {

bool CrossCandidateOptions::Check(std::string* why) const {
  if (!(line_width_px > 0.0)) return *why = "line width must be positive", false;
  if (!(arm_length_px > 2 * line_width_px)) return *why = "arm length must exceed twice the line width", false;
  if (!(min_abs_score > 0.0 && min_abs_score < 1.0)) return *why = "min_abs_score must be in (0, 1)", false;
  if (max_candidates < 1) return *why = "max_candidates must be positive", false;
  return true;
}

int OverviewFactorFor(double line_width_px, long scan_long_side_px, double target_line_px, long max_overview_px) {
  const int by_line = std::max(1, static_cast<int>(std::floor(line_width_px / target_line_px)));
  const int by_memory = static_cast<int>((scan_long_side_px + max_overview_px - 1) / max_overview_px);
  // A power of two, so overview blocks align with power-of-two tiles (overview.cpp).
  int factor = 1;
  while (factor < std::max(by_line, by_memory)) factor *= 2;
  return factor;
}

std::vector<CrossCandidate> FindCrossCandidates(const Overview& overview, const CrossCandidateOptions& options) {
  const double f = overview.factor;
  const double width = std::max(1.0, options.line_width_px / f);
  const double half_arm = std::min(options.max_template_arm_overview_px, 0.5 * options.arm_length_px / f);
  const int half = static_cast<int>(std::ceil(half_arm + width));
  const int size = 2 * half + 1;
  // Bright cross template with pixel-area coverage of the bars, so thin lines keep their weight.
  cv::Mat templ(size, size, CV_32F);
  for (int r = 0; r < size; ++r) {
    for (int c = 0; c < size; ++c) {
      auto coverage = [](double t, double half_width) {  // overlap of [t-0.5, t+0.5] with [-hw, hw]
        return std::clamp(std::min(t + 0.5, half_width) - std::max(t - 0.5, -half_width), 0.0, 1.0);
      };
      const double dx = c - half, dy = r - half;
      const double h = coverage(dy, 0.5 * width) * coverage(dx, half_arm);
      const double v = coverage(dx, 0.5 * width) * coverage(dy, half_arm);
      templ.at<float>(r, c) = static_cast<float>(h + v - h * v);
    }
  }
  const cv::Mat image(static_cast<int>(overview.height_px), static_cast<int>(overview.width_px), CV_32F,
                      const_cast<float*>(overview.values_dn.data()));
  if (image.rows < size || image.cols < size) return {};
  // Scores in tiles: matchTemplate's buffers (integral images, DFTs) grow with
  // the image, so a whole overview would cost several times its own memory.
  // Each tile's score is computed with a halo of half the suppression window,
  // and only peaks in the tile's core are kept, so tiling changes nothing.
  const int score_rows = image.rows - size + 1, score_cols = image.cols - size + 1;
  const int nms = std::max(3, 2 * static_cast<int>(half_arm) + 1);
  const int halo = nms / 2 + 1;
  constexpr int kTile = 1024;
  std::vector<CrossCandidate> candidates;
  for (int ty = 0; ty < score_rows; ty += kTile) {
    for (int tx = 0; tx < score_cols; tx += kTile) {
      const int x0 = std::max(0, tx - halo), y0 = std::max(0, ty - halo);
      const int x1 = std::min(score_cols, tx + kTile + halo), y1 = std::min(score_rows, ty + kTile + halo);
      cv::Mat score;
      cv::matchTemplate(image(cv::Rect(x0, y0, x1 - x0 + size - 1, y1 - y0 + size - 1)), templ, score,
                        cv::TM_CCOEFF_NORMED);
      // Local extrema of |score| within half an arm.
      const cv::Mat magnitude = cv::abs(score);
      cv::Mat dilated;
      cv::dilate(magnitude, dilated, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(nms, nms)));
      for (int r = ty - y0; r < std::min(ty + kTile, score_rows) - y0; ++r) {
        const float* m = magnitude.ptr<float>(r);
        const float* d = dilated.ptr<float>(r);
        const float* sc = score.ptr<float>(r);
        for (int c = tx - x0; c < std::min(tx + kTile, score_cols) - x0; ++c) {
          if (m[c] < options.min_abs_score || m[c] < d[c]) continue;
          // Sub-pixel peak by a parabola through the neighbours (enough to start the fit).
          double ox = 0, oy = 0;
          if (c > 0 && c + 1 < score.cols) {
            const double a = m[c - 1], b = m[c], e = m[c + 1];
            const double denom = a - 2 * b + e;
            if (denom < 0) ox = std::clamp(0.5 * (a - e) / denom, -0.5, 0.5);
          }
          if (r > 0 && r + 1 < score.rows) {
            const double a = magnitude.at<float>(r - 1, c), b = m[c], e = magnitude.at<float>(r + 1, c);
            const double denom = a - 2 * b + e;
            if (denom < 0) oy = std::clamp(0.5 * (a - e) / denom, -0.5, 0.5);
          }
          CrossCandidate candidate;
          candidate.position_px = overview.ToScan(x0 + c + half + ox, y0 + r + half + oy);
          candidate.score = sc[c];
          candidates.push_back(candidate);
        }
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const CrossCandidate& a, const CrossCandidate& b) { return std::abs(a.score) > std::abs(b.score); });
  if (static_cast<int>(candidates.size()) > options.max_candidates) candidates.resize(options.max_candidates);
  return candidates;
}

}  // namespace platemeter
