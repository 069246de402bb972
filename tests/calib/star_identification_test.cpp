// Star identification from a pointing 5 degrees off and an unknown roll, on
// simulated Orbigon plates (seed 001's selection of trail dots), against the
// simulator's star ids.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/Geometry>

#include "platemeter/calib/star_identification.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"
#include "support/stellar_plates.h"

namespace platemeter {
namespace {

struct Case {
  const char* start;
  double roll_deg;
  double offset_azimuth_deg;  // direction in which the given pointing is off
  bool known_lens;            // the definition's lens as the starting camera (else 80.2 mm, no distortion)
};

void Identify(const Case& c) {
  const DefinitionRegistry registry;
  const CameraDefinition& orbigon = registry.Camera("orbigon");
  const sim::StellarPlateSimulation s = testing::BeltsvillePlate("P", c.start, c.roll_deg);
  constexpr double kDeg = M_PI / 180.0;
  const sim::StellarTruthPlate truth = sim::SimulateStellarTruth(s, orbigon);
  const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = 3});
  // The catalog a user would give: every star of the field to V = 6.5, not only the imaged ones.
  const sim::PlateLens lens(orbigon);
  StellarCatalog catalog;
  for (const calib::CatalogStar& star :
       sim::LoadFieldStars(s.field, calib::DefaultStarCatalogPath(), 6.5, lens, 114.0, 114.0))
    catalog[sim::StarId(star)] = {star, 0.4};
  // The detector's view: stars by an anonymous key.
  std::map<std::string, std::string> key_of, truth_of;
  std::vector<DetectedStarImage> images;
  for (const StarImageObservation& o : noisy.plate.images) {
    auto [it, added] = key_of.emplace(o.star_id, "S" + std::to_string(key_of.size() + 1));
    truth_of[it->second] = o.star_id;
    images.push_back({it->second, o.mid_time, o.x_mm, o.y_mm});
  }
  // The given pointing: the zenith tipped 5 deg toward `offset_azimuth_deg`.
  const double a = c.offset_azimuth_deg * kDeg;
  const Eigen::Vector3d axis(std::sin(5 * kDeg) * std::sin(a), std::sin(5 * kDeg) * std::cos(a), std::cos(5 * kDeg));
  const StellarCamera camera = c.known_lens ? StellarCameraFromModel(lens.model(), lens.printed_left_handed())
                                            : NominalStellarCamera(80.2);
  const IdentificationResult r = IdentifyStars(images, catalog, s.field.place, axis, camera);
  int wrong = 0;
  for (const auto& [key, id] : r.catalog_id) wrong += id == truth_of.at(key) ? 0 : 1;
  const double share = static_cast<double>(r.catalog_id.size()) / key_of.size();
  const double axis_error_deg =
      std::acos(std::clamp(r.camera_from_enu.row(2).dot(truth.camera_from_enu.row(2)), -1.0, 1.0)) / kDeg;
  std::printf("%s roll %.0f: %zu stars, %zu identified (%.1f %%), %d wrong, %zu unknown (%zu ambiguous); "
              "%d hypotheses, %d pattern matches, false alarm %.1e; rms %.1f\", axis off %.4f deg\n",
              c.start, c.roll_deg, key_of.size(), r.catalog_id.size(), 100 * share, wrong, r.unknown.size(),
              r.ambiguous.size(), r.hypotheses_tried, r.pattern_matches, r.false_alarm_probability, r.rms_arcsec,
              axis_error_deg);
  for (const std::string& key : r.ambiguous) {
    const calib::CatalogStar& t = catalog.at(truth_of.at(key)).star;
    double best = 1e9; std::string other;
    for (const auto& [id, e] : catalog) {
      if (id == truth_of.at(key)) continue;
      const double d = calib::AngularSeparation(t.ra_rad, t.dec_rad, e.star.ra_rad, e.star.dec_rad) * 206265;
      if (d < best) best = d, other = id;
    }
    std::printf("  ambiguous %s = %s V %.2f: nearest other %s at %.0f\" V %.2f\n", key.c_str(), truth_of.at(key).c_str(), t.v_mag, other.c_str(), best, catalog.at(other).star.v_mag);
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(share, 0.98);
}

TEST(StarIdentification, PointingFiveDegreesOffUnknownRoll) {
  Identify({"1972-05-12T05:30:00Z", 0.0, 30.0, true});
  Identify({"1972-04-09T06:10:00Z", 180.0, 200.0, true});
  Identify({"1972-03-25T04:00:00Z", 73.0, 115.0, false});
}

}  // namespace
}  // namespace platemeter
