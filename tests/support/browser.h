#pragma once
// Headless Chromium (Debian `chromium`, installed by scripts/setup) for the
// tests of generated HTML pages (issue #25): open a page, write a screenshot,
// read the console messages, and probe that every image decodes. The pages
// have no script: the image check runs on a copy of the page with a probe
// added (WriteProbePage).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "report/png_pixels.h"
#include "report/report_files.h"
#include "support/test_support.h"

namespace platemeter::testing {

namespace fs = std::filesystem;

inline std::string FindChromium() {
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

inline BrowserRun RunChromium(const std::string& page, const std::string& extra) {
  TempDir profile;
  const std::string command = "timeout 60 '" + FindChromium() +
                              "' --headless --disable-gpu --no-sandbox --user-data-dir='" + profile.file("profile") +
                              "' --enable-logging=stderr --v=0 " + extra + " 'file://" + page + "' >'" +
                              profile.file("out") + "' 2>'" + profile.file("log") + "'";
  BrowserRun run;
  const int status = std::system(command.c_str());
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadTextFile(profile.file("out"));
  run.log = ReadTextFile(profile.file("log"));
  return run;
}

inline std::vector<std::string> ConsoleLines(const std::string& log) {
  std::vector<std::string> lines;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find(":CONSOLE") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

inline std::set<std::string> SvgLinks(const std::string& html) {
  std::set<std::string> svgs;
  for (const std::string& link : LinkedFiles(html)) {
    if (link.ends_with(".svg")) svgs.insert(link);
  }
  return svgs;
}

// A copy of the page next to it with every linked SVG as an image too and a
// probe that, after the load event, lists the images that did not decode.
inline std::string WriteProbePage(const std::string& dir, const std::string& html, const std::string& extra_images) {
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

inline ProbeResult ReadProbe(const std::string& dom) {
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
// decoded; at least `min_svgs` linked SVGs.
inline void CheckPageInChromium(const std::string& dir, const std::string& name, size_t min_svgs, int height_px) {
  const std::string page = fs::absolute(dir + "/" + name).string();
  const std::string screenshot = fs::absolute(dir + "/screenshot-" + name + ".png").string();
  fs::remove(screenshot);
  const BrowserRun shown =
      RunChromium(page, "--screenshot='" + screenshot + "' --window-size=1400," + std::to_string(height_px));
  ASSERT_EQ(shown.exit_code, 0) << shown.log;
  EXPECT_TRUE(ConsoleLines(shown.log).empty()) << ConsoleLines(shown.log).front();
  const std::string bytes = ReadTextFile(screenshot);
  const PngSize size = ReadPngSize(bytes);
  ASSERT_TRUE(size.valid) << screenshot;
  EXPECT_EQ(size.width, 1400);
  EXPECT_EQ(size.height, height_px);
  // Something was drawn: a share of the screenshot is not white.
  PngPixels pixels(bytes);
  ASSERT_TRUE(pixels.ok());
  long inked = 0;
  for (int y = 0; y < pixels.height(); y += 4) {
    for (int x = 0; x < pixels.width(); x += 4) inked += !pixels.IsWhite(x, y);
  }
  EXPECT_GT(inked, 0.005 * (pixels.width() / 4) * (pixels.height() / 4)) << name;

  const std::string html = ReadTextFile(page);
  const std::string probe_page = WriteProbePage(dir, html, "");
  const BrowserRun probed = RunChromium(probe_page, "--dump-dom");
  fs::remove(probe_page);
  ASSERT_EQ(probed.exit_code, 0) << probed.log;
  const ProbeResult probe = ReadProbe(probed.out);
  // Every image of the page and every SVG it links, probed.
  size_t page_images = 0;
  for (size_t at = html.find("<img"); at != std::string::npos; at = html.find("<img", at + 4)) ++page_images;
  const size_t svgs = SvgLinks(html).size();
  EXPECT_GE(svgs, min_svgs) << name;
  EXPECT_EQ(probe.images, static_cast<int>(page_images + svgs)) << probed.out.substr(0, 500);
  EXPECT_EQ(probe.broken, "");
  EXPECT_TRUE(ConsoleLines(probed.log).empty()) << ConsoleLines(probed.log).front();
}


}  // namespace platemeter::testing
