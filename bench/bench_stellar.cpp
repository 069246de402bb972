// Stellar calibration speed (issue #24): one plate of seed 001's size (about
// 2400 images) adjusted, and six plates (three apertures, North and South)
// combined by the weighted mean; wall times and peak RSS. The combination is
// also timed against the grand simultaneous adjustment of the same six plates
// run by the engine in the same program (the peer it replaces: Ceres over all
// observations at once).
//
//   build/bench/bench_stellar [--threads N]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include <sys/resource.h>

#include "platemeter/calib/stellar_combination.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"

using namespace platemeter;

namespace {

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 0;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--threads") == 0) threads = std::atoi(argv[i + 1]);
  }
  const DefinitionRegistry registry;
  const char* starts[6] = {"1972-03-25T04:00:00Z", "1972-05-12T05:30:00Z", "1972-05-12T02:10:00Z",
                           "1972-04-09T06:10:00Z", "1972-04-18T03:00:00Z", "1972-04-09T02:30:00Z"};
  std::vector<StellarPlate> plates;
  StellarCatalog catalog;
  const auto simulate_start = std::chrono::steady_clock::now();
  for (int p = 0; p < 6; ++p) {
    sim::StellarPlateSimulation s;
    s.plate_id = "P" + std::to_string(p + 1);
    s.group = p < 2 ? "f/3.5" : p < 4 ? "f/4" : "f/5.6";
    constexpr double kDeg = M_PI / 180.0;
    s.field.place.site = {39.03 * kDeg, -76.93 * kDeg, 50.0};
    s.field.start_utc = calib::ParseUtcIso8601(starts[p]);
    s.field.roll_deg = p % 2 == 0 ? 0.0 : 180.0;
    const sim::NoisyStellarPlate noisy =
        sim::Noisy(sim::SimulateStellarTruth(s, registry.Camera("orbigon")), {.seed = static_cast<uint64_t>(p + 1)});
    plates.push_back(noisy.plate);
    catalog.insert(noisy.catalog.begin(), noisy.catalog.end());
  }
  std::printf("simulated 6 plates in %.1f s\n", Seconds(simulate_start));
  StellarOptions options;
  options.adjustment.num_threads = threads;
  std::vector<StellarPlateResult> singles;
  for (const StellarPlate& plate : plates) {
    const auto start = std::chrono::steady_clock::now();
    singles.push_back(RunStellarPlate(plate, catalog, NominalStellarCamera(80.2), options));
    const StellarPlateResult& r = singles.back();
    std::printf("plate %s: %d images of %d stars, %.2f s (solve %.2f s, covariance %.2f s), m_o %.3f\n",
                r.plate_id.c_str(), r.images, r.catalog_stars, Seconds(start), r.adjustment.solve_seconds,
                r.adjustment.covariance_seconds, r.m_o);
  }
  const auto combine_start = std::chrono::steady_clock::now();
  const StellarCombination c = CombineStellarPlates("six plates", plates, singles, catalog, options);
  const double combine_s = Seconds(combine_start);
  const auto simultaneous_start = std::chrono::steady_clock::now();
  const AdjustmentResult simultaneous =
      SolveStellarPlatesSimultaneously(plates, catalog, NominalStellarCamera(80.2), options);
  const double simultaneous_s = Seconds(simultaneous_start);
  std::printf("six-plate weighted mean: %.2f s (%d relinearizations), m_0 %.3f with %.0f dof\n", combine_s,
              c.relinearizations, c.m_0, c.dof);
  std::printf("simultaneous adjustment of the same plates (engine, Ceres): %.2f s, sigma0 %.3f with %.0f dof\n",
              simultaneous_s, simultaneous.sigma0, simultaneous.dof);
  std::printf("ratio simultaneous / weighted mean: %.1f x; peak RSS %.0f MB\n", simultaneous_s / combine_s,
              PeakRssMb());
  return 0;
}
