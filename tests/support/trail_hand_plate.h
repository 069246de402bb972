#pragma once
// The trail decoder's internal context over images built by hand, with a uniform flow fitted over the plate
// (tests of detect/src/trails internals: trail_reading_places_test, trail_merged_seed_test).
#include <numeric>
#include <vector>

#include "../detect/src/trails/trail_internal.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/detect/sky_flow.h"

namespace platemeter::test {

struct HandContext {
  TrailOptions o;
  trail_internal::Context c;
  std::vector<int> ids;
  trail_internal::Grid all;
  SkyFlow flow;
  bool flow_ok = false;

  // Every image usable, none elongated-rejected; lengths are used; the schedule's exposures per trail.
  HandContext(const std::vector<DetectedStar>& images, const std::vector<ShutterExposure>& schedule, double fwhm_px,
              const PixelPoint& velocity_px_per_s)
      : o(Options(fwhm_px)), c{images, o, {}, {}, {}, true, {}, {}, nullptr}, ids(Ids(images.size())), all(Points(), ids, 32.0) {
    c.per_trail.resize(schedule.empty() ? 0 : schedule.back().trail);  // (trails numbered 1.. in time order)
    for (const ShutterExposure& e : schedule) c.per_trail[e.trail - 1].push_back(e);
    c.usable.assign(images.size(), true);
    c.elongated.assign(images.size(), false);
    std::vector<PixelPoint> p, v;
    for (double x = 0; x <= 6000; x += 1000)
      for (double y = 0; y <= 6000; y += 1000) p.push_back({x, y}), v.push_back(velocity_px_per_s);
    flow_ok = flow.Fit(p, v, 1);
  }
  HandContext(const HandContext&) = delete;  // (the grid refers to c.p)
  HandContext& operator=(const HandContext&) = delete;

 private:
  static TrailOptions Options(double fwhm_px) {
    TrailOptions o;
    o.psf_fwhm_px = fwhm_px;
    return o;
  }
  static std::vector<int> Ids(size_t n) {
    std::vector<int> ids(n);
    std::iota(ids.begin(), ids.end(), 0);
    return ids;
  }
  const std::vector<PixelPoint>& Points() {  // c.p filled before the grid is built on it
    for (const DetectedStar& d : c.images) c.p.push_back(d.point.position_px);
    return c.p;
  }
};

}  // namespace platemeter::test
