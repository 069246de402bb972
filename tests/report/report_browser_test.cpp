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
#include "stellar_report_run.h"
#include "png_pixels.h"
#include "report_files.h"

namespace platemeter::report {
namespace {

namespace fs = std::filesystem;

std::string FindChromium() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin", "/snap/bin"}) {
    const fs::path path = fs::path(dir) / "chromium";
    if (fs::exists(path)) return path.string();
  }
  return "";
}

struct BrowserRun {
  int exit_code = -1;
  std::string out;  // stdout (--dump-dom: the DOM after the load event)
  std::string log;  // stderr (--enable-logging=stderr: console messages as "CONSOLE" lines)
};

BrowserRun RunChromium(const std::string& page, const std::string& extra) {
  testing::TempDir profile;
  const std::string command = "timeout 60 '" + FindChromium() +
                              "' --headless --disable-gpu --no-sandbox --user-data-dir='" + profile.file("profile") +
                              "' --enable-logging=stderr --v=0 " + extra + " 'file://" + page + "' >'" +
                              profile.file("out") + "' 2>'" + profile.file("log") + "'";
  BrowserRun run;
  const int status = std::system(command.c_str());
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = testing::ReadTextFile(profile.file("out"));
  run.log = testing::ReadTextFile(profile.file("log"));
  return run;
}

std::vector<std::string> ConsoleLines(const std::string& log) {
  std::vector<std::string> lines;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find(":CONSOLE") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

std::set<std::string> SvgLinks(const std::string& html) {
  std::set<std::string> svgs;
  for (const std::string& link : testing::LinkedFiles(html)) {
    if (link.ends_with(".svg")) svgs.insert(link);
  }
  return svgs;
}

// A copy of the page next to it with every linked SVG as an image too and a
// probe that, after the load event, lists the images that did not decode.
std::string WriteProbePage(const std::string& dir, const std::string& html, const std::string& extra_images) {
  std::string images = extra_images;
  for (const std::string& link : SvgLinks(html)) images += "<img src=\"" + link + "\">";
  const std::string probe =
      "<div id=\"probe\">" + images +
      "</div><script>window.addEventListener('load', () => {"
      "const bad = [...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.getAttribute('src'));"
      "document.body.setAttribute('data-probe', 'images=' + document.images.length + ' broken=' + bad.join(','));"
      "if (bad.length) console.error('broken images: ' + bad.join(','));});</script>";
  std::string page = html;
  page.insert(page.rfind("</body>"), probe);
  const std::string path = dir + "/.report-probe.html";
  std::ofstream(path) << page;
  return path;
}

struct ProbeResult {
  int images = -1;
  std::string broken;
};

ProbeResult ReadProbe(const std::string& dom) {
  std::smatch m;
  ProbeResult r;
  if (std::regex_search(dom, m, std::regex("data-probe=\"images=(\\d+) broken=([^\"]*)\""))) {
    r.images = std::stoi(m[1]);
    r.broken = m[2];
  }
  return r;
}

// Opens `dir`/`name` in Chromium: a screenshot of 1400 x height px with ink on
// it, no console message, and every image of the page (PNG shown, SVG linked)
// decoded; at least `min_svgs` SVG links.
void CheckPageInChromium(const std::string& dir, const std::string& name, size_t min_svgs, int height_px) {
  const std::string page = fs::absolute(dir + "/" + name).string();
  const std::string screenshot = fs::absolute(dir + "/screenshot-" + name + ".png").string();
  fs::remove(screenshot);
  const BrowserRun shown =
      RunChromium(page, "--screenshot='" + screenshot + "' --window-size=1400," + std::to_string(height_px));
  ASSERT_EQ(shown.exit_code, 0) << shown.log;
  EXPECT_TRUE(ConsoleLines(shown.log).empty()) << ConsoleLines(shown.log).front();
  const std::string bytes = testing::ReadTextFile(screenshot);
  const testing::PngSize size = testing::ReadPngSize(bytes);
  ASSERT_TRUE(size.valid) << screenshot;
  EXPECT_EQ(size.width, 1400);
  EXPECT_EQ(size.height, height_px);
  // Something was drawn: a share of the screenshot is not white.
  testing::PngPixels pixels(bytes);
  ASSERT_TRUE(pixels.ok());
  long inked = 0;
  for (int y = 0; y < pixels.height(); y += 4) {
    for (int x = 0; x < pixels.width(); x += 4) inked += !pixels.IsWhite(x, y);
  }
  EXPECT_GT(inked, 0.005 * (pixels.width() / 4) * (pixels.height() / 4)) << name;

  const std::string html = testing::ReadTextFile(page);
  const std::string probe_page = WriteProbePage(dir, html, "");
  const BrowserRun probed = RunChromium(probe_page, "--dump-dom");
  fs::remove(probe_page);
  ASSERT_EQ(probed.exit_code, 0) << probed.log;
  const ProbeResult probe = ReadProbe(probed.out);
  // Each plot's PNG shown and its SVG probed.
  const size_t linked_images = 2 * SvgLinks(html).size();
  EXPECT_GE(linked_images, 2 * min_svgs) << name;
  EXPECT_EQ(probe.images, static_cast<int>(linked_images)) << probed.out.substr(0, 500);
  EXPECT_EQ(probe.broken, "");
  EXPECT_TRUE(ConsoleLines(probed.log).empty()) << ConsoleLines(probed.log).front();
}

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
