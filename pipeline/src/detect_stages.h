#pragma once
// The optional stages of RunDetection (detect_run.cpp) after the reseau and the
// fiducials: each reads the scan with what the earlier stages found and returns
// its measurement-file rows, its part of <scan>.detect.json and a console line.
// One file per stage: detect_stage_stars.cpp (stars and duty-cycle trails),
// detect_stage_passpoints.cpp.
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "platemeter/pipeline/detect_run.h"
#include "platemeter/core/image.h"
#include "platemeter/detect/fiducial_detector.h"
#include "platemeter/detect/grid_assignment.h"
#include "platemeter/detect/reseau_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"

namespace platemeter::pipeline {

// What the earlier stages know; pointers are null when that stage did not run.
struct DetectContext {
  const DetectRequest& request;
  const DefinitionRegistry& registry;
  const Image& image;
  double pixel_size_um = 0.0;
  const CameraDefinition* camera = nullptr;   // null with --grid
  const MasterGrid* grid = nullptr;           // null without a reseau
  const ReseauDetection* reseau = nullptr;
  const FiducialDetection* fiducials = nullptr;
  ScanOrientation orientation;                // decided (or given) orientation
};

struct StageOutput {
  nlohmann::json summary;           // stored under the stage's key in <scan>.detect.json
  std::string message;              // one console line, without the newline
};

// Stars (kind star) and, with request.trails, the duty-cycle trails (kinds trail_dot, trail_dash).
// Each stage appends its rows (pixel columns filled) to the file's `rows`: a plate's hundreds of thousands
// of rows are never held twice.
StageOutput RunStarStage(const DetectContext& context, std::vector<MeasuredPoint>* rows);
// Passpoints (kind passpoint) as request.passpoints defines them.
StageOutput RunPasspointStage(const DetectContext& context, std::vector<MeasuredPoint>* rows);

}  // namespace platemeter::pipeline
