// The bundle's HTML report stays readable with 100 000 residuals (issue #25):
// an aerial block of 24 frames and over 100 000 observations gives a small
// page, small plots, grids of small multiples with every frame aggregated into
// cells, in a few seconds. With PLATEMETER_REPORT_EXAMPLE_DIR set, the report
// is also written to that folder + "-100k".
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/report/bundle_html_report.h"
#include "platemeter/samples/bundle_block.h"

namespace platemeter::report {
namespace {

TEST(BundleHtmlReportLarge, HundredThousandResidualsGiveASmallReadableReport) {
  sim::AerialBlockOptions block_options;
  block_options.strips = 4;
  block_options.frames_per_strip = 6;
  block_options.points = 11000;
  block_options.point_area_extension = 0.0;
  block_options.seed = 2;
  sim::SimulatedBlock block = sim::SimulateAerialBlock(block_options);
  for (int i : {0, 1, 2, 3, 4, 6, 7}) block.input.cameras[0].states[i] = ParameterState::Free();
  BundleOptions options;
  options.adjustment.num_threads = 2;
  const BundleResult result = RunBundleAdjustment(block.input, options);
  ASSERT_GE(result.adjustment.residuals.size(), 100000u);
  ASSERT_EQ(result.frames.size(), 24u);

  const auto start = std::chrono::steady_clock::now();
  BundleReportOptions report_options;
  report_options.title = "Aerial block, 24 frames, over 100 000 observations";
  const auto files = FormatBundleHtmlReport(result, block.input, report_options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 10.0);
  size_t total = 0;
  for (const auto& [name, bytes] : files) {
    total += bytes.size();
    EXPECT_LT(bytes.size(), name == "report.html" ? 300000u : 2500000u) << name;
  }
  EXPECT_LT(total, 20000000u);
  const std::string& html = files.front().second;
  // 24 frames > 12: one grid of small multiples, every frame aggregated into cells.
  EXPECT_NE(html.find("plots/residuals-grid-001.png"), std::string::npos);
  EXPECT_EQ(html.find("plots/residuals-grid-002.png"), std::string::npos);
  EXPECT_NE(html.find("24 of these 24 frames have more than 3000 residuals"), std::string::npos);
  // The network is decimated beyond 5000 points (every 3rd of 11 000).
  EXPECT_NE(html.find("One point in 3 drawn"), std::string::npos);
  if (const char* dir = std::getenv("PLATEMETER_REPORT_EXAMPLE_DIR"); dir != nullptr && *dir) {
    WriteBundleOutputs(std::string(dir) + "-100k", result, report_options, files);
  }
}

}  // namespace
}  // namespace platemeter::report
