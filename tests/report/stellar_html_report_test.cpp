// The stellar calibration's HTML report end to end: `platemeter calibrate
// stellar` writes report.html with every plot of seed 001 Table 4 it links and
// certificate.html; the certificate's distortion table is checked against the
// simulator's true lens within its own printed standard errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "platemeter/calib/stellar_distortion.h"
#include "report_files.h"
#include "stellar_report_run.h"

namespace platemeter::report {
namespace {

namespace fs = std::filesystem;

TEST(StellarHtmlReport, CalibrateStellarWritesEveryTable4PlotAndTheCertificate) {
  const testing::StellarReportRun& run = testing::RunStellarForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err << run.result.out;
  const std::string html = testing::ReadTextFile(run.out + "/report.html");
  ASSERT_FALSE(html.empty());
  const std::vector<std::string> links = testing::LinkedFiles(html);
  const std::set<std::string> linked(links.begin(), links.end());
  for (const std::string& link : linked) {
    const std::string path = run.out + "/" + link;
    ASSERT_TRUE(fs::exists(path)) << link;
    if (!link.ends_with(".png")) continue;
    const testing::PngSize size = testing::ReadPngSize(testing::ReadTextFile(path));
    EXPECT_TRUE(size.valid) << link;
    EXPECT_EQ(testing::AttributeOfImage(html, link, "width"), std::to_string(size.width)) << link;
  }
  // Seed 001 Table 4, per plate and per combination ("all" combines N and S).
  const nlohmann::json calibration = nlohmann::json::parse(testing::ReadTextFile(run.out + "/calibration.json"));
  ASSERT_FALSE(calibration["combinations"].empty());
  std::string combination = calibration["combinations"][0]["name"];
  for (char& ch : combination) ch = std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '.' ? ch : '_';
  std::vector<std::string> stems;
  for (const char* plate : {"N", "S"}) {
    for (const char* kind : {"histogram-plate-{}-x", "histogram-plate-{}-y", "histogram-plate-{}-xy",
                             "stars-plate-{}", "residuals-plate-{}", "distortion-plate-{}"}) {
      stems.push_back(std::regex_replace(kind, std::regex("\\{\\}"), plate));
    }
  }
  for (const char* kind : {"histogram-combination-{}-xy", "stars-combination-{}", "distortion-combination-{}"}) {
    stems.push_back(std::regex_replace(kind, std::regex("\\{\\}"), combination));
  }
  for (const char* kind : {"radial", "transformed", "decentering"}) {
    for (const char* set : {"plates", "combinations"}) stems.push_back(std::string("profile-") + kind + "-" + set);
  }
  for (const std::string& stem : stems) {
    EXPECT_TRUE(linked.count("plots/" + stem + ".png")) << stem;
    EXPECT_TRUE(linked.count("plots/" + stem + ".svg")) << stem;
  }
  for (const auto& entry : fs::directory_iterator(run.out + "/plots")) {
    EXPECT_TRUE(linked.count("plots/" + entry.path().filename().string())) << entry.path();
  }
  EXPECT_TRUE(linked.count("certificate.html"));
  EXPECT_NE(html.find("Single-plate calibrations (seed 001 Table 2)"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

// The certificate's radial (equal-area) and decentering distortion by field
// angle against the true lens's, within 3 of the standard errors it prints.
TEST(StellarHtmlReport, CertificateDistortionMatchesTheTrueLensWithinItsStandardErrors) {
  const testing::StellarReportRun& run = testing::RunStellarForReport();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.err;
  const std::string page = testing::ReadTextFile(run.out + "/certificate.html");
  const std::regex row(
      "<tr><td class=\"num\">([-0-9.]+)</td><td class=\"num\">([-0-9.]+)</td><td class=\"num\">([-+0-9.]+)</td>"
      "<td class=\"num\">([-0-9.]+)</td><td class=\"num\">([-0-9.]+)</td><td class=\"num\">([-0-9.]+)</td></tr>");
  std::vector<std::array<double, 6>> rows;
  for (auto it = std::sregex_iterator(page.begin(), page.end(), row); it != std::sregex_iterator(); ++it) {
    std::array<double, 6> r{};
    for (int k = 0; k < 6; ++k) r[k] = std::stod((*it)[k + 1]);
    rows.push_back(r);
  }
  ASSERT_GE(rows.size(), 5u) << page;
  EXPECT_EQ(rows.front()[0], 0.0);
  // The truth's profile at the printed distances, transformed over the same extent (the orbigon format's corner).
  StellarLensEstimate truth{DistortionModelId::kSlama, run.truth, {}};
  const double corner = std::hypot(57.0, 57.0);  // the builtin orbigon: 114 x 114 mm
  std::vector<double> distances;
  for (const auto& r : rows) distances.push_back(r[1]);
  const StellarProfile expected = ComputeStellarProfile(truth, corner, distances);
  double largest_radial = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    // Printed with 2 decimals: 0.005 um of rounding on top of the sigma.
    EXPECT_LE(std::abs(r[2] - expected.rows[i].transformed_um), 3 * r[3] + 0.01)
        << "field angle " << r[0] << ": " << r[2] << " +- " << r[3] << " vs " << expected.rows[i].transformed_um;
    EXPECT_LE(std::abs(r[4] - expected.rows[i].decentering_um), 3 * r[5] + 0.01)
        << "field angle " << r[0] << ": " << r[4] << " +- " << r[5] << " vs " << expected.rows[i].decentering_um;
    EXPECT_GT(r[3], 0.0);
    largest_radial = std::max(largest_radial, std::abs(expected.rows[i].transformed_um));
  }
  EXPECT_GT(largest_radial, 1.0);  // the truth has a distortion worth certifying
}

}  // namespace
}  // namespace platemeter::report
