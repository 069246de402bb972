#pragma once
// The measure step of the pipeline (detect, corrections, outputs): RunMeasure for
// `platemeter measure` and every scan of `platemeter batch` (batch/measure_batch.h),
// RunValidate for `platemeter validate`.
#include <map>
#include <ostream>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/pipeline/detect_run.h"
#include "platemeter/grids/registry.h"

namespace platemeter::pipeline {

// Every option of `platemeter measure` (docs/measure.md).
struct MeasureRequest {
  DetectRequest detect;                    // detect.scan = the scan (or detect's <scan>.measurements.csv)
  std::optional<double> temperature_degC;  // degC; measuring temperature (thermal scaling), none: no thermal step
  std::optional<double> emulsion_depth_um;  // um; depth of the image centroid in the emulsion, none: no correction
  double refractive_index = 1.65;          // emulsion refractive index
  std::string model = "scales";            // reseau fit model: similarity, affine, scales, projective
  double rejection_threshold = 4.0;        // normalized residual above which a cross is rejected
  double tolerance_um = 5.0;               // um; residual tolerance for the out-of-tolerance flags
  bool no_local = false;                   // skip the bilinear local reseau correction
  bool fiducial_orientation = false;       // reseau cameras: also fit the fiducials and map into their frame
  double min_cross_fraction = 0.5;         // share of the grid's crosses the reseau fit must use, else the scan fails
                                           // (wrong camera or pixel size, most crosses hidden); added to the lead's interface
  std::string fiducial_model = "affine";   // fiducial interior orientation model: similarity, affine
  std::string second_scan, second_orientation;  // the plate scanned again (rotated 180 deg) and its orientation
  std::string out_dir;                     // where the outputs go (created)
};

// The numbers a batch summary row needs.
struct MeasureSummary {
  std::string plate_id;                           // the scan's stem
  std::map<std::string, int> counts_by_status;    // "measured", "rejected", "missing" -> number of points (all kinds)
  std::map<std::string, int> counts_by_kind;      // "reseau", "fiducial", "star", "trail_dot", "passpoint", ...
  std::optional<double> reseau_rms_um;            // um; reseau fit RMS
  std::optional<double> scale_x, scale_y;         // fitted reseau scales (1 = nominal), when the model has them
  std::vector<std::string> written_files;         // absolute paths of every file written
  std::string report_json;                        // path of <stem>.measure.json
  std::string plot_png;                           // path of <stem>.residuals.png ("" when none)
  std::string message;                            // the console lines `measure` prints
};

// Runs detect + corrections and writes the outputs atomically into request.out_dir (creating it).
// Throws platemeter::Error with a one-line reason naming the scan on any failure (unreadable, wrong camera,
// too few crosses...). Prints nothing: the console text is in the summary's message.
MeasureSummary RunMeasure(const MeasureRequest& request, const DefinitionRegistry& registry);

// `platemeter validate`: the reseau check alone (no local step; reseau cameras only). Detects (or reads
// detect's measurement file), fits the grid and writes <stem>.validate.json and <stem>.residuals.png
// atomically into request.out_dir (creating it). Writes its console lines to `console` as it goes: the
// detectors' lines before the fit, so that a scan whose fit fails still shows what was found. Throws Error.
void RunValidate(const MeasureRequest& request, const DefinitionRegistry& registry, std::ostream& console);

// A canonical text of every option that changes the outputs (not scan, not out_dir), with the software
// version: for the batch's resume fingerprint. Deterministic: one "key = value" line per option, fixed order.
std::string CanonicalOptionsText(const MeasureRequest& request);

}  // namespace platemeter::pipeline
