// The MicMac MeasuresIm export parses as XML (xmllint, an independent parser)
// with MicMac's element names and the points' pixel positions.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "platemeter/measure/micmac_export.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

std::string Shell(const std::string& command) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::array<char, 256> buf{};
  while (pipe && fgets(buf.data(), buf.size(), pipe.get())) out += buf.data();
  return out;
}

TEST(MicMacExport, ParsesWithMicMacElementNames) {
  MeasurementFile file;
  file.header.scan_file = "/data/scans/plate <2325>.tif";
  MeasuredPoint a;
  a.id = "X1Y1";
  a.x_px = 259.6176415015885;
  a.y_px = 2760.0100148830065;
  MeasuredPoint b = a;
  b.id = "P&1";
  b.kind = PointKind::kPasspoint;
  b.x_px = 12.5;
  b.y_px = 0.25;
  MeasuredPoint missing;
  missing.id = "X2Y1";
  missing.status = PointStatus::kMissing;
  MeasuredPoint rejected = a;
  rejected.id = "X3Y1";
  rejected.status = PointStatus::kRejected;
  file.points = {a, b, missing, rejected};
  testing::TempDir dir;
  const std::string path = dir.file("m.xml");
  WriteMicMacMeasures(path, file);
  // scripts/setup installs xmllint (libxml2-utils): a missing parser is a failure, not a skip.
  ASSERT_FALSE(Shell("command -v xmllint").empty()) << "xmllint not installed (Debian package libxml2-utils)";
  const std::string root = "/SetOfMesureAppuisFlottants/MesureAppuiFlottant1Im";
  auto xpath = [&](const std::string& expr) {
    std::string out = Shell("xmllint --xpath '" + expr + "' " + path + " 2>&1");
    if (!out.empty() && out.back() == '\n') out.pop_back();
    return out;
  };
  EXPECT_EQ(xpath("string(" + root + "/NameIm)"), "plate <2325>.tif");
  EXPECT_EQ(xpath("count(" + root + "/OneMesureAF1I)"), "2");  // measured only: not missing, not rejected
  EXPECT_EQ(xpath("string(" + root + "/OneMesureAF1I[NamePt=\"X1Y1\"]/PtIm)"), "259.6176415015885 2760.0100148830065");
  EXPECT_EQ(xpath("string(" + root + "/OneMesureAF1I[NamePt=\"P&1\"]/PtIm)"), "12.5 0.25");
  // With rejected points included.
  WriteMicMacMeasures(path, file, "scan.tif", {true});
  EXPECT_EQ(xpath("count(" + root + "/OneMesureAF1I)"), "3");
  EXPECT_EQ(xpath("string(" + root + "/NameIm)"), "scan.tif");
}

// A scan named in another encoding (Latin-1 "plaque-\xe9t\xe9") and an id with a control character stay
// well-formed XML: each byte sequence XML cannot hold becomes U+FFFD; valid UTF-8 passes unchanged.
TEST(MicMacExport, TextThatIsNotUtf8StaysWellFormed) {
  MeasurementFile file;
  file.header.scan_file = "/data/plaque-\xe9t\xe9.tif";
  MeasuredPoint a;
  a.id = "P\x01" "7";
  a.x_px = 1.5;
  a.y_px = 2.5;
  MeasuredPoint b = a;
  b.id = "\xC3\xA9toile";  // UTF-8 e-acute
  file.points = {a, b};
  testing::TempDir dir;
  const std::string path = dir.file("m.xml");
  WriteMicMacMeasures(path, file);
  const std::string root = "/SetOfMesureAppuisFlottants/MesureAppuiFlottant1Im";
  auto text = [&](const std::string& element) {
    std::string out = Shell("xmllint --xpath 'string(" + root + "/" + element + ")' " + path + " 2>&1");
    if (!out.empty() && out.back() == '\n') out.pop_back();
    return out;
  };
  EXPECT_EQ(Shell("xmllint --noout " + path + " 2>&1"), "");  // well-formed: xmllint prints nothing
  EXPECT_EQ(text("NameIm"), "plaque-\xEF\xBF\xBDt\xEF\xBF\xBD.tif");
  EXPECT_EQ(text("OneMesureAF1I[1]/NamePt"), "P\xEF\xBF\xBD" "7");
  EXPECT_EQ(text("OneMesureAF1I[2]/NamePt"), "\xC3\xA9toile");
}

}  // namespace
}  // namespace platemeter
