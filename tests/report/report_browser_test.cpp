// The HTML report in a real browser (issue #25): headless Chromium (Debian
// `chromium`, installed by scripts/setup) opens report.html, writes a
// screenshot, logs no console message, and every image -- the PNGs shown and
// the SVGs linked -- decodes (naturalWidth > 0). The report has no script: the
// image check runs on a copy of the page with a probe added, and a copy with a
// broken image shows that the probe and the console check can fail.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <sys/wait.h>

#include "bundle_report_run.h"
#include "support/browser.h"
#include "stellar_report_run.h"
#include "png_pixels.h"
#include "report_files.h"

namespace platemeter::report {
namespace {

namespace fs = std::filesystem;
using testing::CheckPageInChromium;
using testing::FindChromium;
using testing::ProbeResult;
using testing::ReadProbe;
using testing::RunChromium;
using testing::WriteProbePage;
using testing::ConsoleLines;
using testing::BrowserRun;

TEST(ReportBrowser, ChromiumShowsTheBundleReportAndCertificate) {
  if (FindChromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
  const testing::BundleReportRun& run = testing::RunBundleForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err;
  CheckPageInChromium(run.out, "report.html", 18, 4000);
  CheckPageInChromium(run.out, "certificate.html", 0, 1400);
}

TEST(ReportBrowser, ChromiumShowsTheStellarReportAndCertificate) {
  if (FindChromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
  const testing::StellarReportRun& run = testing::RunStellarForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err;
  CheckPageInChromium(run.out, "report.html", 23, 4000);  // seed 001 Table 4 for 2 plates and their mean
  CheckPageInChromium(run.out, "certificate.html", 0, 1400);
}

// The checks above can fail: a missing image is found by the probe and logged.
TEST(ReportBrowser, TheProbeFindsABrokenImage) {
  if (FindChromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
  const testing::BundleReportRun& run = testing::RunBundleForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err;
  const std::string html = testing::ReadTextFile(run.out + "/report.html");
  const std::string probe_page =
      WriteProbePage(fs::absolute(run.out).string(), html, "<img src=\"plots/no-such-plot.png\">");
  const BrowserRun probed = RunChromium(probe_page, "--dump-dom");
  fs::remove(probe_page);
  ASSERT_EQ(probed.exit_code, 0) << probed.log;
  EXPECT_EQ(ReadProbe(probed.out).broken, "plots/no-such-plot.png");
  ASSERT_EQ(ConsoleLines(probed.log).size(), 1u) << probed.log;
  EXPECT_NE(ConsoleLines(probed.log).front().find("no-such-plot"), std::string::npos);
}

}  // namespace
}  // namespace platemeter::report
