// platemeter detect with passpoints end to end, on the bundled Hasselblad
// plate as `platemeter simulate` renders it (40 random rings and PUG-1): the
// passpoint rows against the simulator's truth file, list mode with the
// user's ids and a missing entry, and a bad list refused with file and line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;
using testing::TempDir;

// Rendered once for the suite: the scan and its truth file.
class CliPasspoints : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const auto r = RunPlatemeter("simulate '" + std::string(PLATEMETER_SOURCE_DIR) +
                                 "/samples/specs/hasselblad-passpoints.toml' -o '" + dir_->file("sim") + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    scan_ = new std::string(dir_->file("sim/hasselblad-passpoints.tif"));
    truth_ = new std::vector<MeasuredPoint>;
    for (const MeasuredPoint& p : ReadMeasurementFile(dir_->file("sim/hasselblad-passpoints.truth.csv")).points)
      if (p.kind == PointKind::kPasspoint) truth_->push_back(p);
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete scan_;
    delete dir_;
  }
  // The demo's orientation for this spec (scanner orientation_deg = 270), ring 250 um, line 50 um.
  static std::string Detect(const std::string& out, const std::string& extra = "") {
    return "detect '" + *scan_ + "' --camera hasselblad-500 --orientation 270 --passpoint-diameter-um 250 "
           "--passpoint-shape ring --passpoint-line-width-um 50 -o '" + out + "' " + extra;
  }
  static const MeasuredPoint* NearestTruth(double x_px, double y_px, double within_px) {
    const MeasuredPoint* best = nullptr;
    for (const MeasuredPoint& t : *truth_) {
      const double d = std::hypot(x_px - *t.x_px, y_px - *t.y_px);
      if (d < within_px) within_px = d, best = &t;
    }
    return best;
  }
  static TempDir* dir_;
  static std::string* scan_;
  static std::vector<MeasuredPoint>* truth_;
};
TempDir* CliPasspoints::dir_ = nullptr;
std::string* CliPasspoints::scan_ = nullptr;
std::vector<MeasuredPoint>* CliPasspoints::truth_ = nullptr;

TEST_F(CliPasspoints, AutomaticRowsMatchTheTruthFile) {
  ASSERT_EQ(truth_->size(), 41u);
  const std::string out = dir_->file("auto");
  const auto r = RunPlatemeter(Detect(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("passpoints: 41 passpoints found"), std::string::npos) << r.out;
  const MeasurementFile file = ReadMeasurementFile(out + "/hasselblad-passpoints.measurements.csv");
  std::map<std::string, int> matched;
  int rows = 0, fiducials = 0;
  double e2 = 0, crb2 = 0, n2 = 0;
  for (const MeasuredPoint& p : file.points) {
    fiducials += p.kind == PointKind::kFiducial;
    if (p.kind != PointKind::kPasspoint) continue;
    ++rows;
    EXPECT_EQ(p.id, "P" + std::to_string(rows));  // rows in numbering order
    ASSERT_EQ(p.status, PointStatus::kMeasured) << p.id;
    ASSERT_TRUE(p.x_px && p.y_px && p.sigma_x_px && p.sigma_y_px) << p.id;
    const MeasuredPoint* t = NearestTruth(*p.x_px, *p.y_px, 1.0);
    ASSERT_NE(t, nullptr) << p.id << " is no passpoint of the truth file";
    ++matched[t->id];
    const double ex = *p.x_px - *t->x_px, ey = *p.y_px - *t->y_px;
    e2 += ex * ex + ey * ey;
    crb2 += *t->crb_x_px * *t->crb_x_px + *t->crb_y_px * *t->crb_y_px;
    n2 += ex * ex / (*p.sigma_x_px * *p.sigma_x_px) + ey * ey / (*p.sigma_y_px * *p.sigma_y_px);
  }
  EXPECT_EQ(fiducials, 4);  // the format corners are fiducials, not passpoints
  EXPECT_EQ(rows, 41);
  EXPECT_EQ(matched.size(), 41u);  // every truth passpoint once
  const double ratio = std::sqrt(e2 / crb2), normalized = std::sqrt(n2 / (2.0 * rows));
  std::printf("CLI passpoints: RMS/CRB %.3f, RMS error/sigma %.3f over %d rings\n", ratio, normalized, rows);
  EXPECT_LE(ratio, 1.3);
  EXPECT_GT(normalized, 0.7);
  EXPECT_LT(normalized, 1.3);
  std::ifstream in(out + "/hasselblad-passpoints.detect.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["passpoints"]["mode"], "automatic");
  EXPECT_EQ(summary["passpoints"]["counts"]["measured"], 41);
  EXPECT_EQ(summary["passpoints"]["counts"]["missing"], 0);
}

TEST_F(CliPasspoints, ListModeKeepsIdsReportsMissingAndRefusesABadList) {
  const MeasuredPoint* pug = nullptr;
  for (const MeasuredPoint& t : *truth_)
    if (t.id == "PUG-1") pug = &t;
  ASSERT_NE(pug, nullptr);
  const MeasuredPoint& other = (*truth_)[0].id == "PUG-1" ? (*truth_)[1] : (*truth_)[0];
  const std::string list = dir_->file("list.csv");
  {
    std::ofstream f(list);
    f << "# clicked by the operator\nid,x_px,y_px\n";
    f << "PUG-1," << *pug->x_px + 4.0 << "," << *pug->y_px - 3.0 << "\n";
    f << "B2," << *other.x_px - 6.0 << "," << *other.y_px + 2.0 << "\n";
    f << "GONE," << *pug->x_px + 75.0 << "," << *pug->y_px + 75.0 << "\n";  // 1.5 mm from PUG-1: nothing there
  }
  const std::string out = dir_->file("list");
  const auto r = RunPlatemeter(Detect(out, "--passpoints '" + list + "'"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MeasurementFile file = ReadMeasurementFile(out + "/hasselblad-passpoints.measurements.csv");
  std::map<std::string, MeasuredPoint> rows;
  for (const MeasuredPoint& p : file.points)
    if (p.kind == PointKind::kPasspoint) rows[p.id] = p;
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(rows["PUG-1"].status, PointStatus::kMeasured);
  EXPECT_NEAR(*rows["PUG-1"].x_px, *pug->x_px, 0.1);
  EXPECT_NEAR(*rows["PUG-1"].y_px, *pug->y_px, 0.1);
  ASSERT_EQ(rows["B2"].status, PointStatus::kMeasured);
  EXPECT_NEAR(*rows["B2"].x_px, *other.x_px, 0.1);
  const MeasuredPoint& gone = rows["GONE"];
  EXPECT_EQ(gone.status, PointStatus::kMissing);
  EXPECT_FALSE(gone.x_px.has_value());  // no fabricated position
  EXPECT_FALSE(gone.sigma_x_px.has_value());
  ASSERT_EQ(gone.flags.size(), 1u);
  EXPECT_EQ(gone.flags[0], "missing:not_found");

  // A bad list: one line naming the file and the line, exit code 1, nothing written.
  const std::string bad = dir_->file("bad.csv");
  {
    std::ofstream f(bad);
    f << "id,x_px,y_px\nA,100,200\nB,100\n";
  }
  const std::string bad_out = dir_->file("bad");
  const auto refused = RunPlatemeter(Detect(bad_out, "--passpoints '" + bad + "'"));
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find(bad + ": line 3: expected 3 fields"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(bad_out + "/hasselblad-passpoints.measurements.csv"));
}

}  // namespace
}  // namespace platemeter
