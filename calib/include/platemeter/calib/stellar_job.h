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
#include "platemeter/calib/stellar_interlock.h"
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
  int camera = 0;                     // index in StellarJob::cameras
  std::string exposure;               // plates of several cameras with one exposure id are interlocked
};

struct StellarJob {
  std::string path;                   // the job file (messages)
  std::string title;
  // The cameras: [0] the job's `camera`, then those the plates name. Each
  // starts from its lens if that is of options.lens_model, else from its
  // nominal principal distance with no distortion.
  std::vector<CameraDefinition> cameras;
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
  // Per camera: per group with 2+ plates, then "all plates" if 2+ plates
  // (named "all plates of NAME" when the job has several cameras).
  std::vector<StellarCombination> combinations;
  std::vector<int> combination_camera;              // camera index of each combination
  std::vector<StellarCamera> initial;               // per camera, plate frame
  std::vector<bool> printed_left_handed;            // per camera: its definition's lens is in seed 001's frame
  // The cameras' joint adjustment (stellar_interlock.h) over the exposures
  // that show camera 0 and another camera, when there are such.
  std::optional<StellarInterlockResult> interlock;
};

// Runs the job; `progress` sees "identification", "plate <id>", "combination <name>", "interlock".
StellarJobResult RunStellarJob(const StellarJob& job, const AdjustmentProgress& progress = {});

}  // namespace platemeter
