// RunMeasure (pipeline/measure_run.h) called as a library: what it wrote and said,
// and failures that name the scan (too few crosses, the wrong camera, a truncated scan).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/pipeline/measure_run.h"
#include "support/job_plates.h"
#include "support/test_support.h"

namespace platemeter::pipeline {
namespace {

using testing::OrbigonJobScan;
using testing::OrbigonTruthMeasurementFile;
using testing::ReadTextFile;
using testing::TempDir;

TEST(MeasureRun, RunMeasureSummarizesWhatItWrote) {
  TempDir dir;
  MeasureRequest request;
  request.detect.scan = OrbigonTruthMeasurementFile(dir, 119);
  request.detect.camera = "orbigon";
  request.temperature_degC = 22.0;
  request.emulsion_depth_um = 21.0;  // the simulated plate's
  request.out_dir = dir.file("out");
  const DefinitionRegistry registry;
  const MeasureSummary summary = RunMeasure(request, registry);
  EXPECT_EQ(summary.plate_id, "orbigon");
  EXPECT_EQ(summary.counts_by_kind, (std::map<std::string, int>{{"reseau", 121}}));
  EXPECT_EQ(summary.counts_by_status, (std::map<std::string, int>{{"measured", 119}, {"missing", 2}}));
  ASSERT_TRUE(summary.reseau_rms_um && summary.scale_x && summary.scale_y);
  const nlohmann::json report = nlohmann::json::parse(ReadTextFile(dir.file("out/orbigon.measure.json")));
  EXPECT_DOUBLE_EQ(*summary.reseau_rms_um, report["reseau"]["rms_um"].get<double>());
  EXPECT_DOUBLE_EQ(*summary.scale_x, report["reseau"]["scale_x"]["value"].get<double>());
  EXPECT_DOUBLE_EQ(*summary.scale_y, report["reseau"]["scale_y"]["value"].get<double>());
  // Exact positions, the simulated temperature and emulsion depth corrected: the nominal grid.
  EXPECT_NEAR(*summary.scale_x, 1.0, 1e-6);
  EXPECT_NEAR(*summary.scale_y, 1.0, 1e-6);
  EXPECT_LT(*summary.reseau_rms_um, 0.1);
  const std::vector<std::string> expected = {"orbigon.measurements.csv", "orbigon.micmac.xml", "orbigon.residuals.png",
                                             "orbigon.measure.json"};
  ASSERT_EQ(summary.written_files.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(summary.written_files[i], std::filesystem::absolute(dir.file("out/" + expected[i])).string());
    EXPECT_TRUE(std::filesystem::exists(summary.written_files[i]));
  }
  EXPECT_EQ(summary.report_json, summary.written_files[3]);
  EXPECT_EQ(summary.plot_png, summary.written_files[2]);
  const std::string rms = [&] { std::ostringstream s; s << *summary.reseau_rms_um; return s.str(); }();
  const size_t first_line = summary.message.find('\n');
  ASSERT_NE(first_line, std::string::npos);
  const std::string fit_line = summary.message.substr(0, first_line);
  EXPECT_TRUE(fit_line.starts_with("reseau fit (scales): 119 crosses, 0 rejected, rms " + rms + " um, sigma0 ")) << fit_line;
  // Noise-free crosses: nothing to tell film deformation from (docs/measure.md, local reseau correction).
  EXPECT_NE(fit_line.find("local reseau correction not applied (p = 1:"), std::string::npos) << fit_line;
  EXPECT_EQ(summary.message.substr(first_line + 1),
            dir.file("out/orbigon.measurements.csv") + "\n" + dir.file("out/orbigon.measure.json") + "\n" +
                dir.file("out/orbigon.residuals.png") + "\n" + dir.file("out/orbigon.micmac.xml") + "\n");
}

// RunMeasure's error for `request`, "" when it succeeds.
std::string RunMeasureError(const MeasureRequest& request) {
  const DefinitionRegistry registry;
  try {
    RunMeasure(request, registry);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.what();
  }
  return "";
}

TEST(MeasureRun, TooFewCrossesOrTheWrongCameraFailNamingTheScan) {
  TempDir dir;
  MeasureRequest request;
  request.detect.scan = OrbigonTruthMeasurementFile(dir, 4);  // 4 crosses: a fit, but one that extrapolates over the plate
  request.detect.camera = "orbigon";
  request.out_dir = dir.file("out");
  EXPECT_EQ(RunMeasureError(request), request.detect.scan +
                                          ": only 4 of the 121 crosses of grid 'orbigon-reseau' usable for the reseau fit, 61 "
                                          "needed (min_cross_fraction 0.5): wrong camera or pixel size, or most crosses "
                                          "hidden or damaged");
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
  request.min_cross_fraction = 0.03;  // 4 of 121 accepted when asked for
  // They lie on one row of the grid: a line does not determine the scales model's second scale and
  // non-orthogonality (a singular fit is refused, not reported with infinite sigmas); a similarity it does.
  EXPECT_EQ(RunMeasureError(request), request.detect.scan +
                                          ": reseau fit: the scales model is not determined by the crosses used "
                                          "(singular normal equations)");
  request.model = "similarity";
  EXPECT_EQ(RunMeasureError(request), "");

  request.detect.scan = OrbigonTruthMeasurementFile(dir);
  request.detect.camera = "sn004-stellar";
  EXPECT_EQ(RunMeasureError(request), request.detect.scan + ": was detected with camera 'orbigon', not 'sn004-stellar'");
}

TEST(MeasureRun, RunMeasureFailuresNameTheScan) {
  const std::string& scan = OrbigonJobScan();
  TempDir dir;
  MeasureRequest request;
  request.detect.camera = "orbigon";
  request.detect.orientation = "0";
  request.out_dir = dir.file("out");
  // A truncated scan.
  const std::string truncated = dir.file("truncated.tif");
  std::filesystem::copy_file(scan, truncated);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(scan) / 2);
  request.detect.scan = truncated;
  const std::string error = RunMeasureError(request);
  EXPECT_EQ(error.rfind(truncated + ": ", 0), 0u) << error;
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  // The scan of another camera: the SN-004 stellar camera's 5 x 5 crosses at 5 mm match few of the
  // Orbigon's 11 x 11 at 10 mm.
  request.detect.scan = scan;
  request.detect.camera = "sn004-stellar";
  const std::string wrong = RunMeasureError(request);
  EXPECT_EQ(wrong.rfind(scan + ": ", 0), 0u) << wrong;
  EXPECT_NE(wrong.find("of the 25 crosses of grid 'ikotar-b' usable for the reseau fit, 13 needed"), std::string::npos) << wrong;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

}  // namespace
}  // namespace platemeter::pipeline
