// The batch's index.html in a real browser (issue #25: every generated HTML
// page): headless Chromium shows it with no console message, and every link of
// the page (each scan's folder, report, measurements and record) resolves.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "batch/batch_fixture.h"
#include "support/browser.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

namespace fs = std::filesystem;

TEST(BatchIndexBrowser, ChromiumShowsTheIndexAndEveryLinkResolves) {
  if (testing::FindChromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
  const batch_test::Fixture& f = batch_test::GetFixture();
  testing::TempDir dir;
  const fs::path scans = dir.path() / "scans";
  fs::create_directories(scans);
  // Three good scans and the truncated one (a failed row).
  for (int i : {0, 1, 2, batch_test::kTruncated}) fs::create_symlink(f.Scan(i), scans / (f.names[i] + ".tif"));
  const fs::path out = dir.path() / "out";
  const testing::CommandResult r =
      testing::RunPlatemeter("--definitions '" + f.defs + "' batch '" + scans.string() + "' -o '" + out.string() +
                             "' --camera batchtest --orientation 0 --jobs 2");
  ASSERT_EQ(r.exit_code, 1) << r.out << r.err;  // the truncated scan failed
  const std::string html = testing::ReadTextFile((out / "index.html").string());
  int links = 0;
  const std::regex href("href=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), href); it != std::sregex_iterator(); ++it) {
    const std::string link = (*it)[1];
    EXPECT_EQ(link.find("://"), std::string::npos) << link;
    EXPECT_TRUE(fs::exists(out / link)) << link;
    ++links;
  }
  EXPECT_GE(links, 4 + 3 * 3);  // the summary CSV, each scan's folder; report, measurements and record of each good one
  testing::CheckPageInChromium(out.string(), "index.html", 0, 900);
}

}  // namespace
}  // namespace platemeter
