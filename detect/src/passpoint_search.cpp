// Correlation search for passpoint marks (passpoint_internal.h): the template,
// its peaks, and the automatic whole-scan search in tiles.
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "masked_pixels.h"
#include "passpoint_internal.h"

namespace platemeter::internal {

int PasspointSearchFactor(const PasspointDetectorOptions& options) {
  // About 12 px across keeps the correlation cheap and the mark still resolved;
  // a ring's line must stay at least 2 px wide or it averages into a grey disk.
  int by_size = static_cast<int>(std::floor(options.diameter_px / 12.0));
  if (options.shape == MarkType::kRing) by_size = std::min(by_size, static_cast<int>(std::floor(options.line_width_px / 2.0)));
  return std::max(1, by_size);
}

namespace {

// inner < 0: a filled disk.
PasspointTemplate MakeDiskTemplate(const PasspointDetectorOptions& options, int factor, double inner) {
  const double f = factor;
  const double outer = 0.5 * options.diameter_px;
  // The mark and a ring of background a quarter diameter wide (what tells a ring from a blob).
  const double half = outer + 0.25 * options.diameter_px + 2.0 * options.blur_sigma_px + f;
  const int n = static_cast<int>(std::ceil(half / f));
  PasspointTemplate t;
  t.factor = factor;
  t.image = cv::Mat::zeros(2 * n + 1, 2 * n + 1, CV_32F);
  const int sub = 5;
  const float sign = options.dark ? -1.0f : 1.0f;
  for (int r = 0; r < t.image.rows; ++r)
    for (int c = 0; c < t.image.cols; ++c) {
      int in = 0;
      for (int j = 0; j < sub; ++j)
        for (int i = 0; i < sub; ++i) {
          // Block (c, r) covers scan offsets [(c - n) f - f/2, ... + f) around the centre.
          const double dx = (c - n + (i + 0.5) / sub - 0.5) * f, dy = (r - n + (j + 0.5) / sub - 0.5) * f;
          const double rr = std::hypot(dx, dy);
          in += rr <= outer && rr >= inner;
        }
      t.image.at<float>(r, c) = sign * static_cast<float>(in) / (sub * sub);
    }
  const double blur = options.blur_sigma_px / f;
  if (blur > 0.3) cv::GaussianBlur(t.image, t.image, cv::Size(0, 0), blur);
  t.anchor_x = t.anchor_y = n;
  return t;
}

}  // namespace

PasspointTemplate MakePasspointTemplate(const PasspointDetectorOptions& options, int factor) {
  const double outer = 0.5 * options.diameter_px;
  return MakeDiskTemplate(options, factor,
                          options.shape == MarkType::kRing ? std::max(0.0, outer - options.line_width_px) : -1.0);
}

PasspointTemplate MakeLookAlikeTemplate(const PasspointDetectorOptions& options, int factor) {
  const double outer = 0.5 * options.diameter_px;
  return MakeDiskTemplate(options, factor, options.shape == MarkType::kRing ? -1.0 : outer - 0.2 * options.diameter_px);
}

std::vector<PasspointPeak> FindPasspointPeaks(const cv::Mat& image, long x0_px, long y0_px,
                                              const PasspointTemplate& templ, double min_score,
                                              double separation_px, int max_peaks,
                                              const PasspointTemplate* look_alike) {
  std::vector<PasspointPeak> peaks;
  if (image.rows < templ.image.rows || image.cols < templ.image.cols) return peaks;
  cv::Mat score;
  cv::matchTemplate(image, templ.image, score, cv::TM_CCOEFF_NORMED);
  cv::Mat dilated;
  cv::dilate(score, dilated, cv::Mat::ones(3, 3, CV_8U));
  const double f = templ.factor;
  for (int r = 0; r < score.rows; ++r) {
    const float* s = score.ptr<float>(r);
    const float* d = dilated.ptr<float>(r);
    for (int c = 0; c < score.cols; ++c)
      if (std::isfinite(s[c]) && s[c] >= min_score && s[c] >= d[c]) {
        // Overview pixel k covers scan pixels x0 + k f .. x0 + k f + f - 1: its centre is x0 + k f + (f - 1) / 2.
        const double ox = c + templ.anchor_x, oy = r + templ.anchor_y;
        peaks.push_back({{x0_px + f * ox + 0.5 * (f - 1), y0_px + f * oy + 0.5 * (f - 1)}, s[c], -1.0});
      }
  }
  std::sort(peaks.begin(), peaks.end(), [](const PasspointPeak& a, const PasspointPeak& b) {
    if (a.score != b.score) return a.score > b.score;
    return a.position_px.y_px != b.position_px.y_px ? a.position_px.y_px < b.position_px.y_px
                                                    : a.position_px.x_px < b.position_px.x_px;
  });
  std::vector<PasspointPeak> kept;
  for (const PasspointPeak& p : peaks) {
    if (static_cast<int>(kept.size()) >= max_peaks) break;
    bool close = false;
    for (const PasspointPeak& k : kept)
      close = close || std::hypot(p.position_px.x_px - k.position_px.x_px, p.position_px.y_px - k.position_px.y_px) < separation_px;
    if (!close) kept.push_back(p);
  }
  if (look_alike) {
    // Both templates are centred (odd, same centre): compare them at the peak and its 8 neighbours.
    const int dc = static_cast<int>(look_alike->anchor_x - templ.anchor_x);
    for (PasspointPeak& p : kept) {
      const int c = static_cast<int>(std::lround((p.position_px.x_px - x0_px - 0.5 * (f - 1)) / f - templ.anchor_x)) - dc;
      const int r = static_cast<int>(std::lround((p.position_px.y_px - y0_px - 0.5 * (f - 1)) / f - templ.anchor_y)) - dc;
      const cv::Rect roi(c - 1, r - 1, look_alike->image.cols + 2, look_alike->image.rows + 2);
      const cv::Rect inside = roi & cv::Rect(0, 0, image.cols, image.rows);
      if (inside.width < look_alike->image.cols || inside.height < look_alike->image.rows) continue;
      cv::Mat other;
      cv::matchTemplate(image(inside), look_alike->image, other, cv::TM_CCOEFF_NORMED);
      double best = -1.0;
      cv::minMaxLoc(other, nullptr, &best);
      p.look_alike_score = best;
    }
  }
  return kept;
}

bool InPasspointMask(const std::vector<PasspointMask>& mask, const PixelPoint& p) {
  for (const PasspointMask& m : mask) {
    const double ux = m.b_px.x_px - m.a_px.x_px, uy = m.b_px.y_px - m.a_px.y_px;
    const double len2 = ux * ux + uy * uy;
    double t = len2 > 0.0 ? ((p.x_px - m.a_px.x_px) * ux + (p.y_px - m.a_px.y_px) * uy) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double dx = p.x_px - (m.a_px.x_px + t * ux), dy = p.y_px - (m.a_px.y_px + t * uy);
    if (dx * dx + dy * dy <= m.radius_px * m.radius_px) return true;
  }
  return false;
}

std::vector<PasspointPeak> SearchWholeScan(const Image& image, const PasspointDetectorOptions& options, int* tiles,
                                           int* masked) {
  const int factor = PasspointSearchFactor(options);
  const PasspointTemplate templ = MakePasspointTemplate(options, factor);
  const PasspointTemplate look_alike = MakeLookAlikeTemplate(options, factor);
  const PixelRect bounds = image.Bounds();
  // Tiles a whole number of blocks wide; each read with one template's overlap
  // so a mark on a tile border is seen whole by the tile that owns its centre.
  const long tile = std::max<long>(factor, options.tile_px / factor * factor);
  const long overlap = static_cast<long>(templ.image.cols) * factor;
  const long nx = (bounds.width_px + tile - 1) / tile, ny = (bounds.height_px + tile - 1) / tile;
  *tiles = static_cast<int>(nx * ny);
  std::vector<std::vector<PasspointPeak>> found(static_cast<size_t>(nx * ny));
  std::vector<int> masked_per_tile(static_cast<size_t>(nx * ny), 0);
  const double separation = 0.5 * options.diameter_px;
  tbb::parallel_for(0L, nx * ny, [&](long k) {
    const long tx = k % nx, ty = k / nx;
    const PixelRect core{tx * tile, ty * tile, std::min(tile, bounds.width_px - tx * tile),
                         std::min(tile, bounds.height_px - ty * tile)};
    // The window starts a whole number of blocks before the core (blocks stay aligned with the core's).
    const long x0 = std::max(0L, core.x0_px - overlap), y0 = std::max(0L, core.y0_px - overlap);
    const long x1 = std::min(bounds.width_px, core.x_end_px() + overlap);
    const long y1 = std::min(bounds.height_px, core.y_end_px() + overlap);
    const long bw = (x1 - x0) / factor, bh = (y1 - y0) / factor;
    if (bw < templ.image.cols || bh < templ.image.rows) return;
    ImageWindow window = image.ReadWindow({x0, y0, bw * factor, bh * factor});
    detect_internal::FillMaskedWithMedian(window.values_dn.data(), window.values_dn.size());
    cv::Mat blocks(static_cast<int>(bh), static_cast<int>(bw), CV_32F);
    if (factor == 1) {
      std::copy(window.values_dn.begin(), window.values_dn.end(), blocks.ptr<float>(0));
    } else {
      const double norm = 1.0 / (static_cast<double>(factor) * factor);
      for (long r = 0; r < bh; ++r) {
        float* out = blocks.ptr<float>(static_cast<int>(r));
        std::fill(out, out + bw, 0.0f);
        std::vector<double> sums(static_cast<size_t>(bw), 0.0);
        for (long j = 0; j < factor; ++j) {
          const float* row = window.values_dn.data() + (r * factor + j) * window.rect.width_px;
          for (long x = 0; x < bw * factor; ++x) sums[static_cast<size_t>(x / factor)] += row[x];
        }
        for (long c = 0; c < bw; ++c) out[c] = static_cast<float>(sums[static_cast<size_t>(c)] * norm);
      }
    }
    for (const PasspointPeak& p : FindPasspointPeaks(blocks, x0, y0, templ, options.min_search_score, separation,
                                                     options.max_candidates_per_tile, &look_alike)) {
      // Owned by the tile whose core holds the centre (pixel centres at integers: core edges at -0.5).
      const bool owned = p.position_px.x_px >= core.x0_px - 0.5 && p.position_px.x_px < core.x_end_px() - 0.5 &&
                         p.position_px.y_px >= core.y0_px - 0.5 && p.position_px.y_px < core.y_end_px() - 0.5;
      if (!owned) continue;
      if (InPasspointMask(options.mask, p.position_px)) {
        ++masked_per_tile[static_cast<size_t>(k)];
        continue;
      }
      found[static_cast<size_t>(k)].push_back(p);
    }
  });
  std::vector<PasspointPeak> all;
  *masked = 0;
  for (size_t k = 0; k < found.size(); ++k) {
    all.insert(all.end(), found[k].begin(), found[k].end());
    *masked += masked_per_tile[k];
  }
  return all;
}

}  // namespace platemeter::internal
