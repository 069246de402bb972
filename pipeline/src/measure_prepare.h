#pragma once
// The first half of measure and validate: the scan detected (or detect's measurement
// file read) and the correction options resolved from the request and the camera.
#include <string>

#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/plate_corrections.h"
#include "platemeter/pipeline/measure_run.h"

namespace platemeter::pipeline {

struct PreparedMeasurement {
  MeasurementFile file;               // pixel columns filled
  PlateCorrectionOptions options;     // the corrections to apply
  const MasterGrid* grid = nullptr;   // the camera's reseau, null for fiducial-only cameras
  std::string stem;                   // the plate id: the scan's stem
};

// Throws Error for option values that name nothing (model, fiducial model, orientation), before any work.
void CheckMeasureOptions(const MeasureRequest& request);

// The plate id and stem of the output files: the scan's stem (detect's <stem>.measurements.csv: <stem>).
std::string PlateStem(const std::string& scan_or_measurements);

// Detects request.detect.scan (or reads it when it is a .csv measurement file) and resolves the correction
// options. `local`: measure (reseau or fiducials, local step) rather than validate (reseau only).
// The detectors' console lines are appended to *messages.
PreparedMeasurement PrepareMeasurement(const MeasureRequest& request, const DefinitionRegistry& registry, bool local,
                                       std::string* messages);

// The corrections: the reseau chain for reseau cameras, else the fiducial one.
PlateCorrectionReport CorrectPrepared(PreparedMeasurement* prepared);

}  // namespace platemeter::pipeline
