// The fiducial interior orientation on simulator plates with exact truth: the
// true pixel positions of the truth file, perturbed by Gaussian noise of the
// stated sigma, go through CorrectFiducialPlate (or CorrectPlate with the
// fiducial switch) and must come back to the truth file's camera x_mm, y_mm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <string>

#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/fiducial_orientation.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/plate_corrections.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

constexpr double kSigmaPx = 0.05;  // px; 2 um at 40 um pixels

// A scanner with rotation, unequal pixel sides and non-orthogonality, an
// affine film deformation and 22 degC: all within the affine model.
std::string Spec(const std::string& camera, double emulsion_depth_um = 0.0) {
  return R"(
name = "f"
camera = ")" + camera + R"("
seed = 7
[output]
pixel_size_um = 40.0
[thermal]
temperature_degC = 22.0
calibration_temperature_degC = 20.0
[film]
affine_ppm = [40.0, 10.0, -6.0, -25.0]
[scanner]
pixel_aspect = 1.0003
rotation_deg = 0.4
non_orthogonality_arcsec = 25.0
[passpoints]
count = 30
[emulsion]
depth_um = )" + std::to_string(emulsion_depth_um) + R"(
refractive_index = 1.65
)";
}

const DefinitionRegistry& Registry() {
  static const DefinitionRegistry registry;
  return registry;
}

sim::SimulatedPlate Plate(const std::string& camera, double emulsion_depth_um = 0.0) {
  return sim::BuildSimulatedPlate(sim::ParseSimulationSpec(Spec(camera, emulsion_depth_um), "f.toml"), Registry());
}

// The truth's pixel positions plus noise; `shift_id` moved by shift_px in x.
MeasurementFile Measure(const sim::SimulatedPlate& plate, unsigned seed, const std::string& shift_id = "",
                        double shift_px = 0.0, double noise_px = kSigmaPx) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px);
  MeasurementFile file;
  file.header.plate_id = "f";
  file.header.camera = plate.camera;
  file.header.pixel_size_um = plate.pixel_size_um;
  file.header.extra.push_back({"orientation", "0"});
  for (const MeasuredPoint& t : plate.truth) {
    if (t.kind != PointKind::kFiducial && t.kind != PointKind::kPasspoint && t.kind != PointKind::kReseau) continue;
    if (!t.x_px) continue;
    MeasuredPoint p;
    p.id = t.id;
    p.kind = t.kind;
    p.x_px = *t.x_px + noise(rng) + (t.id == shift_id ? shift_px : 0.0);
    p.y_px = *t.y_px + noise(rng);
    p.sigma_x_px = kSigmaPx;
    p.sigma_y_px = kSigmaPx;
    file.points.push_back(p);
  }
  return file;
}

PlateCorrectionOptions Options(const sim::SimulatedPlate& plate, ReseauFitModel model) {
  const CameraDefinition& camera = Registry().Camera(plate.camera);
  PlateCorrectionOptions o;
  o.temperature_degC = plate.chain.thermal.temperature_degC;
  o.calibration_temperature_degC = plate.chain.thermal.calibration_temperature_degC;
  o.expansion_per_degC = plate.chain.thermal.expansion_per_degC;
  o.fiducials = CalibratedFiducials(
      camera, camera.fiducial_set.empty() ? nullptr : Registry().FindFiducials(camera.fiducial_set));
  o.fiducial_source = camera.format_corners_as_fiducials ? "format_corners" : camera.fiducial_set;
  o.fiducial.model = model;
  return o;
}

// Sums of squared errors against the truth and of squared propagated sigmas.
struct Tally {
  double err2 = 0.0, sig2 = 0.0;
  int n = 0;
  void Add(const MeasuredPoint& p, const MeasuredPoint& t) {
    ASSERT_TRUE(p.x_mm && p.y_mm && p.sigma_x_mm && p.sigma_y_mm) << p.id;
    err2 += std::pow(*p.x_mm - *t.x_mm, 2) + std::pow(*p.y_mm - *t.y_mm, 2);
    sig2 += std::pow(*p.sigma_x_mm, 2) + std::pow(*p.sigma_y_mm, 2);
    ++n;
  }
  double RmsErrorUm() const { return 1e3 * std::sqrt(err2 / (2 * n)); }
  double RmsSigmaUm() const { return 1e3 * std::sqrt(sig2 / (2 * n)); }
};

std::map<std::string, const MeasuredPoint*> TruthById(const sim::SimulatedPlate& plate) {
  std::map<std::string, const MeasuredPoint*> truth;
  for (const MeasuredPoint& t : plate.truth) truth[t.id] = &t;
  return truth;
}

TEST(FiducialOrientation, CalibratedFiducialsAreTheTableOrTheFormatCorners) {
  const std::vector<CalibratedFiducial> corners = CalibratedFiducials(Registry().Camera("hasselblad-500"), nullptr);
  ASSERT_EQ(corners.size(), 4u);
  EXPECT_EQ(corners[0].id, "UL");
  EXPECT_DOUBLE_EQ(corners[0].x_mm, -27.5);  // seed 000: 55 x 55 mm format
  EXPECT_DOUBLE_EQ(corners[0].y_mm, 27.5);
  EXPECT_EQ(corners[3].id, "LR");
  EXPECT_DOUBLE_EQ(corners[3].x_mm, 27.5);
  EXPECT_DOUBLE_EQ(corners[3].y_mm, -27.5);
  const CameraDefinition& sn004 = Registry().Camera("sn004-terrain");
  const std::vector<CalibratedFiducial> table = CalibratedFiducials(sn004, Registry().FindFiducials(sn004.fiducial_set));
  ASSERT_EQ(table.size(), 8u);
  EXPECT_EQ(table[0].id, "A");
  EXPECT_DOUBLE_EQ(table[0].x_mm, -60.614);  // seed 004, Table A.2
}

// Hasselblad 500 (format corners): corners and passpoints back to their true
// camera coordinates within 1.5 x their propagated sigmas, pooled over noise
// draws (the parameter errors are common to one plate).
void RecoversCameraCoordinates(ReseauFitModel model) {
  const sim::SimulatedPlate plate = Plate("hasselblad-500");
  const auto truth = TruthById(plate);
  Tally corners, passpoints;
  for (unsigned draw = 0; draw < 20; ++draw) {
    MeasurementFile file = Measure(plate, 100 + draw);
    const PlateCorrectionReport report = CorrectFiducialPlate(&file, Options(plate, model));
    ASSERT_TRUE(report.fiducial);
    EXPECT_EQ(report.fiducial->fit.used, 4);
    for (const MeasuredPoint& p : file.points) {
      if (p.kind == PointKind::kFiducial) corners.Add(p, *truth.at(p.id));
      if (p.kind == PointKind::kPasspoint) passpoints.Add(p, *truth.at(p.id));
    }
  }
  ASSERT_EQ(corners.n, 80);
  ASSERT_EQ(passpoints.n, 600);
  std::cout << ReseauFitModelName(model) << ": corners rms error " << corners.RmsErrorUm() << " um, rms sigma "
            << corners.RmsSigmaUm() << " um; passpoints rms error " << passpoints.RmsErrorUm() << " um, rms sigma "
            << passpoints.RmsSigmaUm() << " um\n";
  EXPECT_LT(corners.RmsErrorUm(), 1.5 * corners.RmsSigmaUm());
  EXPECT_LT(passpoints.RmsErrorUm(), 1.5 * passpoints.RmsSigmaUm());
  // The passpoints' sigma: their own 2 um plus the transform's from four
  // 2 um corners (at most about the corners' own 2 um again: sqrt(8) um).
  EXPECT_GT(passpoints.RmsSigmaUm(), 2.0);
  EXPECT_LT(passpoints.RmsSigmaUm(), 2.9);
}

TEST(FiducialOrientation, HasselbladAffineRecoversCornersAndPasspoints) {
  RecoversCameraCoordinates(ReseauFitModel::kAffine);
}

TEST(FiducialOrientation, SimilarityCannotTakeTheScannerAffinity) {
  // The plate's affinity (film 40/-25 ppm, pixel aspect 300 ppm, 25 arcsec)
  // is beyond a similarity: at 27.5 mm it leaves errors of several um.
  const sim::SimulatedPlate plate = Plate("hasselblad-500");
  const auto truth = TruthById(plate);
  MeasurementFile file = Measure(plate, 3);
  CorrectFiducialPlate(&file, Options(plate, ReseauFitModel::kSimilarity));
  Tally passpoints;
  for (const MeasuredPoint& p : file.points) {
    if (p.kind == PointKind::kPasspoint) passpoints.Add(p, *truth.at(p.id));
  }
  EXPECT_GT(passpoints.RmsErrorUm(), 3.0);
}

TEST(FiducialOrientation, HeaderRecordsTheStepAndRoundTrips) {
  const sim::SimulatedPlate plate = Plate("hasselblad-500");
  MeasurementFile file = Measure(plate, 1);
  CorrectFiducialPlate(&file, Options(plate, ReseauFitModel::kAffine));
  const MeasurementFile back = ParseMeasurementFile(FormatMeasurementFile(file), "f");
  ASSERT_EQ(back.header.corrections.size(), 3u);
  EXPECT_EQ(back.header.corrections[0].name, "comparator");
  EXPECT_EQ(back.header.corrections[1].name, "thermal");
  const AppliedCorrection& c = back.header.corrections[2];
  EXPECT_EQ(c.name, "fiducial_orientation");
  std::map<std::string, std::string> params(c.parameters.begin(), c.parameters.end());
  EXPECT_EQ(params["model"], "affine");
  EXPECT_EQ(params["fiducials"], "format_corners");
  EXPECT_EQ(params["fiducials_used"], "4");
  EXPECT_EQ(params["fiducials_rejected"], "0");
  EXPECT_TRUE(params.count("sigma_tx_mm"));
}

TEST(FiducialOrientation, ShiftedSn004FiducialIsRejectedAndFlagged) {
  const sim::SimulatedPlate plate = Plate("sn004-terrain");
  const auto truth = TruthById(plate);
  const double shift_px = 50.0 / plate.pixel_size_um;  // 50 um
  for (const char* bad : {"A", "C'"}) {
    MeasurementFile file = Measure(plate, 21, bad, shift_px);
    const PlateCorrectionReport report = CorrectFiducialPlate(&file, Options(plate, ReseauFitModel::kAffine));
    ASSERT_TRUE(report.fiducial);
    EXPECT_EQ(report.fiducial->fit.used, 7) << bad;
    EXPECT_EQ(report.fiducial->fit.rejected, 1) << bad;
    Tally passpoints;
    for (const MeasuredPoint& p : file.points) {
      const bool flagged = std::find(p.flags.begin(), p.flags.end(), "fiducial_orientation:rejected") != p.flags.end();
      EXPECT_EQ(flagged, p.kind == PointKind::kFiducial && p.id == bad) << p.id;
      if (p.kind == PointKind::kPasspoint) passpoints.Add(p, *truth.at(p.id));
    }
    EXPECT_LT(passpoints.RmsErrorUm(), 1.5 * passpoints.RmsSigmaUm()) << bad;
    std::map<std::string, std::string> params(file.header.corrections.back().parameters.begin(),
                                              file.header.corrections.back().parameters.end());
    EXPECT_EQ(params["rejected_ids"], bad);
    double worst_used = 0.0, rejected_value = 0.0;
    for (size_t i = 0; i < report.fiducial->observations.size(); ++i) {
      const double v = report.fiducial->leave_one_out[i];
      if (report.fiducial->fit.is_rejected[i]) rejected_value = v; else worst_used = std::max(worst_used, v);
    }
    std::cout << "sn004, " << bad << " shifted 50 um: leave-one-out " << rejected_value
              << " sigmas, largest kept " << worst_used << ", sigma0 " << report.fiducial->fit.sigma0 << "\n";
    EXPECT_LT(worst_used, 4.0);
  }
  // Without the shift nothing is rejected.
  MeasurementFile clean = Measure(plate, 21);
  EXPECT_EQ(CorrectFiducialPlate(&clean, Options(plate, ReseauFitModel::kAffine)).fiducial->fit.rejected, 0);
}

TEST(FiducialOrientation, EmulsionDepthBeforeTheFiducialFit) {
  // SN-004's 76 mm lens: 21 um deep at 1.65 bends the marks 60 mm out by
  // about 8.5 um, and not linearly in r, so an affine fit leaves part of it.
  const sim::SimulatedPlate plate = Plate("sn004-terrain", 21.0);
  const auto truth = TruthById(plate);
  // Noisy draws: within the sigmas; noise-free: the correction removes what
  // the affine fit cannot.
  Tally with, without, exact_with, exact_without;
  for (unsigned draw = 0; draw < 6; ++draw) {
    const bool exact = draw == 5;
    for (bool correct : {true, false}) {
      MeasurementFile file = Measure(plate, 40 + draw, "", 0.0, exact ? 0.0 : kSigmaPx);
      PlateCorrectionOptions o = Options(plate, ReseauFitModel::kAffine);
      if (correct) {
        o.emulsion = {21.0, 1.65, plate.chain.emulsion.principal_distance_mm};
        o.principal_point_x_mm = plate.chain.emulsion.principal_point_mm.x_mm;
        o.principal_point_y_mm = plate.chain.emulsion.principal_point_mm.y_mm;
      }
      CorrectFiducialPlate(&file, o);
      if (correct) {
        ASSERT_EQ(file.header.corrections[2].name, "emulsion_depth");
      }
      Tally& tally = exact ? (correct ? exact_with : exact_without) : (correct ? with : without);
      for (const MeasuredPoint& p : file.points) {
        if (p.kind == PointKind::kPasspoint) tally.Add(p, *truth.at(p.id));
      }
    }
  }
  std::cout << "sn004 at 21 um: passpoints rms error " << with.RmsErrorUm() << " um (uncorrected "
            << without.RmsErrorUm() << "), rms sigma " << with.RmsSigmaUm() << " um; noise-free "
            << exact_with.RmsErrorUm() << " um (uncorrected " << exact_without.RmsErrorUm() << ")\n";
  EXPECT_LT(with.RmsErrorUm(), 1.5 * with.RmsSigmaUm());
  EXPECT_LT(exact_with.RmsErrorUm(), 0.05);
  EXPECT_GT(exact_without.RmsErrorUm(), 4.0 * exact_with.RmsErrorUm());
}

TEST(FiducialOrientation, NoRejectionWithoutRedundancy) {
  // Four corners and an affine model: 8 coordinates, 6 parameters; dropping
  // one would leave none to judge it by, so a shifted corner stays (and shows
  // in sigma0).
  const sim::SimulatedPlate plate = Plate("hasselblad-500");
  MeasurementFile file = Measure(plate, 5, "UL", 50.0 / plate.pixel_size_um);
  const PlateCorrectionReport report = CorrectFiducialPlate(&file, Options(plate, ReseauFitModel::kAffine));
  EXPECT_EQ(report.fiducial->fit.rejected, 0);
  EXPECT_GT(report.fiducial->fit.sigma0, 3.0);
}

TEST(FiducialOrientation, TooFewFiducialsThrow) {
  const sim::SimulatedPlate plate = Plate("hasselblad-500");
  MeasurementFile file = Measure(plate, 2);
  std::erase_if(file.points, [](const MeasuredPoint& p) { return p.id == "UL" || p.id == "LR"; });
  EXPECT_THROW(CorrectFiducialPlate(&file, Options(plate, ReseauFitModel::kAffine)), Error);
  PlateCorrectionOptions projective = Options(plate, ReseauFitModel::kProjective);
  MeasurementFile file2 = Measure(plate, 2);
  EXPECT_THROW(CorrectFiducialPlate(&file2, projective), Error);
}

TEST(FiducialOrientation, ReseauCameraSwitchAddsTheStepAfterTheReseau) {
  const sim::SimulatedPlate plate = Plate("sn004-terrain");
  const auto truth = TruthById(plate);
  MeasurementFile file = Measure(plate, 31);
  PlateCorrectionOptions o = Options(plate, ReseauFitModel::kSimilarity);
  o.fiducial_orientation = true;
  const PlateCorrectionReport report = CorrectPlate(&file, *Registry().FindGrid("ikogon-b"), o);
  ASSERT_TRUE(report.fiducial);
  EXPECT_EQ(report.fiducial->fit.used, 8);
  ASSERT_GE(file.header.corrections.size(), 3u);
  EXPECT_EQ(file.header.corrections.back().name, "fiducial_orientation");
  EXPECT_EQ(file.header.corrections[file.header.corrections.size() - 2].name, "local_reseau");
  Tally passpoints, fiducials;
  for (const MeasuredPoint& p : file.points) {
    if (p.kind == PointKind::kPasspoint) passpoints.Add(p, *truth.at(p.id));
    if (p.kind == PointKind::kFiducial) fiducials.Add(p, *truth.at(p.id));
  }
  std::cout << "sn004 reseau + fiducials: passpoints rms error " << passpoints.RmsErrorUm() << " um, rms sigma "
            << passpoints.RmsSigmaUm() << " um; fiducials " << fiducials.RmsErrorUm() << " / "
            << fiducials.RmsSigmaUm() << " um\n";
  EXPECT_LT(passpoints.RmsErrorUm(), 1.5 * passpoints.RmsSigmaUm());
}

TEST(FiducialOrientation, MeasureCliGivesCameraMmForAFiducialOnlyCamera) {
  // A rendered Hasselblad plate (blur and sensor noise): detect finds the
  // format corners, measure maps them into camera mm (seed 000: the 55 mm
  // format, corners at +-27.5 mm).
  testing::TempDir dir;
  {
    std::ofstream spec(dir.file("plate.toml"));
    spec << R"(name = "h"
camera = "hasselblad-500"
seed = 4
[output]
pixel_size_um = 40.0
[film]
affine_ppm = [40.0, 10.0, -6.0, -25.0]
[scanner]
rotation_deg = 0.4
non_orthogonality_arcsec = 25.0
[noise]
blur_sigma_um = 10.0
sensor_sigma_dn = 100.0
)";
  }
  ASSERT_EQ(testing::RunPlatemeter("simulate " + dir.file("plate.toml") + " -o " + dir.file("sim")).exit_code, 0);
  const testing::CommandResult m = testing::RunPlatemeter("measure " + dir.file("sim/h.tif") +
                                                          " --camera hasselblad-500 --orientation 0 --fiducial-model similarity -o " +
                                                          dir.file("out"));
  ASSERT_EQ(m.exit_code, 0) << m.err;
  EXPECT_NE(m.out.find("fiducial orientation (similarity): 4 fiducials"), std::string::npos) << m.out;
  const MeasurementFile file = ReadMeasurementFile(dir.file("out/h.measurements.csv"));
  ASSERT_FALSE(file.header.corrections.empty());
  EXPECT_EQ(file.header.corrections.back().name, "fiducial_orientation");
  int corners = 0;
  for (const MeasuredPoint& p : file.points) {
    if (p.kind != PointKind::kFiducial) continue;
    ASSERT_TRUE(p.x_mm && p.y_mm) << p.id;
    EXPECT_NEAR(std::abs(*p.x_mm), 27.5, 0.003) << p.id;
    EXPECT_NEAR(std::abs(*p.y_mm), 27.5, 0.003) << p.id;
    EXPECT_EQ(*p.x_mm < 0, p.id[1] == 'L') << p.id;
    EXPECT_EQ(*p.y_mm > 0, p.id[0] == 'U') << p.id;
    ++corners;
  }
  EXPECT_EQ(corners, 4);
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/h.measure.json")));
}

}  // namespace
}  // namespace platemeter
