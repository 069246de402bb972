// Detection and correction options for measure and validate (measure_prepare.h).
#include "measure_prepare.h"

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/core/scan_orientation.h"
#include "platemeter/measure/fiducial_orientation.h"

namespace platemeter::pipeline {

void CheckMeasureOptions(const MeasureRequest& request) {
  ReseauFitModel model;
  if (!ParseReseauFitModel(request.model, &model)) {
    throw Error("--model", "'" + request.model + "' is not one of similarity, affine, scales, projective");
  }
  if (!ParseReseauFitModel(request.fiducial_model, &model) ||
      (model != ReseauFitModel::kSimilarity && model != ReseauFitModel::kAffine)) {
    throw Error("--fiducial-model", "'" + request.fiducial_model + "' is not one of similarity, affine");
  }
  for (const std::string* orientation : {&request.detect.orientation, &request.second_orientation}) {
    ScanOrientation parsed;
    if (!orientation->empty() && !ParseScanOrientation(*orientation, &parsed)) {
      throw Error(orientation == &request.detect.orientation ? "--orientation" : "--second-orientation",
                  "'" + *orientation + "' is not one of " + kScanOrientationNames);
    }
  }
  if (!(request.min_cross_fraction >= 0.0 && request.min_cross_fraction <= 1.0)) {
    throw Error("--min-cross-fraction", std::to_string(request.min_cross_fraction) + " must lie in 0..1");
  }
  // A job's per-scan overrides can switch trails or passpoints on without their required value.
  const DetectRequest& d = request.detect;
  if (d.trails && d.trails->start_utc.empty()) throw Error("trails", "no start_utc (the plate's first shutter opening, UTC)");
  if (d.passpoints && d.passpoints->diameter_um <= 0.0) throw Error("passpoints", "no diameter_um (the mark's outer diameter)");
}

PreparedMeasurement PrepareMeasurement(const MeasureRequest& request, const DefinitionRegistry& registry, bool local,
                                       std::string* messages) {
  CheckMeasureOptions(request);
  PreparedMeasurement p;
  const CameraDefinition& camera = registry.Camera(request.detect.camera);
  if (camera.grid.empty() && (!local || (camera.fiducial_set.empty() && !camera.format_corners_as_fiducials))) {
    throw Error("camera '" + camera.name + "'", local ? "has neither a reseau grid nor fiducials to correct with"
                                                      : "has no reseau grid to validate");
  }
  if (!camera.grid.empty()) p.grid = &registry.Grid(camera.grid);
  const std::filesystem::path scan(request.detect.scan);
  if (scan.extension() == ".csv") {
    p.file = ReadMeasurementFile(request.detect.scan);
    if (!p.file.header.camera.empty() && p.file.header.camera != camera.name) {
      throw Error(request.detect.scan, "was detected with camera '" + p.file.header.camera + "', not '" + camera.name + "'");
    }
    p.stem = scan.stem().stem().string();
  } else {
    DetectRun run = RunDetection(request.detect, registry);
    *messages += run.messages;
    p.file = std::move(run.file);
    p.stem = scan.stem().string();
  }
  PlateCorrectionOptions& o = p.options;
  o.pixel_size_um = request.detect.pixel_size_um;
  if (!request.detect.orientation.empty()) o.orientation = request.detect.orientation;
  o.temperature_degC = request.temperature_degC;
  o.calibration_temperature_degC = camera.calibration_temperature_degC.value_or(
      p.grid ? p.grid->calibration_temperature_degC.value_or(20.0) : 20.0);
  o.expansion_per_degC = camera.glass_expansion_per_degC;
  o.emulsion.depth_um = request.emulsion_depth_um.value_or(0.0);
  o.emulsion.refractive_index = request.refractive_index;
  o.emulsion.principal_distance_mm = camera.lens && camera.lens->principal_distance_mm > 0
                                         ? camera.lens->principal_distance_mm
                                         : camera.nominal_principal_distance_mm;
  ParseReseauFitModel(request.model, &o.fit.model);
  o.fit.rejection_threshold = request.rejection_threshold;
  o.local_reseau = local && !request.no_local;
  o.fiducial_orientation = request.fiducial_orientation;
  o.fiducials = CalibratedFiducials(camera, camera.fiducial_set.empty() ? nullptr : &registry.Fiducials(camera.fiducial_set));
  o.fiducial_source = camera.fiducial_set;
  if (camera.format_corners_as_fiducials) o.fiducial_source += (o.fiducial_source.empty() ? "" : "+") + std::string("format_corners");
  ParseReseauFitModel(request.fiducial_model, &o.fiducial.model);
  return p;
}

PlateCorrectionReport CorrectPrepared(PreparedMeasurement* p) {
  return p->grid ? CorrectPlate(&p->file, *p->grid, p->options) : CorrectFiducialPlate(&p->file, p->options);
}

}  // namespace platemeter::pipeline
