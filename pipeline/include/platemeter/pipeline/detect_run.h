#pragma once
// Running the detectors (reseau, fiducials, stars and trails, passpoints) on a scan into a measurement file
// and a JSON summary: the detect step of the pipeline, run by `platemeter detect` and by RunMeasure
// (measure_run.h), hence `platemeter measure`, `validate` and `batch`.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/output_set.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"

namespace platemeter::pipeline {

// The duty-cycle program of a stellar plate (seed 001 Table 1; core/duty_cycle.h).
struct TrailRequest {
  std::string start_utc;                      // ISO 8601 UTC of the plate's first shutter opening (required)
  std::vector<int> leading_dashes{2, 3, 4, 5};  // leading dash count per trail, in exposure order
  double break_s = 480.0;                     // s; break between trails (7-10 min)
  bool require_joined = false;                // tag only trails joined to another trail of their star
                                              // (a lone trail's number is confirmed by nothing else)
  bool forced_dots = true;                    // a decoded trail's undetected dots measured at its track's
                                              // prediction (docs/trails.md)
};

// Marked passpoints (dots or rings) to measure.
struct PasspointRequest {
  std::string list_file;         // approximate positions (docs/passpoints.md); empty: find all, number them P1, P2, ...
  std::string shape = "dot";     // dot | ring
  double diameter_um = 0.0;      // um; outer diameter of the mark (required)
  double line_width_um = 0.0;    // um; ring line width (rings only)
  std::string polarity = "dark";  // dark | bright: the mark against its surroundings
};

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
  std::optional<TrailRequest> trails;   // link star images into duty-cycle trails (implies stars)
  std::optional<PasspointRequest> passpoints;  // measure passpoints
};

struct DetectRun {
  MeasurementFile file;     // every kind found, pixel columns filled
  nlohmann::json summary;   // as detect's <scan>.detect.json
  std::string grid_name;    // the grid searched ("" without a reseau)
  std::string messages;     // one line per detector, for the console
};

// Throws Error naming the option when a value is outside the range the job file accepts (docs/job.md) or
// names nothing (an orientation, a trail program): before any work.
void CheckDetectOptions(const DetectRequest& request);

// Throws Error naming the scan when nothing is found or the orientation is ambiguous.
DetectRun RunDetection(const DetectRequest& request, const DefinitionRegistry& registry);

// The files `platemeter detect` writes (docs/detect.md).
struct DetectFiles {
  std::string measurements_csv;  // <stem>.measurements.csv
  std::string summary_json;      // <stem>.detect.json
};

// The files of one detected scan (<stem>.measurements.csv, <stem>.detect.json): create their OutputSet
// before RunDetection, so that a folder that cannot take them fails the command before any work.
std::vector<std::string> DetectSetMembers(const std::string& scan);
// Writes run's measurement file and JSON summary into `outputs` and commits the set.
DetectFiles WriteDetectRun(const DetectRun& run, const std::string& scan, OutputSet* outputs);

}  // namespace platemeter::pipeline
