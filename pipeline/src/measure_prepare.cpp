// Detection and correction options for measure and validate (measure_prepare.h); the options are
// checked in request_checks.cpp.
#include "measure_prepare.h"

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/measure/fiducial_orientation.h"

namespace platemeter::pipeline {

std::string PlateStem(const std::string& scan_or_measurements) {
  const std::filesystem::path path(scan_or_measurements);
  return path.extension() == ".csv" ? path.stem().stem().string() : path.stem().string();
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
  } else {
    DetectRun run = RunDetection(request.detect, registry);
    *messages += run.messages;
    p.file = std::move(run.file);
  }
  p.stem = PlateStem(request.detect.scan);
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
