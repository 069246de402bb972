#pragma once
// Simulated stellar-calibration plates (seed 001) as the stellar calibration
// takes them (calib/stellar_plate.h), without rendering: the star field's true
// trail-dot positions at mid-exposure (star_field.h), a seed-001 selection of
// images, Gaussian measuring noise, and a catalog whose positions are off the
// truth by the stated catalog sigma. docs/stellar-simulator.md.
//
// Truth. The stars' TRUE directions are the kstars catalog places; the
// catalog handed to the calibration is that catalog moved by a random
// N(0, catalog_sigma) arc east and north per star (equivalently: the true sky
// is off the catalog by its stated error). The true camera is the camera
// definition's lens (for the Orbigon: seed 001 Table 3's combined solution; for
// sn004-terrain seed 004's smac-radial-decentering lens; any lens model of
// stellar_lens.h, projected through CameraModel in its own direction) in the
// plate frame (StellarCameraFromModel), Cx = Cy = C, epsilon = 0.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "platemeter/calib/stellar_plate.h"
#include "platemeter/samples/star_field.h"

namespace platemeter::sim {

struct StellarPlateSimulation {
  std::string plate_id = "plate";
  std::string group;                 // e.g. "f/4"
  StarFieldOptions field;            // site, start, pointing, roll, duty cycle
  std::string catalog_path;          // empty: calib::DefaultStarCatalogPath()
  double magnitude_limit = 6.0;      // V; stars to this magnitude
  // Seed 001's selection: in each cell_mm x cell_mm square of the format at
  // most images_per_cell_per_trail trail dots of each trail (5 per cm^2 per trail).
  double cell_mm = 10.0;
  int images_per_cell_per_trail = 5;
  double format_margin_mm = 2.0;     // images closer than this to the format edge are not measured
  bool Check(std::string* why) const;
};

// The noise-free plate: true image positions of the selected trail dots.
struct StellarTruthPlate {
  StellarPlate plate;                // images at their true positions, sigma 0 (see Noisy)
  StellarCatalog catalog;            // the true places (kstars), keyed by the images' star ids
  StellarCamera camera;              // true camera, plate frame, the definition's lens model
  Eigen::Matrix3d camera_from_enu = Eigen::Matrix3d::Identity();
  double duration_s = 0.0;
};

// Throws platemeter::Error for bad options or an unreadable catalog.
StellarTruthPlate SimulateStellarTruth(const StellarPlateSimulation& options, const CameraDefinition& camera);

struct StellarNoise {
  uint64_t seed = 1;
  double image_sigma_um = 2.5;       // per coordinate, the measured images
  double catalog_sigma_arcsec = 0.4; // per coordinate, the catalog places handed to the calibration
};

// One measured realisation: images with Gaussian noise and their sigma, and a
// catalog off the truth by catalog_sigma (with that sigma stated).
struct NoisyStellarPlate {
  StellarPlate plate;
  StellarCatalog catalog;
};
NoisyStellarPlate Noisy(const StellarTruthPlate& truth, const StellarNoise& noise);

// The plate as a measurement file of trail dots (docs/measurement-file.md),
// as `calibrate stellar` reads it. With `anonymous` each star's images carry a
// detector-like key ("S1", "S2", ... in order of first appearance) instead of
// the catalog key, so that the calibration must identify them. Returns
// key -> catalog key.
std::map<std::string, std::string> WriteStellarMeasurementFile(const StellarPlate& plate, const std::string& path,
                                                               bool anonymous);

}  // namespace platemeter::sim
