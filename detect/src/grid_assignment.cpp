#include "platemeter/detect/grid_assignment.h"
#include "orientation_matrix.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <numbers>

namespace platemeter {
namespace {


// Candidates bucketed on a square grid of cell `cell_px`, for nearest-within-radius queries.
class CandidateIndex {
 public:
  CandidateIndex(const std::vector<CrossCandidate>& candidates, const std::vector<int>& members, double cell_px)
      : candidates_(candidates), cell_px_(cell_px) {
    for (int index : members) buckets_[Key(candidates[index].position_px.x_px, candidates[index].position_px.y_px)].push_back(index);
  }
  // Nearest member within radius_px of (x, y), or -1.
  int Nearest(double x, double y, double radius_px) const {
    const long cx = Cell(x), cy = Cell(y);
    int best = -1;
    double best_d2 = radius_px * radius_px;
    for (long dy = -1; dy <= 1; ++dy) {
      for (long dx = -1; dx <= 1; ++dx) {
        const auto it = buckets_.find(Pack(cx + dx, cy + dy));
        if (it == buckets_.end()) continue;
        for (int index : it->second) {
          const double ex = candidates_[index].position_px.x_px - x, ey = candidates_[index].position_px.y_px - y;
          const double d2 = ex * ex + ey * ey;
          if (d2 <= best_d2) {
            best_d2 = d2;
            best = index;
          }
        }
      }
    }
    return best;
  }

 private:
  long Cell(double v) const { return static_cast<long>(std::floor(v / cell_px_)); }
  static long long Pack(long cx, long cy) { return (static_cast<long long>(cx) << 32) ^ static_cast<unsigned long>(cy & 0xffffffff); }
  long long Key(double x, double y) const { return Pack(Cell(x), Cell(y)); }
  const std::vector<CrossCandidate>& candidates_;
  double cell_px_;
  std::unordered_map<long long, std::vector<int>> buckets_;
};

double MedianNearestNeighbourMm(const MasterGrid& grid) {
  std::vector<double> distances;
  for (const GridPoint& p : grid.points) {
    double best = 1e300;
    for (const GridPoint& q : grid.points) {
      if (&p == &q) continue;
      best = std::min(best, std::hypot(p.x_mm - q.x_mm, p.y_mm - q.y_mm));
    }
    distances.push_back(best);
  }
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
  return distances[distances.size() / 2];
}

struct Lattice {
  bool found = false;
  double rotation_rad = 0.0;  // in (-pi/4, pi/4]
  double scale_px_per_mm = 0.0;
};

// The lattice's rotation (mod 90 deg) and scale from the vectors between
// neighbouring candidates whose length fits the grid spacing.
Lattice MeasureLattice(const std::vector<CrossCandidate>& candidates, const std::vector<int>& members,
                       double spacing_mm, const GridAssignmentOptions& options) {
  const double nominal = 1000.0 / options.pixel_size_um * spacing_mm;
  const double low = nominal * (1 - options.scale_tolerance), high = nominal * (1 + options.scale_tolerance);
  std::vector<double> angles, lengths;
  for (int i : members) {
    for (int j : members) {
      if (j <= i) continue;
      const double dx = candidates[j].position_px.x_px - candidates[i].position_px.x_px;
      const double dy = candidates[j].position_px.y_px - candidates[i].position_px.y_px;
      const double d = std::hypot(dx, dy);
      if (d < low || d > high) continue;
      angles.push_back(std::atan2(dy, dx));
      lengths.push_back(d);
    }
  }
  Lattice lattice;
  if (angles.size() < 2) return lattice;
  // Histogram of 4 * angle (axes are 90-degree symmetric), quarter-degree bins, peak then local mean.
  const int bins = 1440;
  std::vector<double> histogram(bins, 0.0);
  for (double a : angles) {
    double w = std::fmod(4 * a, 2 * std::numbers::pi);
    if (w < 0) w += 2 * std::numbers::pi;
    histogram[static_cast<int>(w / (2 * std::numbers::pi) * bins) % bins] += 1.0;
  }
  int peak = 0;
  double peak_value = -1;
  for (int b = 0; b < bins; ++b) {
    double v = 0;
    for (int k = -4; k <= 4; ++k) v += histogram[(b + k + bins) % bins];
    if (v > peak_value) {
      peak_value = v;
      peak = b;
    }
  }
  const double peak_angle = (peak + 0.5) / bins * 2 * std::numbers::pi;
  double sum_sin = 0, sum_cos = 0;
  std::vector<double> kept_lengths;
  for (size_t i = 0; i < angles.size(); ++i) {
    const double w = 4 * angles[i];
    if (std::cos(w - peak_angle) > std::cos(4.0 * std::numbers::pi / 180.0)) {  // within 1 degree of the peak
      sum_sin += std::sin(w);
      sum_cos += std::cos(w);
      kept_lengths.push_back(lengths[i]);
    }
  }
  if (kept_lengths.size() < 2) return lattice;
  lattice.rotation_rad = std::atan2(sum_sin, sum_cos) / 4;
  std::nth_element(kept_lengths.begin(), kept_lengths.begin() + kept_lengths.size() / 2, kept_lengths.end());
  lattice.scale_px_per_mm = kept_lengths[kept_lengths.size() / 2] / spacing_mm;
  lattice.found = true;
  return lattice;
}

// Matches every grid point to its nearest candidate within the radius.
int MatchAll(const MasterGrid& grid, const PlateToPixel& transform, const CandidateIndex& index, double radius_px,
             std::vector<int>* candidate_of_point) {
  candidate_of_point->assign(grid.points.size(), -1);
  int matched = 0;
  for (size_t g = 0; g < grid.points.size(); ++g) {
    const PixelPoint p = transform.Apply(grid.points[g].x_mm, grid.points[g].y_mm);
    const int c = index.Nearest(p.x_px, p.y_px, radius_px);
    (*candidate_of_point)[g] = c;
    matched += c >= 0;
  }
  return matched;
}

// Least-squares similarity (with the orientation's fixed axis map) on the matched pairs.
bool FitSimilarity(const MasterGrid& grid, const std::vector<CrossCandidate>& candidates,
                   const std::vector<int>& candidate_of_point, const Eigen::Matrix2d& orientation,
                   PlateToPixel* transform, double* rms_px) {
  std::vector<int> points;
  for (size_t g = 0; g < candidate_of_point.size(); ++g)
    if (candidate_of_point[g] >= 0) points.push_back(static_cast<int>(g));
  if (points.size() < 2) return false;
  Eigen::Matrix2Xd from(2, points.size()), to(2, points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    from.col(k) = orientation * Eigen::Vector2d(grid.points[points[k]].x_mm, grid.points[points[k]].y_mm);
    const CrossCandidate& c = candidates[candidate_of_point[points[k]]];
    to.col(k) = Eigen::Vector2d(c.position_px.x_px, c.position_px.y_px);
  }
  const Eigen::Matrix3d similarity = Eigen::umeyama(from, to, true);
  const Eigen::Matrix2d a = similarity.topLeftCorner<2, 2>() * orientation;
  transform->a[0] = a(0, 0);
  transform->a[1] = a(0, 1);
  transform->a[2] = a(1, 0);
  transform->a[3] = a(1, 1);
  transform->t[0] = similarity(0, 2);
  transform->t[1] = similarity(1, 2);
  double sum = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const PixelPoint p = transform->Apply(grid.points[points[k]].x_mm, grid.points[points[k]].y_mm);
    sum += std::pow(p.x_px - to(0, k), 2) + std::pow(p.y_px - to(1, k), 2);
  }
  *rms_px = std::sqrt(sum / points.size());
  return true;
}

}  // namespace

bool GridAssignmentOptions::Check(std::string* why) const {
  if (!(pixel_size_um > 0.0)) return *why = "the scan's pixel size must be given", false;
  if (!(scale_tolerance > 0.0 && scale_tolerance < 0.5)) return *why = "scale_tolerance must be in (0, 0.5)", false;
  if (!(max_rotation_deg >= 0.0 && max_rotation_deg < 45.0)) return *why = "max_rotation_deg must be in [0, 45)", false;
  if (!(match_fraction > 0.0 && match_fraction < 0.5)) return *why = "match_fraction must be in (0, 0.5)", false;
  if (hypothesis_candidates < 1) return *why = "hypothesis_candidates must be positive", false;
  return true;
}

GridAssignment AssignGrid(const std::vector<CrossCandidate>& candidates, const MasterGrid& grid,
                          const GridAssignmentOptions& options) {
  GridAssignment result;
  if (grid.points.size() < 4) {
    result.summary = "the grid has fewer than 4 points";
    return result;
  }
  const double spacing_mm = MedianNearestNeighbourMm(grid);
  const std::vector<ScanOrientation> orientations =
      options.orientation ? std::vector<ScanOrientation>{*options.orientation} : ScanOrientation::All();
  std::vector<GridHypothesis> bests;
  for (int polarity : {-1, +1}) {
    std::vector<int> members;
    for (size_t i = 0; i < candidates.size(); ++i)
      if ((candidates[i].score < 0 ? -1 : 1) == polarity) members.push_back(static_cast<int>(i));
    if (members.size() < 2) continue;
    const Lattice lattice = MeasureLattice(candidates, members, spacing_mm, options);
    if (!lattice.found) continue;
    const double radius_px = options.match_fraction * spacing_mm * lattice.scale_px_per_mm;
    const CandidateIndex index(candidates, members, radius_px);
    const Eigen::Rotation2Dd scanner(lattice.rotation_rad);
    const int seeds = std::min<int>(options.hypothesis_candidates, static_cast<int>(members.size()));
    for (const ScanOrientation& orientation : orientations) {
      const Eigen::Matrix2d o = detect_internal::OrientationMatrix(orientation);
      const Eigen::Matrix2d a = lattice.scale_px_per_mm * scanner.toRotationMatrix() * o;
      GridHypothesis best;
      best.orientation = orientation;
      best.polarity = polarity;
      std::vector<int> matches;
      for (int s = 0; s < seeds; ++s) {
        const CrossCandidate& seed = candidates[members[s]];
        for (const GridPoint& g : grid.points) {
          PlateToPixel transform;
          transform.a[0] = a(0, 0);
          transform.a[1] = a(0, 1);
          transform.a[2] = a(1, 0);
          transform.a[3] = a(1, 1);
          transform.t[0] = seed.position_px.x_px - (a(0, 0) * g.x_mm + a(0, 1) * g.y_mm);
          transform.t[1] = seed.position_px.y_px - (a(1, 0) * g.x_mm + a(1, 1) * g.y_mm);
          const int matched = MatchAll(grid, transform, index, radius_px, &matches);
          if (matched > best.matched) {
            best.matched = matched;
            best.plate_to_pixel = transform;
            best.candidate_of_point = matches;
          }
        }
      }
      if (best.matched < 3) continue;
      // Refine: least-squares similarity, re-match with half the radius, twice.
      for (int round = 0; round < 2; ++round) {
        if (!FitSimilarity(grid, candidates, best.candidate_of_point, o, &best.plate_to_pixel, &best.rms_px)) break;
        best.matched = MatchAll(grid, best.plate_to_pixel, index, 0.5 * radius_px, &best.candidate_of_point);
      }
      FitSimilarity(grid, candidates, best.candidate_of_point, o, &best.plate_to_pixel, &best.rms_px);
      bests.push_back(best);
    }
    if (bests.empty()) continue;
    result.lattice_rotation_deg = lattice.rotation_rad * 180 / std::numbers::pi;
    result.lattice_scale_px_per_mm = lattice.scale_px_per_mm;
  }
  if (bests.empty()) {
    result.summary = "no arrangement of the grid fits the cross candidates (wrong grid, pixel size or no crosses)";
    return result;
  }
  std::sort(bests.begin(), bests.end(), [](const GridHypothesis& x, const GridHypothesis& y) {
    return x.matched != y.matched ? x.matched > y.matched : x.rms_px < y.rms_px;
  });
  const GridHypothesis& top = bests.front();
  for (const GridHypothesis& h : bests) {
    if (h.polarity == top.polarity && h.matched >= options.tie_fraction * top.matched) result.hypotheses.push_back(h);
  }
  result.found = true;
  std::ostringstream summary;
  summary << top.matched << " of " << grid.points.size() << " grid points matched ("
          << (top.polarity < 0 ? "dark" : "bright") << " crosses, orientation " << top.orientation.Name()
          << ", rms " << top.rms_px << " px)";
  if (result.hypotheses.size() > 1) summary << "; " << result.hypotheses.size() - 1 << " other orientation(s) fit as well";
  result.summary = summary.str();
  return result;
}

}  // namespace platemeter
