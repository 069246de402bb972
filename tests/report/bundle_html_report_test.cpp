// The bundle's HTML report end to end: `platemeter calibrate bundle` writes
// report.html and every plot it links (whole PNGs of the stated size, SVGs),
// the tables carry report.md's numbers, and many frames become small multiples.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>

#include "bundle_report_run.h"
#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/core/markup.h"
#include "platemeter/report/bundle_html_report.h"
#include "report_files.h"

namespace platemeter::report {
namespace {

namespace fs = std::filesystem;

TEST(BundleHtmlReport, CalibrateBundleWritesThePageAndEveryPlotItLinks) {
  const testing::BundleReportRun& run = testing::RunBundleForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err << run.result.out;
  const std::string html = testing::ReadTextFile(run.out + "/report.html");
  ASSERT_FALSE(html.empty());
  const std::vector<std::string> links = testing::LinkedFiles(html);
  std::set<std::string> linked(links.begin(), links.end());
  int pngs = 0, svgs = 0, residual_plots = 0;
  for (const std::string& link : linked) {
    EXPECT_EQ(link.find("://"), std::string::npos) << "not relative: " << link;
    const std::string path = run.out + "/" + link;
    ASSERT_TRUE(fs::exists(path)) << link;
    const std::string bytes = testing::ReadTextFile(path);
    if (link.ends_with(".html")) {
      EXPECT_EQ(link, "certificate.html");  // the one page besides the report
      continue;
    }
    if (link.ends_with(".png")) {
      ++pngs;
      const testing::PngSize size = testing::ReadPngSize(bytes);
      EXPECT_TRUE(size.valid) << link;
      // The page states each picture's size: the PNG's own.
      EXPECT_EQ(testing::AttributeOfImage(html, link, "width"), std::to_string(size.width)) << link;
      EXPECT_EQ(testing::AttributeOfImage(html, link, "height"), std::to_string(size.height)) << link;
      if (link.starts_with("plots/residuals-")) ++residual_plots;
    } else {
      ASSERT_TRUE(link.ends_with(".svg")) << link;
      ++svgs;
      EXPECT_TRUE(testing::IsSvg(bytes)) << link;
    }
  }
  EXPECT_EQ(pngs, svgs);  // every PNG with its SVG
  EXPECT_EQ(residual_plots, run.frames);  // one residual plot per frame (9 <= 12)
  // Every plot kind of issue #25.
  for (const char* stem : {"network-plan", "network-side", "rays-per-point", "correlation-camera",
                           "profile-radial-camera", "profile-decentering-camera", "distortion-field-camera",
                           "residual-histogram-x", "residual-histogram-y"}) {
    EXPECT_TRUE(linked.count(std::string("plots/") + stem + ".png")) << stem;
  }
  // No plot file that the page does not link.
  for (const auto& entry : fs::directory_iterator(run.out + "/plots")) {
    EXPECT_TRUE(linked.count("plots/" + entry.path().filename().string())) << entry.path();
  }
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

// Every table cell of report.md is a cell of report.html: one document, two renderings.
TEST(BundleHtmlReport, TablesCarryReportMdsNumbers) {
  const testing::BundleReportRun& run = testing::RunBundleForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err;
  const std::string html = testing::ReadTextFile(run.out + "/report.html");
  const std::string markdown = testing::ReadTextFile(run.out + "/report.md");
  ASSERT_NE(markdown.find("Calibration constants"), std::string::npos);
  ASSERT_NE(markdown.find("Balanced symmetric radial"), std::string::npos);
  std::istringstream lines(markdown);
  std::string line;
  int cells = 0;
  while (std::getline(lines, line)) {
    if (!line.starts_with("| ") ) continue;
    size_t start = 2;
    for (size_t bar = line.find(" |", start); bar != std::string::npos; bar = line.find(" |", start)) {
      const std::string cell = line.substr(start, bar - start);
      start = bar + 3;
      if (cell.empty()) continue;
      ++cells;
      EXPECT_NE(html.find(">" + EscapeMarkup(cell) + "</t"), std::string::npos) << cell;
    }
  }
  EXPECT_GT(cells, 200);
  EXPECT_NE(html.find("<h2>Calibration constants, camera camera (seed 000 Table 1 form)</h2>"), std::string::npos);
}

TEST(BundleHtmlReport, ManyFramesBecomeGridsOfSmallMultiples) {
  sim::LunarBlockOptions block_options = sim::Seed000Table9Options(80.0);
  block_options.seed = 5;
  sim::SimulatedBlock block = sim::SimulateLunarBlock(block_options);
  for (int i : {0, 1, 2, 3, 4, 6, 7}) block.input.cameras[0].states[i] = ParameterState::Free();
  const BundleResult result = RunBundleAdjustment(block.input, BundleOptions{});
  BundleHtmlOptions options;
  options.max_frame_plots = 4;
  options.frames_per_grid = 4;
  const auto files = FormatBundleHtmlReport(result, block.input, BundleReportOptions{}, options);
  std::set<std::string> names;
  for (const auto& [name, bytes] : files) names.insert(name);
  // 9 frames in grids of 4: 4 + 4 + 1.
  for (const char* grid : {"plots/residuals-grid-001.png", "plots/residuals-grid-002.png", "plots/residuals-grid-003.png"}) {
    EXPECT_TRUE(names.count(grid)) << grid;
  }
  EXPECT_FALSE(names.count("plots/residuals-grid-004.png"));
  for (const std::string& name : names) EXPECT_FALSE(name.starts_with("plots/residuals-0")) << name;
  EXPECT_EQ(files.front().first, "report.html");
}

}  // namespace
}  // namespace platemeter::report
