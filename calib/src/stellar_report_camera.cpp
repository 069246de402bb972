// A calibrated stellar camera as the reports print it and as a camera
// definition (stellar_report.h), for each lens model.
#include <cmath>

#include "platemeter/calib/stellar_report.h"
#include "platemeter/core/error.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {


// Seed 001's printed (left-handed) frame and units: an orbigon-11 lens in the
// form of the builtin orbigon definition.
LensCalibration PrintedOrbigonLens(const StellarCamera& values, const StellarCamera& sigmas) {
  const PrintedCamera p = ToPrinted(values, sigmas);
  LensCalibration lens;
  lens.model = "orbigon-11";
  lens.principal_distance_mm = p.value[0] * 1e-3;
  lens.principal_point_x_mm = p.value[1] * 1e-3;
  lens.principal_point_y_mm = p.value[2] * 1e-3;
  const char* keys[] = {"xs_um", "ys_um", "K1_per_m2", "K2_per_m4", "K3_per_m6", "K4_per_m", "K5_per_m3", "Phi_T_deg"};
  for (int i = 3; i < kStellarCameraParams; ++i) {
    lens.coefficients[keys[i - 3]] = p.value[i];
    if (sigmas[i] > 0) lens.sigmas[keys[i - 3]] = p.sigma[i];
  }
  return lens;
}

// A correction lens (smac-radial-decentering, brown-conrady) in the plate
// frame: the definition keys are the model's parameter names (docs/definitions.md).
LensCalibration PlateFrameLens(DistortionModelId model, const StellarCamera& values, const StellarCamera& sigmas) {
  LensCalibration lens;
  lens.model = DistortionModelName(model);
  lens.principal_distance_mm = values[0];
  lens.principal_point_x_mm = values[1];
  lens.principal_point_y_mm = values[2];
  const std::vector<std::string> names = StellarCameraParamNames(model);
  for (size_t i = 3; i < names.size(); ++i) {
    lens.coefficients[names[i]] = values[i];
    if (sigmas[i] > 0) lens.sigmas[names[i]] = sigmas[i];
  }
  return lens;
}

}  // namespace

PrintedCamera ToPrinted(const StellarCamera& values, const StellarCamera& sigmas) {
  const StellarCamera p = StellarCameraToPrinted(values);
  PrintedCamera out;
  for (int i = 0; i < kStellarCameraParams; ++i) out.value[i] = p[i], out.sigma[i] = sigmas[i];
  for (int i = 0; i < 3; ++i) out.value[i] *= 1e3, out.sigma[i] *= 1e3;
  out.value[3] = 1e3 * (p[3] + p[1]);  // from the reseau centre (xp's sigma is ~1e-3 of xs')
  out.value[4] = 1e3 * (p[4] + p[2]);
  out.sigma[3] *= 1e3;
  out.sigma[4] *= 1e3;
  out.value[10] *= kDegPerRad;
  out.sigma[10] *= kDegPerRad;
  return out;
}

ReportedCamera ReportCamera(DistortionModelId lens, const StellarCamera& values, const StellarCamera& sigmas) {
  ReportedCamera out;
  if (lens == DistortionModelId::kSlama) {
    const PrintedCamera p = ToPrinted(values, sigmas);
    out.frame = "seed 001's printed frame";
    out.names.assign(kPrintedCameraNames.begin(), kPrintedCameraNames.end());
    out.value.assign(p.value.begin(), p.value.end());
    out.sigma.assign(p.sigma.begin(), p.sigma.end());
    for (int i = 0; i < kStellarCameraParams; ++i) out.exponent.push_back(i >= 5 && i <= 9);  // K1..K5
    out.decimals = 2;  // um and degrees
    return out;
  }
  out.frame = "plate frame";
  out.names = StellarCameraParamNames(lens);
  out.value = values;
  out.sigma = sigmas;
  const int angle = StellarDecenteringSignOf(lens).angle;
  for (int i = 0; i < static_cast<int>(values.size()); ++i) out.exponent.push_back(i >= 3 && i != angle);
  out.decimals = 5;  // mm (0.01 um) and radians
  return out;
}

CameraDefinition StellarCameraDefinition(const StellarJob& job, const StellarJobResult& result, int camera) {
  int combination = -1, single = -1;
  for (size_t k = 0; k < result.combinations.size(); ++k) {
    if (result.combination_camera[k] == camera) combination = static_cast<int>(k);
  }
  for (size_t i = 0; i < result.singles.size() && single < 0; ++i) {
    if (job.plates[i].camera == camera) single = static_cast<int>(i);
  }
  if (combination < 0 && single < 0) throw Error("stellar calibration", "internal: a camera without plates");
  const bool combined = combination >= 0;
  const StellarCamera& values = combined ? result.combinations[combination].camera : result.singles[single].camera;
  const StellarCamera& sigmas =
      combined ? result.combinations[combination].camera_sigma : result.singles[single].camera_sigma;
  const CameraDefinition& source = job.cameras[camera];
  const DistortionModelId model = job.options.lens_model;
  CameraDefinition d = source;
  d.description = std::string("calibrated by platemeter's stellar calibration (seed 001, ") +
                  DistortionModelName(model) + " lens) from " + source.name;
  d.source = job.title + (combined ? "; " + result.combinations[combination].name : "; plate " + result.singles[single].plate_id);
  d.nominal_principal_distance_mm = values[0];
  LensCalibration lens = model == DistortionModelId::kSlama ? PrintedOrbigonLens(values, sigmas)
                                                            : PlateFrameLens(model, values, sigmas);
  lens.source = d.source + (model == DistortionModelId::kSlama
                                ? " (seed 001's printed, left-handed frame, as the builtin orbigon)"
                                : " (plate frame: x right, y up)");
  const char* struct_keys[] = {"principal_distance_mm", "principal_point_x_mm", "principal_point_y_mm"};
  for (int i = 0; i < 3; ++i) {
    if (sigmas[i] > 0) lens.sigmas[struct_keys[i]] = sigmas[i];
  }
  d.lens = lens;
  return d;
}

}  // namespace platemeter
