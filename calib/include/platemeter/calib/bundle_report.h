#pragma once
// The bundle adjustment's outputs (docs/calibration-output.md):
//   calibration.json   every parameter by its model name with value and sigma,
//                      sigma0 with its degrees of freedom, the chi-square test,
//                      the inner cone's correlation matrix, the rank report,
//                      per-frame and per-point residual RMS, the worst
//                      observations, the warnings of the checks;
//   report.md          seed 000 Tables 1-4 in form: the calibration constants
//                      with their sigmas, the balanced radial and decentering
//                      profiles with propagated sigmas, then the adjustment's
//                      statistics, correlations, tests and rank report;
//   residuals.csv      one row per observation;
//   camera-NAME.toml   the calibrated camera as a definition (lens model
//                      brown-affine, sigmas) that --definitions loads;
//   camera-NAME-opencv.yaml, -micmac.xml, .tsai: the exports, where a pixel
//                      grid is given (fitted where the models differ, the
//                      fit's residual in the file and in calibration.json).
// report.html and plots/ are formatted by the report library (a higher layer:
// report/bundle_html_report.h) and handed to WriteBundleOutputs as extra files.
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/calib/distortion_profile.h"
#include "platemeter/core/text_document.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

struct BundleReportOptions {
  std::string title = "Self-calibrating bundle adjustment";
  // mm; the radial profile is balanced to zero at this radius (seed 000 Tables
  // 2, 4, 7 use 30 mm); none: equal positive and negative lobes over the format.
  std::optional<double> balance_radius_mm;
  std::vector<double> profile_radii_mm;  // mm; empty: 0 to the format's corner in 10 steps
  int worst_observations = 20;           // listed in the JSON and the report
  std::vector<BundleWarning> warnings;   // what the checks left out
  std::string software = "platemeter";
  // With both: every camera also exported for OpenCV, MicMac and ASP
  // (camera_export.h) for scans of this pixel size and image size.
  std::optional<double> export_pixel_size_um;              // um
  std::optional<std::array<int, 2>> export_image_size_px;  // px; width, height
  bool Check(std::string* why) const;
};

// The calibrated camera of result.cameras[index] as a camera definition.
CameraDefinition CalibratedCameraDefinition(const BundleResult& result, int index, const std::string& source);

// The report's content (report.md; report.html renders the same document).
TextDocument BundleReportDocument(const BundleResult& result, const BundleReportOptions& options);

// The camera's adjusted parameters (those with a sigma): their indices in
// result.adjustment.parameters, and their names in `names` (the inner cone's
// correlation matrix is over these).
std::vector<int> AdjustedCameraParameters(const BundleCameraResult& camera, std::vector<std::string>* names);

// The distortion profile of result.cameras[camera_index] balanced as the report
// balances it (options.balance_radius_mm, else equal lobe areas over the
// format's half diagonal) at `radii_mm` (empty: the report's table radii).
// Throws Error("distortion profile", why) where none can be computed.
DistortionProfile BundleDistortionProfile(const BundleResult& result, int camera_index,
                                          const BundleReportOptions& options, std::vector<double> radii_mm = {});
// "balanced to zero at r = 30 mm" or "balanced to equal ... lobe areas over 0..38.9 mm".
std::string BundleBalanceWords(const BundleResult& result, int camera_index, const BundleReportOptions& options);

std::string FormatCalibrationJson(const BundleResult& result, const BundleReportOptions& options);
std::string FormatBundleReportMarkdown(const BundleResult& result, const BundleReportOptions& options);
// frame,point_id,status,x_residual_um,y_residual_um,x_normalized,y_normalized,origin,reason
std::string FormatBundleResidualsCsv(const BundleResult& result);

// Writes every output into `dir` (created if needed), each file atomically;
// returns the paths written. `extra_files` (name relative to `dir`, e.g.
// "plots/network-plan.png", and contents) are files formatted by a higher
// layer (the HTML report and its plots: report/bundle_html_report.h), written
// with the set after everything was formatted. Throws Error naming the file on failure.
std::vector<std::string> WriteBundleOutputs(const std::string& dir, const BundleResult& result,
                                            const BundleReportOptions& options,
                                            const std::vector<std::pair<std::string, std::string>>& extra_files = {});

}  // namespace platemeter
