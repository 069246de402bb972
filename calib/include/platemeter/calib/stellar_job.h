#pragma once
// The stellar calibration job (docs/stellar-job.md): plates as measurement
// files of star images and time-tagged trail dots, the site and atmosphere,
// an approximate pointing per plate, the catalog; identification, one
// adjustment per plate, and the weighted mean per group and over all plates.
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/star_identification.h"
#include "platemeter/calib/stellar_combination.h"
#include "platemeter/calib/stellar_plate.h"
#include "platemeter/grids/definitions.h"
#include "platemeter/grids/registry.h"

namespace platemeter {

struct StellarJobPlate {
  StellarPlate plate;                 // images keyed by the measurement file's star_id
  std::string source;                 // the measurement file
  // Approximate pointing: the optical axis by azimuth/altitude (deg), or by
  // right ascension/declination (deg, ICRS); zenith if neither is given.
  double axis_azimuth_deg = 0.0, axis_altitude_deg = 90.0;
  std::optional<std::pair<double, double>> axis_ra_dec_deg;
};

struct StellarJob {
  std::string path;                   // the job file (messages)
  std::string title;
  CameraDefinition camera;            // starting lens (orbigon-11) or nominal principal distance
  std::string catalog_path;           // kstars stars.dat (default) or a KStars binary file
  double magnitude_limit = 6.5;       // catalog stars to this V
  double catalog_sigma_arcsec = 0.4;  // seed 001: 0.3" FK4, 0.4" others
  bool identify = true;               // false: the files' star_id are catalog keys already
  std::vector<StellarJobPlate> plates;
  StellarOptions options;
  IdentificationOptions identification;
};

// Reads and checks the job; the measurement files are read too. Throws
// platemeter::Error naming the file and line.
StellarJob ReadStellarJob(const std::string& path, const DefinitionRegistry& registry);

struct StellarJobResult {
  StellarCatalog catalog;
  std::vector<StellarPlate> plates;                 // as adjusted: catalog keys or "<plate>:<key>" for unknown stars
  std::vector<std::optional<IdentificationResult>> identification;  // per plate, when identified here
  std::vector<StellarPlateResult> singles;
  std::vector<StellarCombination> combinations;     // per group with 2+ plates, then "all plates" if 2+ plates
  StellarCamera initial{};                          // plate frame
  bool printed_left_handed = false;                 // the camera definition's lens is in seed 001's frame
};

// Runs the job; `progress` sees "identification", "plate <id>", "combination <name>".
StellarJobResult RunStellarJob(const StellarJob& job, const AdjustmentProgress& progress = {});

}  // namespace platemeter
