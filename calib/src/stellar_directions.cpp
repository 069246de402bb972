// Each star image's apparent direction at its mid-time (stellar_internal.h).
#include <map>
#include <utility>

#include <tbb/parallel_for.h>

#include "stellar_internal.h"

namespace platemeter::stellar_internal {
namespace {

// Finite-difference step of the catalog place: 1e-6 rad (0.2") is small against
// the curvature of the apparent-place chain and large against its round-off.
constexpr double kPlaceStep_rad = 1e-6;

calib::CatalogStar Moved(const calib::CatalogStar& star, double east_rad, double north_rad) {
  calib::CatalogStar s = star;
  s.ra_rad += east_rad / std::cos(star.dec_rad);
  s.dec_rad += north_rad;
  return s;
}

ImageDirection DirectionOf(const calib::ApparentPlaceCalculator& calculator, const calib::CatalogStar& star) {
  ImageDirection d;
  d.enu = calculator.Observe(star).enu;
  const double h = kPlaceStep_rad;
  d.d_east = (calculator.Observe(Moved(star, h, 0.0)).enu - calculator.Observe(Moved(star, -h, 0.0)).enu) / (2 * h);
  d.d_north = (calculator.Observe(Moved(star, 0.0, h)).enu - calculator.Observe(Moved(star, 0.0, -h)).enu) / (2 * h);
  return d;
}

}  // namespace

std::vector<ImageDirection> ComputeImageDirections(const calib::ApparentPlaceOptions& place,
                                                   const std::vector<const calib::CatalogStar*>& stars,
                                                   const std::vector<calib::UtcInstant>& times) {
  std::map<std::pair<double, double>, std::vector<size_t>> by_time;
  for (size_t i = 0; i < times.size(); ++i) by_time[{times[i].jd1, times[i].jd2}].push_back(i);
  std::vector<const std::vector<size_t>*> groups;
  for (const auto& [time, members] : by_time) groups.push_back(&members);
  std::vector<ImageDirection> out(stars.size());
  tbb::parallel_for(size_t{0}, groups.size(), [&](size_t g) {
    const std::vector<size_t>& members = *groups[g];
    const calib::ApparentPlaceCalculator calculator(place, times[members.front()]);
    for (size_t i : members) out[i] = DirectionOf(calculator, *stars[i]);
  });
  return out;
}

}  // namespace platemeter::stellar_internal
