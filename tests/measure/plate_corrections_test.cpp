// The corrections end to end on simulator plates with exact truth: the true
// pixel positions of the truth file, perturbed by Gaussian noise of the
// stated sigmas (the detector's job is tested in detect/), go through
// CorrectPlate and must come back to the true plate positions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <string>

#include "platemeter/grids/registry.h"
#include "platemeter/measure/double_measurement.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/plate_corrections.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

constexpr double kSigmaPxPlate = 0.05;  // px; 2 um at 40 um pixels

// Orbigon plate, 40 um pixels, seed 001's temperature and emulsion depth,
// film deformation (affine + a wave), an oblique scanner.
// The wave: a short one (2 um, 30 mm) barely projects on the affine part; a
// long one (8 um, 80 mm) is what the local reseau correction is for.
std::string PlateSpec(double pixel_aspect, const std::string& film_affine, bool long_wave = false,
                      int orientation_deg = 0) {
  return R"(
name = "t"
camera = "orbigon"
seed = 5
[output]
pixel_size_um = 40.0
[thermal]
temperature_degC = 22.0
[emulsion]
depth_um = 21.0
refractive_index = 1.65
[film]
affine_ppm = )" + film_affine + R"(
[[film.wave]]
amplitude_um = )" + std::string(long_wave ? "[8.0, -6.0]" : "[2.0, -1.5]") + R"(
wavelength_mm = )" + std::string(long_wave ? "80.0" : "30.0") + R"(
direction_deg = 30.0
[scanner]
pixel_aspect = )" + std::to_string(pixel_aspect) + R"(
rotation_deg = 0.3
orientation_deg = )" + std::to_string(orientation_deg) + R"(
non_orthogonality_arcsec = 20.0
[passpoints]
count = 40
)";
}

struct Measured {
  sim::SimulatedPlate plate;
  MeasurementFile file;
};

Measured MeasureWithNoise(const std::string& spec_text, unsigned seed, const std::string& orientation = "0") {
  Measured m{sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec_text, "t.toml"), DefinitionRegistry()), {}};
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kSigmaPxPlate);
  m.file.header.plate_id = "t";
  m.file.header.camera = "orbigon";
  m.file.header.pixel_size_um = m.plate.pixel_size_um;
  m.file.header.extra.push_back({"orientation", orientation});
  for (const MeasuredPoint& t : m.plate.truth) {
    MeasuredPoint p;
    p.id = t.id;
    p.kind = t.kind;
    p.x_px = *t.x_px + noise(rng);
    p.y_px = *t.y_px + noise(rng);
    p.sigma_x_px = kSigmaPxPlate;
    p.sigma_y_px = kSigmaPxPlate;
    m.file.points.push_back(p);
  }
  return m;
}

PlateCorrectionOptions OptionsFor(const sim::SimulatedPlate& plate, bool emulsion) {
  PlateCorrectionOptions o;
  o.temperature_degC = plate.chain.thermal.temperature_degC;
  o.calibration_temperature_degC = plate.chain.thermal.calibration_temperature_degC;
  o.expansion_per_degC = plate.chain.thermal.expansion_per_degC;
  o.emulsion = {emulsion ? 21.0 : 0.0, 1.65, plate.chain.emulsion.principal_distance_mm};
  o.principal_point_x_mm = plate.chain.emulsion.principal_point_mm.x_mm;
  o.principal_point_y_mm = plate.chain.emulsion.principal_point_mm.y_mm;
  return o;
}

const MasterGrid& Orbigon() {
  static const DefinitionRegistry registry;
  return *registry.FindGrid("orbigon-reseau");
}

TEST(PlateCorrections, RecoversPlateCoordinatesWithinTheirSigmas) {
  Measured m = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]", true), 11);
  const PlateCorrectionReport report = CorrectPlate(&m.file, Orbigon(), OptionsFor(m.plate, true));
  EXPECT_EQ(report.fit.rejected, 0);
  std::map<std::string, const MeasuredPoint*> truth;
  for (const MeasuredPoint& t : m.plate.truth) truth[t.id] = &t;
  double err2 = 0.0, sig2 = 0.0;
  int n = 0;
  for (const MeasuredPoint& p : m.file.points) {
    if (p.kind != PointKind::kPasspoint) continue;
    ASSERT_TRUE(p.x_mm && p.sigma_x_mm) << p.id;
    const MeasuredPoint& t = *truth.at(p.id);
    err2 += std::pow(*p.x_mm - *t.x_mm, 2) + std::pow(*p.y_mm - *t.y_mm, 2);
    sig2 += std::pow(*p.sigma_x_mm, 2) + std::pow(*p.sigma_y_mm, 2);
    ++n;
  }
  ASSERT_EQ(n, 40);
  const double rms_err = std::sqrt(err2 / (2 * n)), rms_sigma = std::sqrt(sig2 / (2 * n));
  // The propagated sigma: 2 um measured, plus the interpolated corner residuals.
  EXPECT_GT(rms_sigma, 0.002);
  EXPECT_LT(rms_sigma, 0.0035);
  std::cout << "passpoints: rms error " << rms_err * 1e3 << " um, rms propagated sigma " << rms_sigma * 1e3 << " um\n";
  EXPECT_LT(rms_err, 1.5 * rms_sigma) << "rms error " << rms_err << " mm, rms sigma " << rms_sigma << " mm";
  // Without the local correction the wave (8 um) stays in: a much larger error.
  Measured m2 = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]", true), 11);
  PlateCorrectionOptions no_local = OptionsFor(m2.plate, true);
  no_local.local_reseau = false;
  CorrectPlate(&m2.file, Orbigon(), no_local);
  double err2_global = 0.0;
  for (const MeasuredPoint& p : m2.file.points) {
    if (p.kind != PointKind::kPasspoint) continue;
    const MeasuredPoint& t = *truth.at(p.id);
    err2_global += std::pow(*p.x_mm - *t.x_mm, 2) + std::pow(*p.y_mm - *t.y_mm, 2);
  }
  EXPECT_GT(std::sqrt(err2_global / (2 * n)), 1.5 * rms_err);
}

// A glass plate (affine film, no wave): the reseau residuals are measuring
// noise, the chi-square test does not reject it and the local correction is
// left out; forced on, it would carry the corner crosses' noise into every
// passpoint (a larger error than its own). With the 8 um wave it is applied.
TEST(PlateCorrections, LocalReseauCorrectionOnlyWhereTheFilmIsDeformed) {
  std::string rigid = PlateSpec(1.0002, "[3.0, 0.0, 0.0, 2.0]");
  rigid.replace(rigid.find("[2.0, -1.5]"), 11, "[0.0, 0.0]");
  double err2_tested = 0.0, err2_forced = 0.0;
  int n = 0;
  for (unsigned seed = 31; seed < 36; ++seed) {
    Measured tested = MeasureWithNoise(rigid, seed), forced = MeasureWithNoise(rigid, seed);
    const PlateCorrectionReport report = CorrectPlate(&tested.file, Orbigon(), OptionsFor(tested.plate, true));
    EXPECT_FALSE(report.local_reseau_applied) << "seed " << seed << " p " << report.reseau_p_value;
    EXPECT_GT(report.reseau_p_value, 0.01);
    EXPECT_EQ(report.reseau_dof, 2 * report.fit.used - report.fit.parameter_count);
    const AppliedCorrection& record = tested.file.header.corrections.back();
    ASSERT_EQ(record.name, "local_reseau");
    EXPECT_EQ(record.parameters[1].first, "applied");
    EXPECT_EQ(record.parameters[1].second, "no");
    PlateCorrectionOptions always = OptionsFor(forced.plate, true);
    always.local_reseau_significance = 1.0 - 1e-12;  // any chi-square rejects: the correction runs
    ASSERT_TRUE(CorrectPlate(&forced.file, Orbigon(), always).local_reseau_applied);
    std::map<std::string, const MeasuredPoint*> truth;
    for (const MeasuredPoint& t : tested.plate.truth) truth[t.id] = &t;
    for (size_t k = 0; k < tested.file.points.size(); ++k) {
      const MeasuredPoint& p = tested.file.points[k];
      if (p.kind != PointKind::kPasspoint) continue;
      EXPECT_TRUE(p.flags.empty()) << p.id;
      const MeasuredPoint& t = *truth.at(p.id);
      const MeasuredPoint& f = forced.file.points[k];
      err2_tested += std::pow(*p.x_mm - *t.x_mm, 2) + std::pow(*p.y_mm - *t.y_mm, 2);
      err2_forced += std::pow(*f.x_mm - *t.x_mm, 2) + std::pow(*f.y_mm - *t.y_mm, 2);
      ++n;
    }
  }
  ASSERT_EQ(n, 200);
  std::cout << "rigid plate: passpoint rms error " << std::sqrt(err2_tested / (2 * n)) * 1e3 << " um tested, "
            << std::sqrt(err2_forced / (2 * n)) * 1e3 << " um with the local correction forced\n";
  EXPECT_GT(err2_forced, 1.1 * err2_tested);

  Measured waved = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]", true), 11);
  const PlateCorrectionReport report = CorrectPlate(&waved.file, Orbigon(), OptionsFor(waved.plate, true));
  EXPECT_TRUE(report.local_reseau_applied);
  EXPECT_LT(report.reseau_p_value, 1e-6);
}

TEST(PlateCorrections, FittedScalesAndNonOrthogonalityMatchTheTrueChain) {
  Measured m = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]"), 12);
  const PlateCorrectionReport report = CorrectPlate(&m.file, Orbigon(), OptionsFor(m.plate, true));
  // The true linear map grid -> comparator with thermal and emulsion removed:
  // comparator (mm per px) x scanner (px per mm) x film (I + 1e-6 A).
  const sim::ScannerStep& s = m.plate.chain.scanner;
  const sim::Matrix2 px_per_mm = s.PixelPerMm();
  const double p_mm = m.plate.pixel_size_um * 1e-3;
  const double* a = m.plate.chain.film.affine_ppm;
  const sim::Matrix2 film{{1 + 1e-6 * a[0], 1e-6 * a[1], 1e-6 * a[2], 1 + 1e-6 * a[3]}};
  const sim::Matrix2 t = sim::Matrix2{{p_mm, 0, 0, -p_mm}} * px_per_mm * film;
  // diag(sx, sy) K(eps) R: rows have lengths |sx| / cos eps and sy / cos eps
  // and the sine of the angle between them is sin eps.
  const double r1 = std::hypot(t(0, 0), t(0, 1)), r2 = std::hypot(t(1, 0), t(1, 1));
  const double eps = std::asin((t(0, 0) * t(1, 0) + t(0, 1) * t(1, 1)) / (r1 * r2));
  const double sx = r1 * std::cos(eps), sy = r2 * std::cos(eps);
  std::cout << "sx - true " << (report.fit.scale_x.value - sx) / report.fit.scale_x.sigma << " sigma, sy - true "
            << (report.fit.scale_y.value - sy) / report.fit.scale_y.sigma << " sigma, eps - true "
            << (report.fit.non_orthogonality_rad.value - eps) / report.fit.non_orthogonality_rad.sigma
            << " sigma (sigma_sx " << report.fit.scale_x.sigma << ", sigma_eps "
            << report.fit.non_orthogonality_rad.sigma * 206264.806 << " arcsec)\n";
  EXPECT_NEAR(report.fit.scale_x.value, sx, 2 * report.fit.scale_x.sigma);
  EXPECT_NEAR(report.fit.scale_y.value, sy, 2 * report.fit.scale_y.sigma);
  EXPECT_NEAR(report.fit.non_orthogonality_rad.value, eps, 2 * report.fit.non_orthogonality_rad.sigma);
  // The sigmas are those of 121 crosses at 2 um over +-50 mm: a few ppm / arcsec, not more.
  EXPECT_LT(report.fit.scale_x.sigma, 2e-5);
  EXPECT_GT(report.fit.scale_x.sigma, 1e-7);
  // The scanner's 20 arcsec dominate eps: the fit sees them.
  EXPECT_NEAR(eps, 20.0 / 206264.806, 15.0 / 206264.806);
}

TEST(PlateCorrections, ScaleDiscrepancyReadsAsTheEmulsionDepth) {
  // Square pixels and a trace-free film affine: without the emulsion
  // correction the mean scale is the emulsion's (the validation's reading).
  Measured m = MeasureWithNoise(PlateSpec(1.0, "[10.0, 0.0, 0.0, -10.0]"), 13);
  const PlateCorrectionReport report = CorrectPlate(&m.file, Orbigon(), OptionsFor(m.plate, false));
  std::cout << "emulsion depth reading " << report.emulsion_depth_reading_um.value << " +- "
            << report.emulsion_depth_reading_um.sigma << " um (mean scale " << report.fit.mean_scale.value << ")\n";
  EXPECT_NEAR(report.emulsion_depth_reading_um.value, 21.0, 2 * report.emulsion_depth_reading_um.sigma + 0.5);
  EXPECT_LT(report.emulsion_depth_reading_um.sigma, 3.0);
  EXPECT_GT(report.fit.mean_scale.value, 1.0001);
}

TEST(PlateCorrections, OutliersAreRejectedAndFlagged) {
  Measured m = MeasureWithNoise(PlateSpec(1.0, "[0.0, 0.0, 0.0, 0.0]"), 14);
  for (MeasuredPoint& p : m.file.points) {
    if (p.id == "X3Y7") *p.x_px += 1.0;  // 40 um
    if (p.id == "X9Y2") *p.y_px -= 0.8;  // 32 um
  }
  const PlateCorrectionReport report = CorrectPlate(&m.file, Orbigon(), OptionsFor(m.plate, true));
  EXPECT_EQ(report.fit.rejected, 2);
  for (const MeasuredPoint& p : m.file.points) {
    const bool flagged = std::find(p.flags.begin(), p.flags.end(), "reseau_fit:rejected") != p.flags.end();
    EXPECT_EQ(flagged, p.id == "X3Y7" || p.id == "X9Y2") << p.id;
  }
}

TEST(PlateCorrections, FileRoundTripsWithTheNewColumnsAndCorrections) {
  Measured m = MeasureWithNoise(PlateSpec(1.0, "[0.0, 0.0, 0.0, 0.0]"), 15);
  CorrectPlate(&m.file, Orbigon(), OptionsFor(m.plate, true));
  const MeasurementFile back = ParseMeasurementFile(FormatMeasurementFile(m.file), "t.csv");
  ASSERT_EQ(back.points.size(), m.file.points.size());
  for (size_t i = 0; i < back.points.size(); ++i) {
    EXPECT_EQ(back.points[i].x_mm, m.file.points[i].x_mm);
    EXPECT_EQ(back.points[i].sigma_y_mm, m.file.points[i].sigma_y_mm);
    EXPECT_EQ(back.points[i].flags, m.file.points[i].flags);
  }
  ASSERT_EQ(back.header.corrections.size(), 5u);
  const char* order[] = {"comparator", "thermal", "emulsion_depth", "reseau_fit", "local_reseau"};
  for (int k = 0; k < 5; ++k) EXPECT_EQ(back.header.corrections[k].name, order[k]);
  EXPECT_EQ(back.header.corrections[1].parameters, m.file.header.corrections[1].parameters);
}

TEST(PlateCorrections, DoubleMeasurementMeansTwoScansRotated180Degrees) {
  // The same plate (same film deformation) scanned twice, the second time
  // turned 180 degrees, each with its own noise.
  Measured a = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]", true, 0), 21, "0");
  Measured b = MeasureWithNoise(PlateSpec(1.0002, "[30.0, 5.0, -8.0, -20.0]", true, 180), 22, "180");
  CorrectPlate(&a.file, Orbigon(), OptionsFor(a.plate, true));
  CorrectPlate(&b.file, Orbigon(), OptionsFor(b.plate, true));
  const MeasurementFile single = a.file;
  const DoubleMeasurementReport report = MeanDoubleMeasurement(&a.file, b.file);
  EXPECT_EQ(report.paired, 121 + 40);
  EXPECT_EQ(report.only_first, 0);
  // Independent errors with the propagated sigmas: the normalized
  // discrepancies have an RMS near 1 (322 values: 1 +- 0.04; the film
  // deformation is the same in both scans and cancels in the differences).
  EXPECT_GT(report.rms_normalized, 0.5);
  EXPECT_LT(report.rms_normalized, 1.3);
  std::map<std::string, const MeasuredPoint*> truth;
  for (const MeasuredPoint& t : a.plate.truth) truth[t.id] = &t;
  double err2_mean = 0.0, err2_single = 0.0, sig2 = 0.0;
  int n = 0;
  for (size_t i = 0; i < a.file.points.size(); ++i) {
    const MeasuredPoint& p = a.file.points[i];
    if (p.kind != PointKind::kPasspoint) continue;
    const MeasuredPoint& t = *truth.at(p.id);
    err2_mean += std::pow(*p.x_mm - *t.x_mm, 2) + std::pow(*p.y_mm - *t.y_mm, 2);
    err2_single += std::pow(*single.points[i].x_mm - *t.x_mm, 2) + std::pow(*single.points[i].y_mm - *t.y_mm, 2);
    sig2 += std::pow(*p.sigma_x_mm, 2) + std::pow(*p.sigma_y_mm, 2);
    ++n;
  }
  const double rms_mean = std::sqrt(err2_mean / (2 * n)), rms_sigma = std::sqrt(sig2 / (2 * n));
  std::cout << "double measurement: rms error " << rms_mean * 1e3 << " um (single scan "
            << std::sqrt(err2_single / (2 * n)) * 1e3 << " um), rms sigma " << rms_sigma * 1e3
            << " um, normalized discrepancy rms " << report.rms_normalized << "\n";
  EXPECT_LT(rms_mean, 1.5 * rms_sigma);
  EXPECT_LT(rms_mean, std::sqrt(err2_single / (2 * n)));
  EXPECT_EQ(a.file.header.corrections.back().name, "double_measurement");
  // The file with the mean still round-trips.
  EXPECT_NO_THROW(ParseMeasurementFile(FormatMeasurementFile(a.file), "t.csv"));
}

}  // namespace
}  // namespace platemeter
