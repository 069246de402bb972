// Trail mode: deblending of merged dashes and dots (star_internal.h, SplitComponents).
#include <algorithm>
#include <cmath>
#include <deque>

#include "star_internal.h"

namespace platemeter::star_internal {
namespace {

constexpr int kLevels = 32;

struct Deblender {
  const cv::Mat& labels;
  const cv::Mat& filtered;
  const Component& c;
  std::vector<float> levels;
  int min_area;
  double min_flux, min_rise;
  cv::Mat stamp;  // box-sized visit marks
  int visit = 0;

  float F(int v) const { return filtered.at<float>(c.y + v / c.width, c.x + v % c.width); }

  // 8-connected pieces of the pixels of `pix` at or above `level`.
  std::vector<std::vector<int>> Pieces(const std::vector<int>& pix, float level) {
    ++visit;
    const int mark_in = 2 * visit, mark_done = 2 * visit + 1;
    for (int v : pix)
      if (F(v) >= level) stamp.at<int>(v / c.width, v % c.width) = mark_in;
    std::vector<std::vector<int>> pieces;
    for (int v : pix) {
      if (stamp.at<int>(v / c.width, v % c.width) != mark_in) continue;
      std::vector<int> piece{v};
      stamp.at<int>(v / c.width, v % c.width) = mark_done;
      for (size_t k = 0; k < piece.size(); ++k) {
        const int x = piece[k] % c.width, y = piece[k] / c.width;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int u = x + dx, w = y + dy;
            if (u < 0 || w < 0 || u >= c.width || w >= c.height || stamp.at<int>(w, u) != mark_in) continue;
            stamp.at<int>(w, u) = mark_done;
            piece.push_back(w * c.width + u);
          }
      }
      pieces.push_back(std::move(piece));
    }
    return pieces;
  }

  bool Significant(const std::vector<int>& piece, float level) const {
    if (static_cast<int>(piece.size()) < min_area) return false;
    double flux = 0, peak = -1e30;
    for (int v : piece) flux += F(v), peak = std::max<double>(peak, F(v));
    return flux >= min_flux && peak >= level + min_rise;
  }

  void Split(const std::vector<int>& pix, int from, std::vector<std::vector<int>>* leaves) {
    for (int k = from + 1; k < kLevels; ++k) {
      std::vector<std::vector<int>> pieces = Pieces(pix, levels[k]);
      std::vector<std::vector<int>*> significant;
      for (auto& p : pieces)
        if (Significant(p, levels[k])) significant.push_back(&p);
      if (significant.empty()) break;
      if (significant.size() >= 2) {
        for (auto* p : significant) Split(*p, k, leaves);
        return;
      }
    }
    leaves->push_back(pix);
  }
};

}  // namespace

std::vector<Component> SplitComponents(cv::Mat* labels, const cv::Mat& filtered, const std::vector<Component>& in,
                                       const std::vector<float>& threshold, const std::vector<float>& min_rise,
                                       double min_long_side_px, int min_piece_area, double min_contrast,
                                       int* next_label) {
  std::vector<Component> out;
  for (size_t ci = 0; ci < in.size(); ++ci) {
    const Component& c = in[ci];
    Component whole = c;  // not cut: no clump's piece
    whole.crowded = false;
    if (std::max(c.width, c.height) <= min_long_side_px) {
      out.push_back(whole);
      continue;
    }
    std::vector<int> pix;
    double total = 0;
    float peak = -1e30f;
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x)
        if (labels->at<int>(c.y + y, c.x + x) == c.label) {
          pix.push_back(y * c.width + x);
          const float f = filtered.at<float>(c.y + y, c.x + x);
          total += f, peak = std::max(peak, f);
        }
    const float low = std::max(threshold[ci], 1e-6f);
    if (!(peak > low)) {
      out.push_back(whole);
      continue;
    }
    Deblender d{*labels, filtered, c, {}, min_piece_area, min_contrast * total, min_rise[ci],
                cv::Mat(c.height, c.width, CV_32S, cv::Scalar(0))};
    for (int k = 0; k < kLevels; ++k) d.levels.push_back(low * std::pow(peak / low, static_cast<float>(k) / kLevels));
    std::vector<std::vector<int>> leaves;
    d.Split(pix, 0, &leaves);
    if (leaves.size() < 2) {
      out.push_back(whole);
      continue;
    }
    // Flood the component's other pixels from the leaves (breadth first: nearest leaf wins).
    cv::Mat owner(c.height, c.width, CV_32S, cv::Scalar(-1));
    std::deque<int> queue;
    for (size_t k = 0; k < leaves.size(); ++k)
      for (int v : leaves[k]) owner.at<int>(v / c.width, v % c.width) = static_cast<int>(k), queue.push_back(v);
    while (!queue.empty()) {
      const int v = queue.front();
      queue.pop_front();
      const int x = v % c.width, y = v / c.width;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, w = y + dy;
          if (u < 0 || w < 0 || u >= c.width || w >= c.height || owner.at<int>(w, u) >= 0) continue;
          if (labels->at<int>(c.y + w, c.x + u) != c.label) continue;
          owner.at<int>(w, u) = owner.at<int>(y, x);
          queue.push_back(w * c.width + u);
        }
    }
    const size_t n = leaves.size();
    std::vector<Component> parts(n);
    std::vector<int> x0(n, 1 << 30), y0(n, 1 << 30), x1(n, -1), y1(n, -1);
    for (size_t k = 0; k < n; ++k) {
      parts[k].label = k == 0 ? c.label : (*next_label)++;
      parts[k].crowded = c.crowded;
      parts[k].clump = c.clump;
    }
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) {
        const int k = owner.at<int>(y, x);
        if (k < 0) continue;
        labels->at<int>(c.y + y, c.x + x) = parts[k].label;
        ++parts[k].area;
        x0[k] = std::min(x0[k], x), x1[k] = std::max(x1[k], x), y0[k] = std::min(y0[k], y), y1[k] = std::max(y1[k], y);
      }
    for (size_t k = 0; k < n; ++k) {
      parts[k].x = c.x + x0[k], parts[k].y = c.y + y0[k];
      parts[k].width = x1[k] - x0[k] + 1, parts[k].height = y1[k] - y0[k] + 1;
      out.push_back(parts[k]);
    }
  }
  return out;
}

}  // namespace platemeter::star_internal
