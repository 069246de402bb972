#pragma once
// Identification of the stars of a plate (seed 001: "the star-image
// measurements were ... catalog identified") from an approximate pointing and
// an unknown roll. docs/star-identification.md.
//
// 1. Reference epoch: the time around which most detected stars have an image
//    (within `window_s`); each star's image nearest it is its pattern image.
// 2. Triangles: each star with pairs of its nearest neighbours, on the plate
//    (through the nominal camera) and in the catalog (apparent places at the
//    reference epoch); triangles whose three sides agree within the tolerance
//    give a rotation hypothesis (three pairs, least squares).
// 3. Verification: every detected star's image is carried to the reference
//    epoch through the hypothesis (the sky turns about the pole) and matched to
//    its nearest catalog star; the count of matches is compared with what
//    chance gives (Poisson, Bonferroni over the hypotheses tried). The first
//    hypothesis with a false-alarm probability below `false_alarm` and the
//    pointing within `pointing_tolerance_deg` wins.
// 4. Refinement and assignment: the rotation is refitted to the matches, and
//    each detected star gets the catalog star that all its images (each at its
//    own time) agree on within `match_tolerance_arcsec`, unless another
//    catalog star is within 2 x that tolerance (ambiguous: left unknown, never
//    guessed).
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/stellar_plate.h"

namespace platemeter {

struct DetectedStarImage {
  std::string star_key;        // the detector's star ("S12"): images of one star share it
  calib::UtcInstant mid_time;
  double x_mm = 0.0, y_mm = 0.0;  // plate frame
};

struct IdentificationOptions {
  double pointing_tolerance_deg = 6.0;  // the optical axis lies within this of the approximate pointing
  double window_s = 20.0;               // s; pattern images within this of the reference epoch
  double side_tolerance_deg = 0.12;     // triangle sides: the images' time spread (20 s: 5') and the nominal camera
  double verify_tolerance_deg = 0.15;   // a detected star and a catalog star match within this (hypotheses)
  double match_tolerance_arcsec = 120.0;  // final assignment, after refitting the rotation
  double false_alarm = 1e-9;            // accepted hypothesis: chance of as many matches, all hypotheses counted
  int neighbours = 4;                   // triangles of each star with pairs of its nearest neighbours
  int max_hypotheses = 5000;            // give up after verifying this many
  // The camera's lens model (stellar_lens.h): how its distortion is undone.
  DistortionModelId lens_model = DistortionModelId::kSlama;
  bool Check(std::string* why) const;
};

struct IdentificationResult {
  std::map<std::string, std::string> catalog_id;  // detected star key -> catalog key (identified ones)
  std::vector<std::string> unknown;               // detected stars not identified (no or ambiguous match)
  std::vector<std::string> ambiguous;             // of those: two catalog stars within reach
  Eigen::Matrix3d camera_from_enu = Eigen::Matrix3d::Identity();
  calib::UtcInstant reference_epoch;
  int hypotheses_tried = 0;
  int pattern_matches = 0;          // matches of the accepted hypothesis
  double false_alarm_probability = 1.0;
  double rms_arcsec = 0.0;          // of the identified images after the refit
};

// `catalog`: the stars to identify against (keys as the calibration will use
// them); `axis_enu`: the approximate optical axis in the site's local frame;
// `camera`: the nominal camera (options.lens_model; its distortion undone). Throws platemeter::Error
// when no hypothesis passes verification ("no identification: ...").
IdentificationResult IdentifyStars(const std::vector<DetectedStarImage>& images, const StellarCatalog& catalog,
                                   const calib::ApparentPlaceOptions& place, const Eigen::Vector3d& axis_enu,
                                   const StellarCamera& camera, const IdentificationOptions& options = {});

}  // namespace platemeter
