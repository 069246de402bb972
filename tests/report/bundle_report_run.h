#pragma once
// One bundle run through the CLI on a small simulated block (seed 000 Table 9,
// 80 mm: 9 frames, about 1900 observations), shared by the report tests. With
// PLATEMETER_REPORT_EXAMPLE_DIR set, the outputs stay there (to look at).
#include <cstdlib>
#include <memory>
#include <string>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/samples/bundle_block.h"
#include "support/test_support.h"

namespace platemeter::testing {

struct BundleReportRun {
  std::string out;  // the output folder
  int frames = 0;
  CommandResult result;
};

inline const BundleReportRun& RunBundleForReport() {
  static const std::unique_ptr<TempDir> dir = std::make_unique<TempDir>();
  static const BundleReportRun run = [] {
    BundleReportRun r;
    sim::LunarBlockOptions options = sim::Seed000Table9Options(80.0);
    options.seed = 3;
    const sim::SimulatedBlock block = sim::SimulateLunarBlock(options);
    const std::string observations = dir->file("observations.csv");
    WriteObservationsCsv(observations, block.input.observations);
    const char* example = std::getenv("PLATEMETER_REPORT_EXAMPLE_DIR");
    r.out = example != nullptr && *example ? std::string(example) : dir->file("out");
    r.frames = static_cast<int>(block.input.frames.size());
    r.result = RunPlatemeter("calibrate bundle --quiet --observations '" + observations +
                             "' --principal-distance-mm 80.5 --free c,xp,yp,k1,k2,p1,p2 --balance-radius-mm 30 -o '" +
                             r.out + "'");
    return r;
  }();
  return run;
}

}  // namespace platemeter::testing
