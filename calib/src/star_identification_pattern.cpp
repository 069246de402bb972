// Triangles of stars on the plate and in the catalog, the rotation hypotheses
// they give, and the verification of each against chance (star_identification.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <Eigen/Geometry>
#include <boost/math/distributions/poisson.hpp>
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "star_identification_internal.h"

namespace platemeter::star_identification_internal {
namespace {

constexpr int kMaxCatalogNeighbours = 40;  // 780 triangles per catalog star

double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// Vertices ordered by the length of the opposite side (shortest first); sides
// in the same order. Near-isosceles triangles (an order within the tolerance)
// are dropped: their vertex correspondence is ambiguous.
struct Triangle {
  std::array<int, 3> vertex{};
  std::array<double, 3> side{};  // side[k] is opposite vertex[k]
};

std::vector<Triangle> Triangles(const std::vector<Eigen::Vector3d>& points, int neighbours, double tolerance_rad) {
  std::set<std::array<int, 3>> seen;
  std::vector<Triangle> out;
  const int n = static_cast<int>(points.size());
  for (int i = 0; i < n; ++i) {
    std::vector<std::pair<double, int>> near;
    for (int j = 0; j < n; ++j) {
      if (j != i) near.push_back({Angle(points[i], points[j]), j});
    }
    const int k = std::min<int>(neighbours, static_cast<int>(near.size()));
    std::partial_sort(near.begin(), near.begin() + k, near.end());
    for (int a = 0; a < k; ++a) {
      for (int b = a + 1; b < k; ++b) {
        std::array<int, 3> key{i, near[a].second, near[b].second};
        std::sort(key.begin(), key.end());
        if (!seen.insert(key).second) continue;
        std::array<std::pair<double, int>, 3> opposite = {
            std::pair{Angle(points[key[1]], points[key[2]]), key[0]},
            std::pair{Angle(points[key[0]], points[key[2]]), key[1]},
            std::pair{Angle(points[key[0]], points[key[1]]), key[2]}};
        std::sort(opposite.begin(), opposite.end());
        if (opposite[1].first - opposite[0].first < 2 * tolerance_rad ||
            opposite[2].first - opposite[1].first < 2 * tolerance_rad)
          continue;
        Triangle t;
        for (int v = 0; v < 3; ++v) t.vertex[v] = opposite[v].second, t.side[v] = opposite[v].first;
        out.push_back(t);
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const Triangle& a, const Triangle& b) { return a.side[2] < b.side[2]; });
  return out;
}

struct Candidate {
  double misfit = 0.0;
  const Triangle* plate = nullptr;
  const Triangle* sky = nullptr;
};

// Chance that `matches` or more of `tried` stars fall within `tolerance_rad` of one of
// `field_count` catalog stars spread over a cap of radius `field_rad` (Poisson).
double ChanceOfMatches(int matches, int tried, int field_count, double tolerance_rad, double field_rad) {
  const double covered = std::min(1.0, field_count * (1.0 - std::cos(tolerance_rad)) / (1.0 - std::cos(field_rad)));
  const double expected = std::max(1e-12, tried * covered);
  if (matches <= 0) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::poisson_distribution<>(expected), matches - 1));
}

}  // namespace

Nearest NearestFieldStar(const std::vector<FieldStar>& field, const Eigen::Vector3d& enu) {
  std::vector<Eigen::Vector3d> directions;
  directions.reserve(field.size());
  for (const FieldStar& f : field) directions.push_back(f.enu);
  return NearestOf(directions, enu);
}

Nearest NearestOf(const std::vector<Eigen::Vector3d>& directions, const Eigen::Vector3d& enu) {
  Nearest best;
  double first = -2.0, second = -2.0;  // cosines
  for (int i = 0; i < static_cast<int>(directions.size()); ++i) {
    const double c = directions[i].dot(enu);
    if (c > first) {
      second = first;
      first = c;
      best.index = i;
    } else if (c > second) {
      second = c;
    }
  }
  best.angle_rad = std::acos(std::clamp(first, -1.0, 1.0));
  best.second_rad = std::acos(std::clamp(second, -1.0, 1.0));
  return best;
}

Hypothesis FindRotation(const std::vector<PlateStar>& stars, const std::vector<FieldStar>& field,
                        const SkyRotation& sky, const Eigen::Vector3d& axis_enu, const IdentificationOptions& options,
                        IdentificationResult* result) {
  constexpr double kDeg = M_PI / 180.0;
  const double side_tolerance = options.side_tolerance_deg * kDeg;
  std::vector<int> pattern;  // plate stars with an image within the window
  std::vector<Eigen::Vector3d> plate_points, sky_points;
  for (int s = 0; s < static_cast<int>(stars.size()); ++s) {
    if (std::abs(stars[s].dt_s[stars[s].pattern]) > options.window_s) continue;
    pattern.push_back(s);
    plate_points.push_back(stars[s].rays[stars[s].pattern]);
  }
  for (const FieldStar& f : field) sky_points.push_back(f.enu);
  if (pattern.size() < 3)
    throw Error("star identification", "fewer than 3 stars have an image near the reference epoch");
  const std::vector<Triangle> plate = Triangles(plate_points, options.neighbours, side_tolerance);
  // The pattern is a subset of the catalog (stars with an image near the
  // epoch, only the brighter ones detected): a pattern star's nearest pattern
  // neighbours are among its nearest catalog ones in proportion to the densities.
  const double density_ratio = static_cast<double>(field.size()) / static_cast<double>(pattern.size());
  const int catalog_neighbours = std::clamp(static_cast<int>(std::ceil(1.5 * options.neighbours * density_ratio)),
                                            options.neighbours + 2, kMaxCatalogNeighbours);
  const std::vector<Triangle> catalog = Triangles(sky_points, catalog_neighbours, side_tolerance);

  std::vector<Candidate> candidates;
  for (const Triangle& t : plate) {
    auto it = std::lower_bound(catalog.begin(), catalog.end(), t.side[2] - side_tolerance,
                               [](const Triangle& c, double v) { return c.side[2] < v; });
    for (; it != catalog.end() && it->side[2] <= t.side[2] + side_tolerance; ++it) {
      if (std::abs(it->side[0] - t.side[0]) > side_tolerance || std::abs(it->side[1] - t.side[1]) > side_tolerance)
        continue;
      double misfit = 0.0;
      for (int k = 0; k < 3; ++k) misfit += std::pow(it->side[k] - t.side[k], 2);
      candidates.push_back({misfit, &t, &*it});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.misfit < b.misfit; });

  double field_rad = 0.0;
  for (const FieldStar& f : field) field_rad = std::max(field_rad, Angle(f.enu, axis_enu));
  const double pointing_tolerance = options.pointing_tolerance_deg * kDeg;
  const double verify_tolerance = options.verify_tolerance_deg * kDeg;
  int off_pointing = 0, mirrored = 0;
  const double trials = static_cast<double>(std::min<size_t>(candidates.size(), options.max_hypotheses));
  for (const Candidate& c : candidates) {
    if (result->hypotheses_tried >= options.max_hypotheses) break;
    Eigen::Matrix3d from, to;
    for (int v = 0; v < 3; ++v) {
      from.col(v) = sky_points[c.sky->vertex[v]];
      to.col(v) = plate_points[c.plate->vertex[v]];
    }
    const Eigen::Matrix3d m = Eigen::umeyama(from, to, false).topLeftCorner<3, 3>();
    if (Angle(m.row(2).transpose(), axis_enu) > pointing_tolerance) { ++off_pointing; continue; }
    if ((m * from - to).colwise().norm().maxCoeff() > 2 * side_tolerance) { ++mirrored; continue; }  // a mirror image
    ++result->hypotheses_tried;
    int matches = 0;
    for (int s : pattern) {
      const PlateStar& star = stars[s];
      const Eigen::Vector3d enu = sky.Over(-star.dt_s[star.pattern]) * m.transpose() * star.rays[star.pattern];
      matches += NearestOf(sky_points, enu).angle_rad <= verify_tolerance ? 1 : 0;
    }
    const double chance = trials * ChanceOfMatches(matches, static_cast<int>(pattern.size()),
                                                   static_cast<int>(field.size()), verify_tolerance, field_rad);
    if (chance < options.false_alarm) {
      result->pattern_matches = matches;
      result->false_alarm_probability = chance;
      return {m, matches, chance};
    }
  }
  throw Error("star identification",
              fmt::format("no identification: {} hypotheses from {} plate and {} catalog triangles ({} matching "
                          "triangles, {} off the pointing, {} mirrored), none beyond chance (is the pointing within "
                          "{} deg, the principal distance and the time right?)",
                          result->hypotheses_tried, plate.size(), catalog.size(), candidates.size(), off_pointing,
                          mirrored, options.pointing_tolerance_deg));
}

}  // namespace platemeter::star_identification_internal
