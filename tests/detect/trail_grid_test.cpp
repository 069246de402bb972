// The trail linker's spatial hash (detect/src/trails/trail_internal.h, internal): every point within the radius
// and no other, wherever the query lies -- also far off the plate with a radius grown with the distance
// (a place carried along the flow beyond its images: the search must not walk the empty cells between).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "../detect/src/trails/trail_internal.h"

namespace platemeter {
namespace {

using trail_internal::Grid;

std::set<int> BruteForce(const std::vector<PixelPoint>& p, double x, double y, double r) {
  std::set<int> near;
  for (int i = 0; i < static_cast<int>(p.size()); ++i)
    if (std::hypot(p[i].x_px - x, p[i].y_px - y) <= r) near.insert(i);
  return near;
}

TEST(TrailGrid, FindsEveryPointWithinTheRadiusWhereverTheQueryLies) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> on_plate(0.0, 6000.0), anywhere(-20000.0, 26000.0), radius(0.0, 3000.0);
  std::vector<PixelPoint> p(3000);
  std::vector<int> ids;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) p[i] = {on_plate(random), on_plate(random)}, ids.push_back(i);
  const Grid grid(p, ids, 32.0);
  for (int q = 0; q < 400; ++q) {
    const double x = anywhere(random), y = anywhere(random), r = q % 4 == 0 ? radius(random) : radius(random) / 30.0;
    std::set<int> found;
    grid.Near(x, y, r, [&](int i) { EXPECT_TRUE(found.insert(i).second) << "point " << i << " reported twice"; });
    EXPECT_EQ(found, BruteForce(p, x, y, r)) << "query (" << x << ", " << y << ") r " << r;
  }
}

TEST(TrailGrid, FarOffQueriesWithGrownRadiiFindNothingAndReturn) {
  std::vector<PixelPoint> p = {{100.0, 100.0}, {5000.0, 5900.0}};
  const Grid grid(p, {0, 1}, 32.0);
  // The flow's tolerance 0.4 px + 2e-4 of the distance carried: 1e9 px away, 2e5 px (before the fix each of
  // these walked (4e5 / 32)^2 = 1.6e8 empty cells).
  int found = 0;
  for (int k = 1; k <= 50; ++k) {
    const double d = 1e9 * k;
    grid.Near(d, -d, 0.4 + 2e-4 * d, [&](int) { ++found; });
  }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  grid.Near(nan, 100.0, 10.0, [&](int) { ++found; });
  grid.Near(100.0, inf, 10.0, [&](int) { ++found; });
  EXPECT_EQ(found, 0);
  // Within reach of the plate a huge radius still finds the points.
  grid.Near(-1e5, -1e5, 2e5, [&](int) { ++found; });
  EXPECT_EQ(found, 2);
  // So does an unbounded one, from anywhere (the range is cut to the occupied cells, not refused).
  grid.Near(1e12, 1e12, std::numeric_limits<double>::infinity(), [&](int) { ++found; });
  EXPECT_EQ(found, 4);
}

TEST(TrailGrid, AnEmptyGridFindsNothing) {
  const std::vector<PixelPoint> p = {{10.0, 10.0}};
  const Grid grid(p, {}, 32.0);
  int found = 0;
  grid.Near(10.0, 10.0, 100.0, [&](int) { ++found; });
  EXPECT_EQ(found, 0);
}

}  // namespace
}  // namespace platemeter
