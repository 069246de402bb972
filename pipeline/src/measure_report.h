#pragma once
// The JSON pieces of <scan>.measure.json and <scan>.validate.json (docs/measure.md):
// the reseau validation, the fiducial interior orientation, the double measurement.
#include <nlohmann/json.hpp>

#include <string>

#include "platemeter/measure/double_measurement.h"
#include "platemeter/measure/fiducial_orientation.h"
#include "platemeter/measure/plate_corrections.h"

namespace platemeter::pipeline {

inline constexpr double kRadToArcsec = 206264.80624709636;

// The reseau validation: per-cross residuals, RMS, the decomposed linear part with sigmas, the scale
// discrepancy and its reading as an emulsion depth, out-of-tolerance flags (tolerance in um).
nlohmann::json ValidationJson(const PlateCorrectionReport& report, double tolerance_um);

// The fiducial interior orientation: fit, per-fiducial residuals and leave-one-out discrepancies.
nlohmann::json FiducialJson(const FiducialOrientation& orientation);

// The double measurement: the second scan's fits, pairing counts and per-point discrepancies.
nlohmann::json DoubleMeasurementJson(const std::string& second_scan, const PlateCorrectionReport& second,
                                     bool with_reseau, const DoubleMeasurementReport& report, double tolerance_um);

}  // namespace platemeter::pipeline
