// Stellar calibration of single simulated plates (seed 001) against the simulator's truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "platemeter/calib/stellar_plate.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"

namespace platemeter {
namespace {

using testing::BeltsvillePlate;

TEST(StellarPlate, RecoversTheTrueLensWithinThreeSigma) {
  const DefinitionRegistry registry;
  const sim::StellarTruthPlate truth =
      sim::SimulateStellarTruth(BeltsvillePlate("N1", "1972-05-12T05:30:00Z", 0.0), registry.Camera("orbigon"));
  const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = 7});
  StellarOptions options;
  const StellarPlateResult r = RunStellarPlate(noisy.plate, noisy.catalog, NominalStellarCamera(80.2), options);
  std::printf("images %d stars %d m_o %.3f dof %.0f solve %.2f s cov %.2f s sets %zu motion %.2f\"\n", r.images,
              r.catalog_stars, r.m_o, r.adjustment.dof, r.adjustment.solve_seconds, r.adjustment.covariance_seconds,
              r.orientation_sets.size(), r.largest_motion_arcsec);
  for (int i = 0; i < kStellarCameraParams; ++i) {
    double difference = r.camera[i] - truth.camera[i];
    if (i == 10) difference = std::remainder(difference, 2 * M_PI);  // Phi_T is an angle
    const double z = difference / r.camera_sigma[i];
    std::printf("%-10s %14.8g  truth %14.8g  sigma %10.3g  z %6.2f\n", kStellarCameraParamNames[i], r.camera[i],
                truth.camera[i], r.camera_sigma[i], z);
    EXPECT_LT(std::abs(z), 3.0) << kStellarCameraParamNames[i];
  }
  std::printf("%s\n", r.adjustment.summary.c_str());
}

}  // namespace
}  // namespace platemeter

namespace platemeter {
namespace {

using testing::BeltsvillePlate;

// Seed 001's data snooping: 1 % of the trail dots given a time tag 40 s off and
// 1 % of the stars swapped for their nearest catalog neighbour are all rejected
// by the robust pass, and the camera stays within 3 sigma of the truth.
TEST(StellarPlate, RejectsWrongTimeTagsAndMisidentifiedStars) {
  const DefinitionRegistry registry;
  const sim::StellarTruthPlate truth =
      sim::SimulateStellarTruth(BeltsvillePlate("S1", "1972-04-09T06:10:00Z", 180.0), registry.Camera("orbigon"));
  sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = 11});
  std::set<std::string> bad_images;
  for (size_t i = 0; i < noisy.plate.images.size(); i += 100) {  // 1 % of the dots
    noisy.plate.images[i].mid_time = noisy.plate.images[i].mid_time.PlusSeconds(40.0);
    bad_images.insert(noisy.plate.images[i].image_id);
  }
  // 1 % of the stars: every image of the star carries the id of the nearest other star of the catalog.
  std::vector<std::string> ids;
  for (const auto& [id, entry] : noisy.catalog) ids.push_back(id);
  std::map<std::string, std::string> swapped;
  for (size_t k = 0; k < ids.size(); k += 100) {
    const calib::CatalogStar& star = noisy.catalog.at(ids[k]).star;
    std::string nearest;
    double best = 1e9;
    for (const auto& [id, entry] : noisy.catalog) {
      const double d = calib::AngularSeparation(star.ra_rad, star.dec_rad, entry.star.ra_rad, entry.star.dec_rad);
      if (id != ids[k] && d < best) best = d, nearest = id;
    }
    swapped[ids[k]] = nearest;
  }
  for (StarImageObservation& image : noisy.plate.images) {
    if (swapped.count(image.star_id)) {
      bad_images.insert(image.image_id);
      image.star_id = swapped.at(image.star_id);
    }
  }
  StellarOptions options;
  options.adjustment.robust_loss_scale = 3.0;
  const StellarPlateResult r = RunStellarPlate(noisy.plate, noisy.catalog, NominalStellarCamera(80.2), options);
  std::set<std::string> rejected;
  for (const ObservationResidual& o : r.adjustment.residuals) {
    if (o.status == ObservationStatus::kRejected) rejected.insert(o.item.substr(0, o.item.find(' ')));
  }
  int missed = 0, false_alarms = 0;
  for (const std::string& id : bad_images) missed += rejected.count(id) ? 0 : 1;
  for (const std::string& id : rejected) false_alarms += bad_images.count(id) ? 0 : 1;
  std::printf("%zu bad images (%zu swapped stars), %zu rejected: %d missed, %d good ones rejected; m_o %.3f\n",
              bad_images.size(), swapped.size(), rejected.size(), missed, false_alarms, r.m_o);
  EXPECT_EQ(missed, 0);
  EXPECT_LE(false_alarms, static_cast<int>(0.01 * r.images));
  for (int i = 0; i < kStellarCameraParams; ++i) {
    double difference = r.camera[i] - truth.camera[i];
    if (i == 10) difference = std::remainder(difference, 2 * M_PI);
    EXPECT_LT(std::abs(difference / r.camera_sigma[i]), 3.0) << kStellarCameraParamNames[i];
  }
}

}  // namespace
}  // namespace platemeter
