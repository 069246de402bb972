#pragma once
// One stellar calibration through the CLI on two simulated Orbigon plates
// (North and South, seed 001's trails and selection), combined, shared by the
// report tests; the true camera kept for the checks. With
// PLATEMETER_STELLAR_REPORT_EXAMPLE_DIR set, the outputs stay there (to look at).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <tuple>

#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"
#include "support/test_support.h"

namespace platemeter::testing {

struct StellarReportRun {
  std::string out;      // the output folder
  StellarCamera truth;  // plate frame
  CommandResult result;
};

inline const StellarReportRun& RunStellarForReport() {
  static const std::unique_ptr<TempDir> dir = std::make_unique<TempDir>();
  static const StellarReportRun run = [] {
    StellarReportRun r;
    const DefinitionRegistry registry;
    std::string plates;
    for (const auto& [id, start, roll, seed] : {std::tuple{"N", "1972-05-12T05:30:00Z", 0.0, 31},
                                                std::tuple{"S", "1972-04-09T06:10:00Z", 180.0, 32}}) {
      sim::StellarPlateSimulation s = BeltsvillePlate(id, start, roll);
      s.field.place.pressure_hpa = 1013.25 * std::exp(-50.0 / (29.3 * (273.15 + 10.0)));  // the job's default
      const sim::StellarTruthPlate truth = sim::SimulateStellarTruth(s, registry.Camera("orbigon"));
      r.truth = truth.camera;
      const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = static_cast<uint64_t>(seed)});
      const std::string path = dir->file(std::string(id) + ".csv");
      sim::WriteStellarMeasurementFile(noisy.plate, path, true);
      plates += "[[plate]]\nid = \"" + std::string(id) + "\"\nmeasurements = \"" + path +
                "\"\naxis_azimuth_deg = 120\naxis_altitude_deg = 86\n";
    }
    const std::string job = dir->file("job.toml");
    std::ofstream(job) << "title = \"two simulated Orbigon plates\"\ncamera = \"orbigon\"\n"
                       << "[site]\nlatitude_deg = 39.03\nlongitude_deg = -76.93\nheight_m = 50\n"
                       << plates;
    const char* example = std::getenv("PLATEMETER_STELLAR_REPORT_EXAMPLE_DIR");
    r.out = example != nullptr && *example ? std::string(example) : dir->file("out");
    r.result = RunPlatemeter("calibrate stellar --quiet '" + job + "' -o '" + r.out + "'");
    return r;
  }();
  return run;
}

}  // namespace platemeter::testing
