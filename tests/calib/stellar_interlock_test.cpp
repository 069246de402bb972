// Two cameras exposed together on the stars (seed 004's SMAC), simulated:
// the joint adjustment recovers both lenses and the interlock, and the
// interlock's printed sigmas match the spread of its errors over re-noised sets.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "platemeter/calib/stellar_interlock.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"

namespace platemeter {
namespace {

using testing::BeltsvillePlate;

constexpr double kRadToArcsec = 180.0 * 3600.0 / M_PI;

// A mount of two Orbigon-like cameras 96 deg apart (as SN-004's terrain and
// stellar cameras): camera A looks north at 48 deg altitude, camera B south at
// 48 deg with its own roll, and a lens of its own (principal distance and
// point moved off the Orbigon's).
struct MountTruth {
  std::vector<sim::StellarTruthPlate> a, b;  // per exposure
  Eigen::Matrix3d b_from_a = Eigen::Matrix3d::Identity();
};

MountTruth SimulateMount(const std::vector<std::string>& starts_utc, double magnitude_limit) {
  const DefinitionRegistry registry;
  const CameraDefinition lens_a = registry.Camera("orbigon");
  CameraDefinition lens_b = lens_a;
  lens_b.lens->principal_distance_mm += 0.6;
  lens_b.lens->principal_point_x_mm += 0.040;
  lens_b.lens->principal_point_y_mm -= 0.025;
  MountTruth truth;
  for (size_t e = 0; e < starts_utc.size(); ++e) {
    sim::StellarPlateSimulation a = BeltsvillePlate("A" + std::to_string(e + 1), starts_utc[e], 0.0);
    a.field.axis_azimuth_deg = 0.0;
    a.field.axis_altitude_deg = 48.0;
    a.magnitude_limit = magnitude_limit;
    sim::StellarPlateSimulation b = a;
    b.plate_id = "B" + std::to_string(e + 1);
    b.field.axis_azimuth_deg = 180.0;
    b.field.roll_deg = 30.0;
    truth.a.push_back(sim::SimulateStellarTruth(a, lens_a));
    truth.b.push_back(sim::SimulateStellarTruth(b, lens_b));
  }
  truth.b_from_a = truth.b[0].camera_from_enu * truth.a[0].camera_from_enu.transpose();
  return truth;
}

struct NoisyMount {
  std::vector<InterlockExposure> exposures;
  StellarCatalog catalog;
};

NoisyMount Noisy(const MountTruth& truth, uint64_t seed) {
  NoisyMount out;
  for (size_t e = 0; e < truth.a.size(); ++e) {
    const sim::NoisyStellarPlate a = sim::Noisy(truth.a[e], {.seed = seed * 100 + 2 * e});
    const sim::NoisyStellarPlate b = sim::Noisy(truth.b[e], {.seed = seed * 100 + 2 * e + 1});
    out.exposures.push_back({std::to_string(e + 1), {a.plate, b.plate}});
    out.catalog.insert(a.catalog.begin(), a.catalog.end());
    out.catalog.insert(b.catalog.begin(), b.catalog.end());
  }
  return out;
}

StellarInterlockResult Adjust(const NoisyMount& noisy) {
  StellarOptions options;
  options.orientation_sets = 2;
  return RunStellarInterlock({"A", "B"}, {NominalStellarCamera(80.2), NominalStellarCamera(80.2)},
                             noisy.exposures, noisy.catalog, options);
}

// Angle errors of the interlock (rad): the rotation from the truth to the estimate.
Eigen::Vector3d AngleErrors(const CameraInterlockResult& r, const Eigen::Matrix3d& truth) {
  const OmegaPhiKappa t = OmegaPhiKappaFromMatrix(truth);
  return Eigen::Vector3d(std::remainder(r.angles.angles.omega_rad - t.omega_rad, 2 * M_PI),
                         std::remainder(r.angles.angles.phi_rad - t.phi_rad, 2 * M_PI),
                         std::remainder(r.angles.angles.kappa_rad - t.kappa_rad, 2 * M_PI));
}

TEST(StellarInterlock, RecoversBothLensesAndTheInterlock) {
  const MountTruth truth = SimulateMount({"1972-05-12T05:30:00Z", "1972-05-12T07:00:00Z", "1972-04-09T06:10:00Z"}, 6.0);
  const StellarInterlockResult r = Adjust(Noisy(truth, 3));
  std::printf("%s\n", r.adjustment.summary.c_str());
  ASSERT_EQ(r.cameras.size(), 2u);
  ASSERT_EQ(r.interlocks.size(), 1u);
  EXPECT_GT(r.adjustment.sigma0, 0.9);
  EXPECT_LT(r.adjustment.sigma0, 1.1);
  const std::vector<const sim::StellarTruthPlate*> lens_truth = {&truth.a[0], &truth.b[0]};
  for (int k = 0; k < 2; ++k) {
    const InterlockCameraResult& c = r.cameras[k];
    std::printf("camera %s: %d plates, %d stars, %d images, %d rejected, rms %.2f um\n", c.name.c_str(), c.plates,
                c.stars, c.images, c.rejected_images, c.rms_residual_um);
    for (int i = 0; i < kStellarCameraParams; ++i) {
      double difference = c.camera[i] - lens_truth[k]->camera[i];
      if (i == 10) difference = std::remainder(difference, 2 * M_PI);
      const double z = difference / c.camera_sigma[i];
      std::printf("  %-10s %14.8g truth %14.8g sigma %10.3g z %6.2f\n", kStellarCameraParamNames[i], c.camera[i],
                  lens_truth[k]->camera[i], c.camera_sigma[i], z);
      EXPECT_LT(std::abs(z), 3.0) << c.name << " " << kStellarCameraParamNames[i];
    }
  }
  const CameraInterlockResult& interlock = r.interlocks[0];
  std::printf("%s\n", interlock.angles.summary.c_str());
  const Eigen::Vector3d error = AngleErrors(interlock, truth.b_from_a);
  const double sigmas[3] = {interlock.angles.omega_sigma_arcsec, interlock.angles.phi_sigma_arcsec,
                            interlock.angles.kappa_sigma_arcsec};
  for (int i = 0; i < 3; ++i) {
    std::printf("  angle %d error %.2f\" sigma %.2f\"\n", i, error[i] * kRadToArcsec, sigmas[i]);
    EXPECT_GT(sigmas[i], 0.0);
    EXPECT_LT(std::abs(error[i] * kRadToArcsec), 3.0 * sigmas[i]) << "angle " << i;
  }
  // The element covariance is the angles' propagated: its trace is positive and
  // the matrix is a rotation.
  EXPECT_NEAR((interlock.matrix.transpose() * interlock.matrix - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_GT(interlock.element_covariance.trace(), 0.0);
}

// 50 re-noised measurement sets of two exposures (images and catalog places):
// the spread of each interlock angle's error and of camera B's c, xp, yp
// within 25 % of the mean predicted sigma.
TEST(StellarInterlock, MonteCarloSigmasMatchTheSpread) {
  const MountTruth truth = SimulateMount({"1972-05-12T05:30:00Z", "1972-04-09T06:10:00Z"}, 5.5);
  constexpr int kReplicates = 50;
  Eigen::ArrayXXd error(kReplicates, 6), sigma(kReplicates, 6);
  for (int rep = 0; rep < kReplicates; ++rep) {
    const StellarInterlockResult r = Adjust(Noisy(truth, 1000 + rep));
    const CameraInterlockResult& interlock = r.interlocks[0];
    const Eigen::Vector3d e = AngleErrors(interlock, truth.b_from_a) * kRadToArcsec;
    const InterlockAngles& a = interlock.angles;
    const InterlockCameraResult& b = r.cameras[1];
    error.row(rep) << e[0], e[1], e[2], b.camera[0] - truth.b[0].camera[0], b.camera[1] - truth.b[0].camera[1],
        b.camera[2] - truth.b[0].camera[2];
    sigma.row(rep) << a.omega_sigma_arcsec, a.phi_sigma_arcsec, a.kappa_sigma_arcsec, b.camera_sigma[0],
        b.camera_sigma[1], b.camera_sigma[2];
  }
  const char* names[6] = {"omega", "phi", "kappa", "B c_mm", "B xp_mm", "B yp_mm"};
  for (int i = 0; i < 6; ++i) {
    const double spread = std::sqrt(error.col(i).square().mean());  // about the truth
    const double predicted = sigma.col(i).mean();
    std::printf("%-8s spread %.4g predicted %.4g ratio %.3f mean error %.3g\n", names[i], spread, predicted,
                spread / predicted, error.col(i).mean());
    EXPECT_NEAR(spread / predicted, 1.0, 0.25) << names[i];
  }
}

}  // namespace
}  // namespace platemeter
