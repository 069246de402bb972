// The stellar calibration with seed 004's and seed 000's lens models
// (stellar_lens.h): plates simulated through a lens of the model adjusted
// (the simulator projects through the definition's lens, CameraModel), so that
// every parameter has a truth: sn004-terrain's smac-radial-decentering lens
// (seed 004 Table A.4) and the same field as a brown-conrady lens (converted
// exactly, model_conversion.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "platemeter/calib/model_conversion.h"
#include "platemeter/calib/stellar_combination.h"
#include "platemeter/calib/stellar_interlock.h"
#include "platemeter/calib/stellar_plate.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"

namespace platemeter {
namespace {

using testing::BeltsvillePlate;

// sn004-terrain with its lens converted to brown-conrady (exact up to J2 r^4,
// which is 1e-20 in Table A.4).
CameraDefinition BrownTerrainCamera() {
  const DefinitionRegistry registry;
  CameraDefinition camera = registry.Camera("sn004-terrain");
  const LensEstimate smac = LensEstimateFromCalibration(*camera.lens, "sn004-terrain");
  ConversionOptions conversion;
  conversion.format_width_mm = camera.format_width_mm;
  conversion.format_height_mm = camera.format_height_mm;
  const LensConversion brown = ConvertLens(smac, DistortionModelId::kBrownConrady, conversion);
  std::printf("sn004-terrain as brown-conrady: %s\n", brown.summary.c_str());
  camera.name = "sn004-terrain-brown";
  camera.lens->model = "brown-conrady";
  camera.lens->principal_distance_mm = brown.lens.principal_distance_mm;
  camera.lens->coefficients.clear();
  camera.lens->sigmas.clear();
  const std::vector<std::string> names = StellarCameraParamNames(DistortionModelId::kBrownConrady);
  for (size_t i = 3; i < names.size(); ++i) camera.lens->coefficients[names[i]] = brown.lens.params[i - 3];
  return camera;
}

CameraDefinition TerrainCamera(DistortionModelId lens) {
  return lens == DistortionModelId::kBrownConrady ? BrownTerrainCamera()
                                                  : DefinitionRegistry().Camera("sn004-terrain");
}

// Every parameter's z against the truth (the decentering angle wrapped); returns the largest |z|.
double CheckCamera(DistortionModelId lens, const StellarCamera& value, const StellarCamera& sigma,
                   const StellarCamera& truth) {
  const std::vector<std::string> names = StellarCameraParamNames(lens);
  const int angle = StellarDecenteringSignOf(lens).angle;
  double largest = 0.0;
  for (size_t i = 0; i < names.size(); ++i) {
    double difference = value[i] - truth[i];
    if (static_cast<int>(i) == angle) difference = std::remainder(difference, 2 * M_PI);
    const double z = difference / sigma[i];
    std::printf("  %-11s %15.8g truth %15.8g sigma %10.3g z %6.2f\n", names[i].c_str(), value[i], truth[i], sigma[i], z);
    EXPECT_LT(std::abs(z), 3.0) << names[i];
    largest = std::max(largest, std::abs(z));
  }
  return largest;
}

void RecoversTheLens(DistortionModelId lens) {
  const CameraDefinition camera = TerrainCamera(lens);
  const sim::StellarTruthPlate truth =
      sim::SimulateStellarTruth(BeltsvillePlate("N1", "1972-05-12T05:30:00Z", 0.0), camera);
  ASSERT_EQ(static_cast<int>(truth.camera.size()), StellarCameraParamCount(lens));
  const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = 7});
  StellarOptions options;
  options.lens_model = lens;
  const StellarPlateResult r = RunStellarPlate(noisy.plate, noisy.catalog,
                                               NominalStellarCamera(camera.nominal_principal_distance_mm, lens), options);
  std::printf("%s: images %d stars %d m_o %.3f dof %.0f solve %.2f s\n", DistortionModelName(lens), r.images,
              r.catalog_stars, r.m_o, r.adjustment.dof, r.adjustment.solve_seconds);
  CheckCamera(lens, r.camera, r.camera_sigma, truth.camera);
  EXPECT_GT(r.m_o, 0.9);
  EXPECT_LT(r.m_o, 1.1);
}

TEST(StellarLensModel, SmacPlateRecoversTheSmacLensWithinThreeSigma) {
  RecoversTheLens(DistortionModelId::kSmacRadialDecentering);
}

TEST(StellarLensModel, BrownPlateRecoversTheBrownLensWithinThreeSigma) {
  RecoversTheLens(DistortionModelId::kBrownConrady);
}

// The weighted mean of two SMAC plates is the simultaneous solution (as for
// the orbigon-11 camera, stellar_combination_test) and recovers the lens.
TEST(StellarLensModel, SmacCombinationEqualsTheSimultaneousSolution) {
  const DistortionModelId lens = DistortionModelId::kSmacRadialDecentering;
  const CameraDefinition camera = TerrainCamera(lens);
  std::vector<StellarPlate> plates;
  StellarCatalog catalog;
  StellarCamera truth;
  for (const auto& [id, start, roll, seed] : {std::tuple{"N", "1972-05-12T05:30:00Z", 0.0, 31},
                                              std::tuple{"S", "1972-04-09T06:10:00Z", 180.0, 32}}) {
    sim::StellarPlateSimulation s = BeltsvillePlate(id, start, roll);
    s.magnitude_limit = 5.5;
    const sim::StellarTruthPlate t = sim::SimulateStellarTruth(s, camera);
    truth = t.camera;
    sim::NoisyStellarPlate noisy = sim::Noisy(t, {.seed = static_cast<uint64_t>(seed)});
    plates.push_back(std::move(noisy.plate));
    catalog.insert(noisy.catalog.begin(), noisy.catalog.end());
  }
  StellarOptions options;
  options.lens_model = lens;
  // Both solutions to their last digits. Ceres' parameter tolerance is
  // relative to the norm of all parameters (c = 76 mm dominates it), and
  // seed 004's units put J2's sigma at 6e-12 /mm^3: 1e-16 could end the
  // simultaneous solve at a step of 1e-3 sigma of J2, so it is set far below.
  options.adjustment.function_tolerance = 1e-16;
  options.adjustment.parameter_tolerance = 1e-30;
  options.adjustment.polish = true;
  const StellarCamera nominal = NominalStellarCamera(camera.nominal_principal_distance_mm, lens);
  std::vector<StellarPlateResult> singles;
  for (const StellarPlate& plate : plates) singles.push_back(RunStellarPlate(plate, catalog, nominal, options));
  const StellarCombination c = CombineStellarPlates("N+S", plates, singles, catalog, options);
  const AdjustmentResult simultaneous = SolveStellarPlatesSimultaneously(plates, catalog, nominal, options);
  std::vector<int> index;
  StellarCamera reference;
  for (const std::string& name : StellarCameraParamNames(lens)) {
    index.push_back(simultaneous.Find("camera", name));
    reference.push_back(simultaneous.parameters[index.back()].value);
  }
  Eigen::MatrixXd q = simultaneous.Covariance(index, false);
  CanonicalDecentering(&reference, &q, lens);
  double worst_value = 0.0, worst_covariance = 0.0, worst_sigma = 0.0;
  for (size_t i = 0; i < reference.size(); ++i) {
    worst_value = std::max(worst_value, std::abs(c.camera[i] - reference[i]) /
                                            std::max(std::abs(c.camera[i]), std::abs(reference[i])));
    worst_sigma = std::max(worst_sigma, std::abs(c.camera[i] - reference[i]) / std::sqrt(q(i, i)));
    for (size_t j = 0; j < reference.size(); ++j)
      worst_covariance = std::max(worst_covariance, std::abs(c.cofactor(i, j) - q(i, j)) / std::sqrt(q(i, i) * q(j, j)));
  }
  std::printf("relinearizations %d; m_0 %.6f (simultaneous %.6f); largest relative difference: values %.2e "
              "(%.2e sigma), cofactor elements %.2e\n",
              c.relinearizations, c.m_0, simultaneous.sigma0, worst_value, worst_sigma, worst_covariance);
  EXPECT_EQ(c.dof, simultaneous.dof);
  EXPECT_NEAR(c.m_0, simultaneous.sigma0, 1e-9 * simultaneous.sigma0);
  EXPECT_LT(worst_value, 1e-9);
  EXPECT_LT(worst_covariance, 1e-9);
  CheckCamera(lens, c.camera, c.camera_sigma, truth);
  EXPECT_GT(c.m_0, 0.9);
  EXPECT_LT(c.m_0, 1.1);
}

// Two Brown cameras exposed together (stellar_interlock.h): camera A looks
// north, camera B (its lens 0.6 mm longer) south, 96 deg apart, two exposures.
TEST(StellarLensModel, BrownInterlockRecoversBothLensesAndTheInterlock) {
  const DistortionModelId lens = DistortionModelId::kBrownConrady;
  const CameraDefinition a_camera = TerrainCamera(lens);
  CameraDefinition b_camera = a_camera;
  b_camera.lens->principal_distance_mm += 0.6;
  b_camera.lens->principal_point_x_mm += 0.040;
  std::vector<InterlockExposure> exposures;
  StellarCatalog catalog;
  std::vector<StellarCamera> truth(2);
  Eigen::Matrix3d b_from_a;
  int seed = 50;
  for (const char* start : {"1972-05-12T05:30:00Z", "1972-04-09T06:10:00Z"}) {
    InterlockExposure exposure{start, {}};
    for (const bool b : {false, true}) {
      sim::StellarPlateSimulation s = BeltsvillePlate((b ? "B" : "A") + std::to_string(exposures.size()), start,
                                                      b ? 30.0 : 0.0);
      s.field.axis_azimuth_deg = b ? 180.0 : 0.0;
      s.field.axis_altitude_deg = 48.0;
      s.magnitude_limit = 5.5;
      const sim::StellarTruthPlate t = sim::SimulateStellarTruth(s, b ? b_camera : a_camera);
      truth[b] = t.camera;
      if (b) b_from_a = t.camera_from_enu * b_from_a;  // camera B from camera A
      else b_from_a = t.camera_from_enu.transpose();
      sim::NoisyStellarPlate noisy = sim::Noisy(t, {.seed = static_cast<uint64_t>(++seed)});
      exposure.plates.push_back(std::move(noisy.plate));
      catalog.insert(noisy.catalog.begin(), noisy.catalog.end());
    }
    exposures.push_back(std::move(exposure));
  }
  StellarOptions options;
  options.lens_model = lens;
  options.orientation_sets = 2;
  const StellarCamera nominal = NominalStellarCamera(a_camera.nominal_principal_distance_mm, lens);
  const StellarInterlockResult r = RunStellarInterlock({"A", "B"}, {nominal, nominal}, exposures, catalog, options);
  std::printf("%s\n", r.adjustment.summary.c_str());
  ASSERT_EQ(r.cameras.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    std::printf("camera %s:\n", r.cameras[k].name.c_str());
    CheckCamera(lens, r.cameras[k].camera, r.cameras[k].camera_sigma, truth[k]);
  }
  const OmegaPhiKappa t = OmegaPhiKappaFromMatrix(b_from_a);
  const InterlockAngles& angles = r.interlocks[0].angles;
  const double error_rad[3] = {std::remainder(angles.angles.omega_rad - t.omega_rad, 2 * M_PI),
                               std::remainder(angles.angles.phi_rad - t.phi_rad, 2 * M_PI),
                               std::remainder(angles.angles.kappa_rad - t.kappa_rad, 2 * M_PI)};
  const double sigma_arcsec[3] = {angles.omega_sigma_arcsec, angles.phi_sigma_arcsec, angles.kappa_sigma_arcsec};
  for (int i = 0; i < 3; ++i) {
    const double z = error_rad[i] * 180 * 3600 / M_PI / sigma_arcsec[i];
    std::printf("interlock angle %d: sigma %.2f\" z %.2f\n", i, sigma_arcsec[i], z);
    EXPECT_LT(std::abs(z), 3.0);
  }
  EXPECT_GT(r.adjustment.sigma0, 0.9);
  EXPECT_LT(r.adjustment.sigma0, 1.1);
}

}  // namespace
}  // namespace platemeter
