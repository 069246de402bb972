// Background mesh of the star detector: SExtractor's estimator per cell.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "star_internal.h"

namespace platemeter::star_internal {
namespace {

// Sigma-clipped mode (2.5 median - 1.5 mean unless the cell is crowded) and sigma.
bool CellStatistics(std::vector<float>& v, double clip_sigma, float* level, float* sigma) {
  if (v.size() < 16) return false;
  double med = 0, sd = 0, mean = 0;
  size_t n = v.size();
  const size_t start_n = n;
  for (int iteration = 0; iteration < 6; ++iteration) {
    std::nth_element(v.begin(), v.begin() + n / 2, v.begin() + n);
    med = v[n / 2];
    double s = 0, s2 = 0;
    for (size_t i = 0; i < n; ++i) s += v[i], s2 += double(v[i]) * v[i];
    mean = s / n;
    sd = std::sqrt(std::max(0.0, s2 / n - mean * mean));
    if (sd <= 0) break;
    size_t k = 0;
    for (size_t i = 0; i < n; ++i)
      if (std::abs(v[i] - med) <= clip_sigma * sd) v[k++] = v[i];
    if (k == n || k < 16) break;
    n = k;
  }
  if (n < start_n / 4) return false;
  *level = static_cast<float>(std::abs(mean - med) < 0.3 * sd ? 2.5 * med - 1.5 * mean : med);
  *sigma = static_cast<float>(sd);
  return true;
}

}  // namespace

float BackgroundMesh::LevelAt(double x_px, double y_px) const {
  const double fx = std::clamp(x_px / cell_px - 0.5 + 0.5 / cell_px, 0.0, double(nx - 1));
  const double fy = std::clamp(y_px / cell_px - 0.5 + 0.5 / cell_px, 0.0, double(ny - 1));
  const long ix = std::min<long>(long(fx), nx - 2 < 0 ? 0 : nx - 2), iy = std::min<long>(long(fy), ny - 2 < 0 ? 0 : ny - 2);
  const long ix1 = std::min(ix + 1, nx - 1), iy1 = std::min(iy + 1, ny - 1);
  const double tx = fx - ix, ty = fy - iy;
  auto at = [&](long i, long j) { return double(level_dn[j * nx + i]); };
  return static_cast<float>((1 - ty) * ((1 - tx) * at(ix, iy) + tx * at(ix1, iy)) +
                            ty * ((1 - tx) * at(ix, iy1) + tx * at(ix1, iy1)));
}

void BackgroundMesh::LevelRow(long y_px, long width_px, float* out) const {
  // The mesh interpolated to this row first, then along it.
  std::vector<float> row(nx);
  for (long i = 0; i < nx; ++i) row[i] = LevelAt((i + 0.5) * cell_px - 0.5, y_px);
  for (long x = 0; x < width_px; ++x) {
    const double fx = std::clamp(x / double(cell_px) - 0.5 + 0.5 / cell_px, 0.0, double(nx - 1));
    const long ix = std::min<long>(long(fx), nx - 2 < 0 ? 0 : nx - 2);
    const long ix1 = std::min(ix + 1, nx - 1);
    const double t = fx - ix;
    out[x] = static_cast<float>((1 - t) * row[ix] + t * row[ix1]);
  }
}

float BackgroundMesh::SigmaAt(double x_px, double y_px) const {
  const long ix = std::clamp<long>(long(x_px / cell_px), 0, nx - 1);
  const long iy = std::clamp<long>(long(y_px / cell_px), 0, ny - 1);
  return sigma_dn[iy * nx + ix];
}

BackgroundMesh ComputeBackgroundMesh(const float* values_dn, long width_px, long height_px, int cell_px,
                                     double clip_sigma, double low_dn, double high_dn) {
  BackgroundMesh mesh;
  mesh.cell_px = cell_px;
  mesh.nx = std::max<long>(1, (width_px + cell_px - 1) / cell_px);
  mesh.ny = std::max<long>(1, (height_px + cell_px - 1) / cell_px);
  const long cells = mesh.nx * mesh.ny;
  std::vector<float> level(cells, 0.f), sigma(cells, 0.f);
  std::vector<char> valid(cells, 0);
  tbb::parallel_for(0L, cells, [&](long c) {
    const long cx = c % mesh.nx, cy = c / mesh.nx;
    std::vector<float> v;
    v.reserve(size_t(cell_px) * cell_px);
    // Every other pixel in both directions: a quarter of the cost, and the
    // statistics of a 64 x 64 cell still rest on about 1000 values.
    const long step = cell_px >= 32 ? 2 : 1;
    for (long y = cy * cell_px; y < std::min(height_px, (cy + 1) * cell_px); y += step)
      for (long x = cx * cell_px; x < std::min(width_px, (cx + 1) * cell_px); x += step) {
        const float d = values_dn[y * width_px + x];
        if (d > low_dn && d < high_dn) v.push_back(d);
      }
    valid[c] = CellStatistics(v, clip_sigma, &level[c], &sigma[c]);
  });
  // Invalid cells (crowded, saturated) take the median of the valid ones.
  std::vector<float> good_level, good_sigma;
  for (long c = 0; c < cells; ++c)
    if (valid[c]) good_level.push_back(level[c]), good_sigma.push_back(sigma[c]);
  auto median = [](std::vector<float> v) {
    if (v.empty()) return 0.f;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const float fill_level = median(good_level), fill_sigma = median(good_sigma);
  for (long c = 0; c < cells; ++c)
    if (!valid[c]) level[c] = fill_level, sigma[c] = fill_sigma;
  // 3x3 median over the mesh: a bright star or a defect in one cell does not pull the map.
  mesh.level_dn.resize(cells);
  mesh.sigma_dn.resize(cells);
  for (long cy = 0; cy < mesh.ny; ++cy)
    for (long cx = 0; cx < mesh.nx; ++cx) {
      std::vector<float> a, b;
      for (long j = std::max(0L, cy - 1); j <= std::min(mesh.ny - 1, cy + 1); ++j)
        for (long i = std::max(0L, cx - 1); i <= std::min(mesh.nx - 1, cx + 1); ++i)
          a.push_back(level[j * mesh.nx + i]), b.push_back(sigma[j * mesh.nx + i]);
      mesh.level_dn[cy * mesh.nx + cx] = median(a);
      mesh.sigma_dn[cy * mesh.nx + cx] = median(b);
    }
  return mesh;
}

}  // namespace platemeter::star_internal
