#pragma once
// Running the reseau and fiducial detectors on a scan into a measurement file
// and a JSON summary: shared by `platemeter detect` and `platemeter measure`.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>

#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"

namespace platemeter::cli {

struct DetectRequest {
  std::string scan;
  std::string camera;                   // camera definition (grid and fiducials), or
  std::string grid;                     // a master grid alone
  std::optional<double> pixel_size_um;  // um; default the TIFF resolution tags
  std::string orientation;              // known orientation ("0", "90m", ...), empty: detect it
  bool allow_ambiguous = false;         // accept an undecided orientation
  bool stars = false;                   // also detect star images (kind star)
  bool stars_bright = false;            // stars brighter than the background (a positive); default dark (a negative)
  double star_fwhm_px = 2.5;            // px; expected FWHM of a star image
};

struct DetectRun {
  MeasurementFile file;     // kinds reseau/fiducial, pixel columns filled
  nlohmann::json summary;   // as detect's <scan>.detect.json
  std::string grid_name;    // the grid searched ("" without a reseau)
  std::string messages;     // one line per detector, for the console
};

// Throws Error naming the scan when nothing is found or the orientation is ambiguous.
DetectRun RunDetection(const DetectRequest& request, const DefinitionRegistry& registry);

}  // namespace platemeter::cli
