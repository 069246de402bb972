// platemeter calibrate bundle: the self-calibrating bundle adjustment of seed
// 000 on a job file or on an observations CSV (docs/bundle-job.md), writing
// calibration.json, report.md, report.html with its plots, residuals.csv and
// the calibrated camera.
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "cmd_calibrate_simulate.h"
#include "cmd_calibrate_stellar.h"
#include "written_outputs.h"
#include "commands.h"
#include "platemeter/core/output_set.h"
#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/calib/bundle_report.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/report/bundle_html_report.h"

namespace platemeter::cli {
namespace {

struct BundleCommandOptions {
  std::string job;
  std::string output_dir;
  std::vector<std::string> observations;
  std::string ground_points;
  double principal_distance_mm = 0.0;
  std::string camera;  // a camera definition to start from
  std::string free = "c,xp,yp,k1,k2,p1,p2";
  std::string datum = "auto";
  double robust_scale = 0.0;
  double balance_radius_mm = 0.0;
  bool quiet = false;
};

// "c,xp,k1" -> the camera's parameter states (listed: free, others fixed).
void SetFreeParameters(const std::string& list, CameraSetup* camera) {
  static const std::map<std::string, int> kShort = {{"c", 0},  {"xp", 1}, {"yp", 2}, {"k1", 3}, {"k2", 4},
                                                    {"k3", 5}, {"p1", 6}, {"p2", 7}, {"b1", 8}, {"b2", 9}};
  std::stringstream stream(list);
  std::string name;
  while (std::getline(stream, name, ',')) {
    if (name.empty()) continue;
    auto it = kShort.find(name);
    int index = -1;
    if (it != kShort.end()) index = it->second;
    for (int i = 0; i < kBundleCameraParams; ++i) {
      if (name == kBundleCameraParamNames[i]) index = i;
    }
    if (index < 0) throw Error("--free", "unknown parameter '" + name + "' (known: c, xp, yp, k1, k2, k3, p1, p2, b1, b2)");
    camera->states[index] = ParameterState::Free();
  }
}

BundleJob JobFromFlags(const BundleCommandOptions& o, const GlobalOptions& global) {
  BundleJob job;
  job.source = o.observations.front();
  for (const std::string& path : o.observations) {
    const std::vector<ImageObservation> part = ReadObservationsCsv(path);
    job.input.observations.insert(job.input.observations.end(), part.begin(), part.end());
  }
  if (!o.ground_points.empty()) job.input.ground_points = ReadGroundPointsCsv(o.ground_points);
  CameraSetup camera;
  if (!o.camera.empty()) {
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    camera = CameraSetupFromDefinition(registry.Camera(o.camera), "camera", &job.warnings);
  } else if (o.principal_distance_mm > 0.0) {
    camera.values[0] = o.principal_distance_mm;
  } else {
    throw Error("calibrate bundle", "give --principal-distance-mm (the approximate focal length) or --camera NAME");
  }
  camera.name = "camera";
  for (auto& state : camera.states) state = ParameterState::Fixed();
  SetFreeParameters(o.free, &camera);
  job.input.cameras.push_back(camera);
  if (!ParseDatumKind(o.datum, &job.options.datum)) {
    throw Error("--datum", "unknown datum '" + o.datum + "' (auto, control, fixed-frames, inner-constraints)");
  }
  job.options.adjustment.robust_loss_scale = o.robust_scale;
  if (o.balance_radius_mm > 0.0) job.output.balance_radius_mm = o.balance_radius_mm;
  return job;
}

void RunBundle(const BundleCommandOptions& o, const GlobalOptions& global) {
  if (o.job.empty() == o.observations.empty()) {
    throw Error("calibrate bundle", "give a job file or --observations (one of them)");
  }
  BundleJob job = o.job.empty() ? JobFromFlags(o, global)
                                 : ReadBundleJob(o.job, DefinitionRegistry::Load(global.definition_files));
  if (o.balance_radius_mm > 0.0) job.output.balance_radius_mm = o.balance_radius_mm;
  CheckedBundleInput checked = CheckBundleInput(job.input, job.check_options);
  std::vector<BundleWarning> warnings = job.warnings;
  warnings.insert(warnings.end(), checked.warnings.begin(), checked.warnings.end());
  for (const BundleWarning& w : warnings) std::cerr << "platemeter: warning: " << w.item << ": " << w.reason << '\n';
  AdjustmentProgress progress;
  if (!o.quiet) {
    progress = [last = std::string()](const std::string& stage, double fraction) mutable {
      if (stage != last) std::cerr << "calibrate bundle: " << stage << "...\n";
      last = stage;
      (void)fraction;
    };
  }
  const BundleResult result = RunBundleAdjustment(checked.input, job.options, progress);
  BundleReportOptions report;
  report.title = job.output.title.empty() ? "Self-calibrating bundle adjustment: " + job.source : job.output.title;
  report.balance_radius_mm = job.output.balance_radius_mm;
  report.warnings = warnings;
  report.export_pixel_size_um = job.output.export_pixel_size_um;
  report.export_image_size_px = job.output.export_image_size_px;
  // The HTML report and its plots are formatted first and written with the set.
  const auto html = report::FormatBundleHtmlReport(result, checked.input, report);
  const std::vector<std::string> written = WriteBundleOutputs(o.output_dir, result, report, html);
  RemoveStalePlots(o.output_dir, written);
  std::cout << result.adjustment.summary << '\n';
  for (const BundleCameraResult& camera : result.cameras) {
    std::cout << "camera " << camera.name << ":";
    for (int i = 0; i < kBundleCameraParams; ++i) {
      if (!camera.sigmas[i]) continue;
      std::cout << ' ' << kBundleCameraParamNames[i] << " = " << camera.values[i] << " +- " << *camera.sigmas[i] << ';';
    }
    std::cout << '\n';
  }
  PrintWritten(o.output_dir, written);
}

}  // namespace

void RegisterCalibrateCommand(CLI::App& app, GlobalOptions& global) {
  auto* calibrate = app.add_subcommand("calibrate", "adjustments that recover a camera's calibration");
  calibrate->require_subcommand(1);
  auto o = std::make_shared<BundleCommandOptions>();
  auto* bundle = calibrate->add_subcommand(
      "bundle", "self-calibrating bundle adjustment (seed 000) of a job file or an observations CSV (docs/bundle-job.md)");
  bundle->add_option("JOB", o->job, "bundle job file (TOML)")->check(CLI::ExistingFile);
  bundle->add_option("-o,--output", o->output_dir, "output folder")->required();
  bundle->add_option("--observations", o->observations, "observations CSV: frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm")
      ->check(CLI::ExistingFile);
  bundle->add_option("--ground-points", o->ground_points, "ground points CSV: point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m")
      ->check(CLI::ExistingFile);
  bundle->add_option("--principal-distance-mm", o->principal_distance_mm, "approximate principal distance, mm")
      ->check(CLI::PositiveNumber);
  bundle->add_option("--camera", o->camera, "start from this camera definition (see `platemeter cameras list`)");
  bundle->add_option("--free", o->free, "camera parameters to adjust (c,xp,yp,k1,k2,k3,p1,p2,b1,b2); others are fixed")
      ->capture_default_str();
  bundle->add_option("--datum", o->datum, "auto, control, fixed-frames or inner-constraints")->capture_default_str();
  bundle->add_option("--robust-scale", o->robust_scale, "robust first pass: Cauchy scale in sigmas (0 = none)")
      ->check(CLI::NonNegativeNumber);
  bundle->add_option("--balance-radius-mm", o->balance_radius_mm, "report the radial profile balanced to zero here, mm")
      ->check(CLI::PositiveNumber);
  bundle->add_flag("--quiet", o->quiet, "no progress on stderr");
  bundle->callback([o, &global] {
    InstallOutputSetInterruptCleanup();
    RunBundle(*o, global);
  });
  RegisterCalibrateSimulate(calibrate, global);
  RegisterCalibrateStellar(calibrate, global);
}

}  // namespace platemeter::cli
