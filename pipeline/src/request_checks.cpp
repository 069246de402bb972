// The checks of detect's and measure's options before any work (CheckDetectOptions in detect_run.h,
// CheckMeasureOptions in measure_prepare.h): numbers against the ranges the job file accepts
// (docs/job.md), names against what they may name, so that a bad value cannot fail a run half way
// through its outputs.
#include <filesystem>
#include <sstream>

#include "measure_prepare.h"
#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/error.h"
#include "platemeter/core/scan_orientation.h"
#include "platemeter/pipeline/detect_run.h"

namespace platemeter::pipeline {
namespace {

std::string Text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// `value` within [min, max] (or (min, max] when the minimum is excluded), else an Error naming the option.
void CheckRange(const char* option, double value, double min, double max, bool min_excluded = false) {
  const bool above_min = min_excluded ? value > min : value >= min;
  if (above_min && value <= max) return;
  throw Error(option, Text(value) + " is outside the accepted range " + (min_excluded ? "(" : "[") + Text(min) + ", " +
                          Text(max) + "]");
}

void CheckOrientation(const char* option, const std::string& orientation) {
  ScanOrientation parsed;
  if (!orientation.empty() && !ParseScanOrientation(orientation, &parsed)) {
    throw Error(option, "'" + orientation + "' is not one of " + kScanOrientationNames);
  }
}

// A job's per-scan overrides can switch trails or passpoints on without their required value.
void CheckTrailsAndPasspoints(const DetectRequest& d) {
  if (d.trails) {
    if (d.trails->start_utc.empty()) throw Error("trails", "no start_utc (the plate's first shutter opening, UTC)");
    CheckRange("--trail-break-s", d.trails->break_s, 0.0, 86400.0);
    DutyCycleScheduleOptions schedule;  // the program must be one seed 001's Table 1 allows
    schedule.leading_dashes = d.trails->leading_dashes;
    schedule.break_s = d.trails->break_s;
    std::string why;
    if (!schedule.Check(&why)) throw Error("--trail-dashes", "an invalid trail program: " + why);
  }
  if (d.passpoints) {
    if (d.passpoints->diameter_um <= 0.0) throw Error("passpoints", "no diameter_um (the mark's outer diameter)");
    CheckRange("--passpoint-diameter-um", d.passpoints->diameter_um, 0.1, 1e5);
    CheckRange("--passpoint-line-width-um", d.passpoints->line_width_um, 0.0, 1e5);
  }
}

// The same plate scanned twice means two independent measurements; the scan itself given again would
// halve the variances of one measurement.
void CheckSecondScan(const MeasureRequest& request) {
  if (request.second_scan.empty()) return;
  std::error_code ec;
  if (request.second_scan == request.detect.scan ||
      std::filesystem::equivalent(request.second_scan, request.detect.scan, ec)) {
    throw Error("--second-scan", request.second_scan + " is the scan itself; give the plate's second scan (turned 180 deg)");
  }
}

}  // namespace

void CheckDetectOptions(const DetectRequest& request) {
  if (request.pixel_size_um) CheckRange("--pixel-size-um", *request.pixel_size_um, 0.01, 10000.0);
  CheckRange("--star-fwhm-px", request.star_fwhm_px, 0.5, 100.0);
  CheckOrientation("--orientation", request.orientation);
  CheckTrailsAndPasspoints(request);
}

void CheckMeasureOptions(const MeasureRequest& request) {
  CheckDetectOptions(request.detect);
  if (request.temperature_degC) CheckRange("--temperature-degC", *request.temperature_degC, -100.0, 100.0);
  if (request.emulsion_depth_um) CheckRange("--emulsion-depth-um", *request.emulsion_depth_um, 0.0, 1000.0);
  CheckRange("--refractive-index", request.refractive_index, 1.0, 3.0);
  CheckRange("--rejection-threshold", request.rejection_threshold, 1.0, 1e6, true);
  CheckRange("--tolerance-um", request.tolerance_um, 0.0, 1e6, true);
  CheckRange("--min-cross-fraction", request.min_cross_fraction, 0.0, 1.0);
  CheckOrientation("--second-orientation", request.second_orientation);
  CheckSecondScan(request);
  ReseauFitModel model;
  if (!ParseReseauFitModel(request.model, &model)) {
    throw Error("--model", "'" + request.model + "' is not one of similarity, affine, scales, projective");
  }
  if (!ParseReseauFitModel(request.fiducial_model, &model) ||
      (model != ReseauFitModel::kSimilarity && model != ReseauFitModel::kAffine)) {
    throw Error("--fiducial-model", "'" + request.fiducial_model + "' is not one of similarity, affine");
  }
}

}  // namespace platemeter::pipeline
