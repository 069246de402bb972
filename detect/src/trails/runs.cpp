// Runs of leading dashes (step 1, decoder.h): elongated images equally spaced along a line.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <unordered_map>

#include "trail_internal.h"

namespace platemeter::trail_internal {

namespace {

// With measured segments (trail-mode detection): a dash's run neighbours lie along its own direction
// (angle_deg) at 1.5 of its length, with its length. Each side takes its one candidate; two or more
// (crossing trails) link nothing on that side, and the dash is marked `open`: a run ending there could
// be longer than it looks.
void SegmentNeighbours(const Context& c, const Grid& dashes, const std::vector<int>& dash_ids,
                       std::unordered_map<int, std::vector<int>>* nb, std::unordered_map<int, bool>* open) {
  const TrailOptions& o = c.o;
  const double sin_bend = std::sin(o.tuning.max_run_bend_deg * std::numbers::pi / 180.0);
  for (int i : dash_ids) {
    const DetectedStar& di = c.images[i];
    if (di.length_px <= 0) continue;
    const double a = di.angle_deg * std::numbers::pi / 180.0, ux = std::cos(a), uy = std::sin(a);
    const double expect = 1.5 * di.length_px;
    const double along_tol = 2.0 * o.tuning.run_spacing_tolerance * expect + o.psf_fwhm_px;
    for (int side : {1, -1}) {
      int found = -1, count = 0;
      dashes.Near(c.p[i].x_px, c.p[i].y_px, expect + along_tol, [&](int j) {
        if (j == i || c.images[j].length_px <= 0) return;
        const double dx = c.p[j].x_px - c.p[i].x_px, dy = c.p[j].y_px - c.p[i].y_px;
        const double along = side * (dx * ux + dy * uy), across = std::abs(dx * uy - dy * ux);
        if (along <= 0 || std::abs(along - expect) > along_tol) return;
        if (across > std::max(0.5 * o.psf_fwhm_px, along * sin_bend)) return;
        const double dl = std::abs(c.images[j].length_px - di.length_px);
        if (dl > o.tuning.dash_length_tolerance * di.length_px + o.psf_fwhm_px + 3.0 * (di.sigma_length_px + c.images[j].sigma_length_px))
          return;
        found = j, ++count;
      });
      if (count == 1) (*nb)[i].push_back(found);
      if (count > 1) (*open)[i] = true;
    }
  }
}

}  // namespace

// Runs of leading dashes: elongated images equally spaced along a line (spatial order).
std::vector<std::vector<int>> FindRuns(const Context& c, const Grid& dashes, const std::vector<int>& dash_ids) {
  const TrailOptions& o = c.o;
  const double cos_bend = std::cos(o.tuning.max_run_bend_deg * std::numbers::pi / 180.0);
  // Each dash's two neighbours in a run: the nearest dash, and the nearest one opposite to it.
  std::unordered_map<int, std::vector<int>> nb;
  std::unordered_map<int, bool> open;
  if (c.use_lengths) SegmentNeighbours(c, dashes, dash_ids, &nb, &open);
  for (int i : dash_ids) {
    if (c.use_lengths) break;
    std::vector<std::pair<double, int>> near;
    dashes.Near(c.p[i].x_px, c.p[i].y_px, o.max_dash_spacing_px, [&](int j) {
      if (j != i) near.push_back({Dist(c.p[i], c.p[j]), j});
    });
    std::sort(near.begin(), near.end());
    if (near.empty()) continue;
    const auto [d0, a] = near[0];
    // With measured lengths the spacing is 1.5 dash lengths (30 s against 20 s).
    auto spacing_ok = [&](double d, int j) {
      if (!c.use_lengths) return true;
      const double expect = 0.75 * (c.images[i].length_px + c.images[j].length_px);
      return std::abs(d - expect) <= 2.0 * o.tuning.run_spacing_tolerance * expect + c.o.psf_fwhm_px;
    };
    if (!spacing_ok(d0, a)) continue;
    nb[i].push_back(a);
    const double ax = (c.p[a].x_px - c.p[i].x_px) / d0, ay = (c.p[a].y_px - c.p[i].y_px) / d0;
    for (size_t k = 1; k < near.size(); ++k) {
      const auto [d, b] = near[k];
      if (std::abs(d - d0) > o.tuning.run_spacing_tolerance * d0) continue;
      const double cb = (ax * (c.p[b].x_px - c.p[i].x_px) + ay * (c.p[b].y_px - c.p[i].y_px)) / d;
      if (cb <= -cos_bend && spacing_ok(d, b)) {
        nb[i].push_back(b);
        break;
      }
    }
  }
  auto mutual = [&](int i, int j) {
    auto it = nb.find(j);
    return it != nb.end() && std::find(it->second.begin(), it->second.end(), i) != it->second.end();
  };
  std::unordered_map<int, std::vector<int>> adj;
  for (const auto& [i, js] : nb)
    for (int j : js)
      if (mutual(i, j)) adj[i].push_back(j);
  std::vector<std::vector<int>> runs;
  std::unordered_map<int, bool> seen;
  for (const auto& [i, js] : adj) {
    if (js.size() != 1 || seen[i]) continue;
    std::vector<int> run{i};
    seen[i] = true;
    int prev = -1, cur = i;
    for (;;) {
      int next = -1;
      for (int j : adj[cur])
        if (j != prev && !seen[j]) next = j;
      if (next < 0) break;
      seen[next] = true;
      run.push_back(next);
      prev = cur, cur = next;
    }
    // Equal spacing along the whole run, straight.
    bool ok = true;
    std::vector<double> gaps;
    for (size_t k = 1; k < run.size(); ++k) gaps.push_back(Dist(c.p[run[k]], c.p[run[k - 1]]));
    const double mean = std::accumulate(gaps.begin(), gaps.end(), 0.0) / gaps.size();
    for (double g : gaps) ok = ok && std::abs(g - mean) <= o.tuning.run_spacing_tolerance * mean;
    // An end dash with several candidates beyond it: the run may continue through a crossing.
    ok = ok && !open[run.front()] && !open[run.back()];
    if (ok) runs.push_back(run);
  }
  return runs;
}

}  // namespace platemeter::trail_internal
