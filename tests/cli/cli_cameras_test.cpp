// platemeter cameras profile, through the binary: seed 000's Tables 2 and 7 from
// a definitions file and the built-in, the balances, and one-line errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/seed000_tables.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

// Seed 000 Table 1 (pure self-calibration) as a user definition; the OCR
// reconstructions are documented in tests/calib/profile_seed000_test.cpp and
// docs/cameras.md. Plus a camera without a lens.
const std::string kDefinitions = std::string(testing::kSeed000Tables1And3Toml) + R"toml(
[[camera]]
name = "no-lens"
description = "a camera without a lens calibration"
source = "test"
format_width_mm = 55.0
format_height_mm = 55.0
nominal_principal_distance_mm = 500.0
format_corners_as_fiducials = true
)toml";

class CamerasProfile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ofstream(dir_.file("seed000.toml")) << kDefinitions;
    definitions_ = "--definitions '" + dir_.file("seed000.toml") + "' ";
  }
  testing::TempDir dir_;
  std::string definitions_;
};

const char kSeedRadii[] = "--radii-mm 0,5,10,15,20,25,30,35,39";

struct Row {
  double r, radial, radial_sigma, decentering, decentering_sigma;
};

// The CSV rows (lines not starting with '#', after the header).
std::vector<Row> CsvRows(const std::string& out) {
  std::vector<Row> rows;
  std::istringstream lines(out);
  std::string line;
  bool header = false;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      EXPECT_EQ(line, "r_mm,radial_um,radial_sigma_um,decentering_um,decentering_sigma_um");
      header = true;
      continue;
    }
    Row row{};
    char comma;
    std::istringstream fields(line);
    fields >> row.r >> comma >> row.radial >> comma >> row.radial_sigma >> comma >> row.decentering >> comma >>
        row.decentering_sigma;
    EXPECT_TRUE(fields) << line;
    rows.push_back(row);
  }
  return rows;
}

void ExpectOneLineError(const testing::CommandResult& result, int exit_code, const std::string& text) {
  EXPECT_EQ(result.exit_code, exit_code) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(text), std::string::npos) << result.err;
  EXPECT_TRUE(result.out.empty()) << result.out;
}

TEST_F(CamerasProfile, Table2FromTable1AsCsv) {
  const auto result =
      RunPlatemeter(definitions_ + "cameras profile hasselblad-500-selfcal " + kSeedRadii + " --format csv");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty()) << result.err;
  const std::vector<Row> printed = {{0, 0, 0, 0, 0},        {5, -68, 0, 0, 0},      {10, -125, 1, 0, 0},
                                    {15, -158, 1, 1, 1},    {20, -156, 2, 2, 1},    {25, -108, 3, 3, 2},
                                    {30, 0, 5, 4, 3},       {35, 177, 8, 6, 4},     {39, 378, 11, 7, 5}};
  const std::vector<Row> rows = CsvRows(result.out);
  ASSERT_EQ(rows.size(), printed.size()) << result.out;
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].r, printed[i].r);
    EXPECT_NEAR(rows[i].radial, printed[i].radial, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].radial_sigma, printed[i].radial_sigma, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].decentering, printed[i].decentering, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].decentering_sigma, printed[i].decentering_sigma, 1.0) << rows[i].r;
  }
  // Table 8: -50 +- 40 deg.
  EXPECT_NE(result.out.find("# phase_angle_deg: -50.2 +- 39.8\n"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("# c_prime_mm: 502.6300 +- 2.0600\n"), std::string::npos) << result.out;
}

TEST_F(CamerasProfile, Table4FromTheDefinitionsInTheDocs) {
  // docs/cameras.md's TOML block (Tables 1 and 3), as a user would save it.
  std::ifstream doc(std::string(PLATEMETER_SOURCE_DIR) + "/docs/cameras.md");
  std::stringstream text;
  text << doc.rdbuf();
  const std::string markdown = text.str();
  const size_t begin = markdown.find("```toml\n");
  ASSERT_NE(begin, std::string::npos);
  const size_t end = markdown.find("```", begin + 8);
  std::ofstream(dir_.file("seed000-selfcal.toml")) << markdown.substr(begin + 8, end - begin - 8);
  const auto result = RunPlatemeter("--definitions '" + dir_.file("seed000-selfcal.toml") +
                                    "' cameras profile hasselblad-500-selfcal-constrained " + kSeedRadii +
                                    " --format csv");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::vector<Row> printed = {{0, 0, 0, 0, 0},     {5, -69, 0, 0, 0},   {10, -126, 0, 0, 0},
                                    {15, -159, 1, 0, 1}, {20, -157, 2, 0, 1}, {25, -108, 3, 0, 2},
                                    {30, 0, 5, 1, 2},    {35, 178, 8, 1, 3},  {39, 380, 11, 1, 4}};
  const std::vector<Row> rows = CsvRows(result.out);
  ASSERT_EQ(rows.size(), printed.size()) << result.out;
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_NEAR(rows[i].radial, printed[i].radial, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].radial_sigma, printed[i].radial_sigma, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].decentering, printed[i].decentering, 1.0) << rows[i].r;
    EXPECT_NEAR(rows[i].decentering_sigma, printed[i].decentering_sigma, 1.0) << rows[i].r;
  }
  // Table 8: -92 +- 240 deg.
  EXPECT_NE(result.out.find("# phase_angle_deg: -91.8 +- 239.7\n"), std::string::npos) << result.out;
}

TEST_F(CamerasProfile, Table7FromTheBuiltinWithTheCorrelation) {
  const auto result = RunPlatemeter(std::string("cameras profile hasselblad-500 ") + kSeedRadii +
                                    " --correlation k1_per_mm2,k2_per_mm4=-0.96");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("phase_angle_deg: -72.2 +- 11.9\n"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("    r_mm  radial_um  radial_sigma_um  decentering_um  decentering_sigma_um\n"),
            std::string::npos)
      << result.out;
  // Table 7 at 39 mm: +361, 8, 6, 1.
  EXPECT_NE(result.out.find("      39      361.4              7.4             6.2                   1.3\n"),
            std::string::npos)
      << result.out;
}

TEST_F(CamerasProfile, BalancesAndDefaultRadii) {
  // Zero at 30 mm: value and sigma 0 there.
  const auto at30 = RunPlatemeter(definitions_ + "cameras profile hasselblad-500-selfcal --balance-radius-mm 30 " +
                                  kSeedRadii + " --format csv");
  ASSERT_EQ(at30.exit_code, 0) << at30.err;
  const std::vector<Row> rows = CsvRows(at30.out);
  ASSERT_EQ(rows.size(), 9u);
  EXPECT_EQ(rows[6].r, 30);
  EXPECT_EQ(rows[6].radial, 0.0);
  EXPECT_EQ(rows[6].radial_sigma, 0.0);
  EXPECT_NE(at30.out.find("# balance: zero at r = 30 mm"), std::string::npos);
  // Equal lobes over the format's half diagonal (38.89 mm); default radii to 38.9 mm.
  const auto lobes = RunPlatemeter("cameras profile hasselblad-500 --equal-lobes --format csv");
  ASSERT_EQ(lobes.exit_code, 0) << lobes.err;
  const std::vector<Row> lobe_rows = CsvRows(lobes.out);
  ASSERT_EQ(lobe_rows.size(), 9u);
  EXPECT_NEAR(lobe_rows.back().r, 38.8909, 1e-4);  // the corner
  double high = 0.0, low = 0.0;
  for (const Row& row : lobe_rows) high = std::max(high, row.radial), low = std::min(low, row.radial);
  EXPECT_GT(high, 50.0);
  EXPECT_LT(low, -50.0);
  // The corner is the positive peak; the rows only sample the negative lobe (peak near 20 mm).
  EXPECT_GE(high, -low - 1e-3);
  EXPECT_LT(high, -low + 2.0);
  EXPECT_NE(lobes.out.find("# balance: equal positive and negative lobe peaks over 0..38.8909 mm"),
            std::string::npos)
      << lobes.out;
  const auto areas = RunPlatemeter("cameras profile hasselblad-500 --equal-areas --max-radius-mm 35");
  ASSERT_EQ(areas.exit_code, 0) << areas.err;
  EXPECT_NE(areas.out.find("equal positive and negative lobe areas over 0..35 mm"), std::string::npos);
  // A seed 004 lens.
  const auto sn004 = RunPlatemeter("cameras profile sn004-terrain");
  ASSERT_EQ(sn004.exit_code, 0) << sn004.err;
  EXPECT_NE(sn004.out.find("smac-radial-decentering"), std::string::npos);
  EXPECT_NE(sn004.out.find("phase_angle_deg: -166.8 +- 16.7\n"), std::string::npos) << sn004.out;
}

TEST_F(CamerasProfile, CameraErrorsAreOneLine) {
  ExpectOneLineError(RunPlatemeter("cameras profile nope"), 1, "nope");
  ExpectOneLineError(RunPlatemeter(definitions_ + "cameras profile no-lens"), 1, "no lens calibration");
  ExpectOneLineError(RunPlatemeter("cameras profile orbigon"), 1, "orbigon-11");
}

TEST_F(CamerasProfile, OptionErrorsAreOneLine) {
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --radii-mm 5,abc"), 1,
                     "--radii-mm: 'abc' is not a number");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --radii-mm=5,-1"), 1,
                     "--radii-mm: a radius must be >= 0 mm");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --radii-mm ,"), 1, "--radii-mm: ");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --balance-radius-mm 0"), 1,
                     "the balance radius must be > 0 mm");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --max-radius-mm 30"), 1, "--max-radius-mm");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --correlation k1_per_mm2,k9=0.5"), 1,
                     "no parameter k9");
  ExpectOneLineError(RunPlatemeter("cameras profile hasselblad-500 --correlation k1_per_mm2"), 1,
                     "is not NAME1,NAME2=RHO");
  // Usage errors (CLI11): exit 2.
  const auto both = RunPlatemeter("cameras profile hasselblad-500 --balance-radius-mm 30 --equal-lobes");
  EXPECT_EQ(both.exit_code, 2) << both.err;
  const auto format = RunPlatemeter("cameras profile hasselblad-500 --format xml");
  EXPECT_EQ(format.exit_code, 2) << format.err;
}

TEST_F(CamerasProfile, ListAndShowStillWork) {
  const auto list = RunPlatemeter(definitions_ + "cameras list");
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_NE(list.out.find("hasselblad-500-selfcal"), std::string::npos);
  const auto show = RunPlatemeter("cameras show hasselblad-500");
  ASSERT_EQ(show.exit_code, 0) << show.err;
  const auto help = RunPlatemeter("cameras --help");
  EXPECT_NE(help.out.find("profile"), std::string::npos) << help.out;
}

}  // namespace
}  // namespace platemeter
