// The bundle's output files (bundle_report.h): residuals.csv, the calibrated
// camera definition, and all outputs written atomically into one folder.
#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "bundle_report_internal.h"
#include "output_files.h"
#include "platemeter/calib/bundle_report.h"
#include "platemeter/calib/camera_export.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/definition_io.h"

namespace platemeter {

bool BundleReportOptions::Check(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (balance_radius_mm && !(*balance_radius_mm > 0.0)) return fail("balance_radius_mm must be positive");
  for (double r : profile_radii_mm) {
    if (!(r >= 0.0) || !std::isfinite(r)) return fail("profile radii must be finite and >= 0");
  }
  if (worst_observations < 0) return fail("worst_observations must be >= 0");
  return true;
}

std::vector<int> AdjustedCameraParameters(const BundleCameraResult& camera, std::vector<std::string>* names) {
  std::vector<int> adjusted;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (!camera.sigmas[i]) continue;
    adjusted.push_back(camera.parameter_index[i]);
    names->push_back(kBundleCameraParamNames[i]);
  }
  return adjusted;
}

std::vector<const ObservationResidual*> WorstObservations(const BundleResult& result, int count) {
  std::vector<const ObservationResidual*> all;
  for (const ObservationResidual& r : result.adjustment.residuals) {
    if (r.normalized.size() == 2) all.push_back(&r);
  }
  // Rejected ones first, then by the length of the normalized residual.
  auto key = [](const ObservationResidual* r) {
    return std::make_pair(r->status == ObservationStatus::kRejected, std::hypot(r->normalized[0], r->normalized[1]));
  };
  const size_t n = std::min<size_t>(all.size(), std::max(0, count));
  std::partial_sort(all.begin(), all.begin() + n, all.end(), [&](auto* a, auto* b) { return key(a) > key(b); });
  all.resize(n);
  return all;
}

std::string FormatBundleResidualsCsv(const BundleResult& result) {
  std::string out = "frame,point_id,status,x_residual_um,y_residual_um,x_normalized,y_normalized,origin,reason\n";
  for (const ObservationResidual& r : result.adjustment.residuals) {
    if (r.residual.size() != 2) continue;  // distances: in calibration.json's summary only
    out += fmt::format("{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{},{}\n", r.group, r.item,
                       r.status == ObservationStatus::kUsed ? "used" : "rejected", 1e3 * r.residual[0],
                       1e3 * r.residual[1], r.normalized[0], r.normalized[1], r.origin, r.reason);
  }
  return out;
}

CameraDefinition CalibratedCameraDefinition(const BundleResult& result, int index, const std::string& source) {
  const BundleCameraResult& camera = result.cameras.at(index);
  // The definition it started from keeps its grid, fiducials and format; the lens is new.
  CameraDefinition definition = camera.definition.value_or(CameraDefinition{});
  definition.name = camera.name;
  definition.description = camera.definition ? "calibrated by platemeter's self-calibrating bundle adjustment from " +
                                                   camera.definition->name
                                             : "calibrated by platemeter's self-calibrating bundle adjustment (seed 000)";
  definition.source = source;
  if (!camera.definition) {
    definition.format_width_mm = camera.format_width_mm > 0 ? camera.format_width_mm : 1.0;
    definition.format_height_mm = camera.format_height_mm > 0 ? camera.format_height_mm : 1.0;
  }
  definition.nominal_principal_distance_mm = camera.values[0];
  LensCalibration lens;
  lens.model = "brown-affine";
  lens.source = fmt::format("{}; sigma0 {:.4f} with {:.0f} degrees of freedom", source, result.adjustment.sigma0,
                            result.adjustment.dof);
  lens.principal_distance_mm = camera.values[0];
  lens.principal_point_x_mm = camera.values[1];
  lens.principal_point_y_mm = camera.values[2];
  const char* struct_keys[3] = {"principal_distance_mm", "principal_point_x_mm", "principal_point_y_mm"};
  for (int i = 0; i < kBundleCameraParams; ++i) {
    const std::string key = i < 3 ? struct_keys[i] : kBundleCameraParamNames[i];
    if (i >= 3) lens.coefficients[key] = camera.values[i];
    if (camera.sigmas[i]) lens.sigmas[key] = *camera.sigmas[i];
  }
  definition.lens = lens;
  return definition;
}

namespace {

// The calibrated camera for other tools, one file per format.
void AppendExports(const CameraDefinition& camera, const BundleReportOptions& options,
                   std::vector<std::pair<std::string, std::string>>* files) {
  CameraExportOptions export_options;
  export_options.pixel_size_um = *options.export_pixel_size_um;
  export_options.image_width_px = (*options.export_image_size_px)[0];
  export_options.image_height_px = (*options.export_image_size_px)[1];
  const std::pair<CameraExportFormat, const char*> formats[] = {
      {CameraExportFormat::kOpenCv, "-opencv.yaml"}, {CameraExportFormat::kMicMac, "-micmac.xml"},
      {CameraExportFormat::kAspTsai, ".tsai"}};
  for (const auto& [format, suffix] : formats) {
    files->emplace_back("camera-" + camera.name + suffix, ExportCamera(camera, format, export_options));
  }
}

}  // namespace

std::vector<std::string> WriteBundleOutputs(const std::string& dir, const BundleResult& result,
                                            const BundleReportOptions& options,
                                            const std::vector<std::pair<std::string, std::string>>& extra_files) {
  std::string why;
  if (!options.Check(&why)) throw Error("bundle report options", why);
  // Every text is formatted before the first file is written: a failure leaves no partial set.
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back("calibration.json", FormatCalibrationJson(result, options));
  files.emplace_back("report.md", FormatBundleReportMarkdown(result, options));
  files.emplace_back("residuals.csv", FormatBundleResidualsCsv(result));
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    const CameraDefinition definition = CalibratedCameraDefinition(result, static_cast<int>(c), options.title);
    files.emplace_back("camera-" + result.cameras[c].name + ".toml",
                       "# " + options.title + "\n# Format: docs/definitions.md\n\n" + ToToml(definition));
  }
  if (options.export_pixel_size_um && options.export_image_size_px) {
    for (size_t c = 0; c < result.cameras.size(); ++c) {
      AppendExports(CalibratedCameraDefinition(result, static_cast<int>(c), options.title), options, &files);
    }
  }
  files.insert(files.end(), extra_files.begin(), extra_files.end());
  return WriteOutputFiles(dir, files);
}

}  // namespace platemeter
