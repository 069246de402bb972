// platemeter measure SCAN --camera NAME ... -o DIR: detect, then the comparator
// corrections into a measurement file with plate millimetres and a JSON report
// (the flow is measure_run.cpp's); platemeter validate SCAN ...: the reseau check
// alone (docs/measure.md). Both take --job JOB.toml (docs/job.md).
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "detect_options.h"
#include "job.h"
#include "measure_prepare.h"
#include "measure_report.h"
#include "measure_run.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/atomic_file.h"
#include "platemeter/measure/residual_plot.h"

namespace platemeter::cli {
namespace {

// The options of measure and validate: the scan's detection part and the corrections part, each laid
// over the --job file's values.
struct MeasureOptions {
  explicit MeasureOptions(CLI::App* cmd) : detect(cmd), measure(cmd) {}
  OptionOverlay<DetectRequest> detect;
  OptionOverlay<MeasureRequest> measure;
  std::string scan, out_dir, job_file;

  MeasureRequest Resolve(const std::string& command) const {
    MeasureRequest request = job_file.empty() ? MeasureRequest{} : LoadJobFile(job_file).measure;
    request.detect = detect.Resolve(request.detect);
    request = measure.Resolve(request);
    request.detect.scan = scan;
    request.out_dir = out_dir;
    if (request.detect.camera.empty()) throw Error(command, "give --camera NAME (or camera in the --job file)");
    return request;
  }
};

std::shared_ptr<MeasureOptions> AddOptions(CLI::App* cmd) {
  auto o = std::make_shared<MeasureOptions>(cmd);
  cmd->add_option("SCAN", o->scan, "the scan, or detect's <scan>.measurements.csv")->required();
  o->detect.Option("--camera", [](DetectRequest& r) -> auto& { return r.camera; }, "camera definition");
  AddScanOptions(o->detect);
  auto field = [&o](const std::string& name, auto get, const std::string& help) { return o->measure.Option(name, get, help); };
  field("--temperature-degC", [](MeasureRequest& r) -> auto& { return r.temperature_degC; },
        "measuring temperature (thermal scaling to the grid's calibration temperature)");
  field("--refractive-index", [](MeasureRequest& r) -> auto& { return r.refractive_index; }, "emulsion refractive index (1.65)");
  field("--model", [](MeasureRequest& r) -> auto& { return r.model; }, "reseau fit model: similarity, affine, scales, projective (scales)");
  field("--rejection-threshold", [](MeasureRequest& r) -> auto& { return r.rejection_threshold; },
        "normalized residual above which a cross is rejected (4)");
  field("--tolerance-um", [](MeasureRequest& r) -> auto& { return r.tolerance_um; },
        "residual tolerance for the out-of-tolerance flags (5 um)");
  field("--fiducial-model", [](MeasureRequest& r) -> auto& { return r.fiducial_model; },
        "fiducial interior orientation model: similarity, affine (affine)");
  cmd->add_option("--job", o->job_file, "job definition file (docs/job.md); options given here override its values");
  cmd->add_option("-o,--output", o->out_dir, "output folder")->required();
  return o;
}

void RegisterValidate(CLI::App& app, GlobalOptions& global) {
  auto* val = app.add_subcommand("validate", "the reseau check alone: residuals, scales, non-orthogonality, emulsion-depth reading");
  auto o = AddOptions(val);
  o->measure.Option("--emulsion-depth-um", [](MeasureRequest& r) -> auto& { return r.emulsion_depth_um; },
                    "correct this depth first (default none: the discrepancy reads as a depth)");
  val->callback([o, &global] {
    const MeasureRequest request = o->Resolve("validate");
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    std::string messages;
    PreparedMeasurement p = PrepareMeasurement(request, registry, false, &messages);
    std::cout << messages;
    const PlateCorrectionReport report = CorrectPlate(&p.file, *p.grid, p.options);
    std::filesystem::create_directories(request.out_dir);
    const std::string json = (std::filesystem::path(request.out_dir) / (p.stem + ".validate.json")).string();
    WriteFileAtomically(json, ValidationJson(report, request.tolerance_um).dump(2) + "\n");
    const std::string png = (std::filesystem::path(request.out_dir) / (p.stem + ".residuals.png")).string();
    ResidualPlotOptions plot;
    plot.tolerance_um = request.tolerance_um;
    WriteResidualPlotPng(png, report.observations, report.fit, plot);
    const ReseauFit& f = report.fit;
    std::cout << "reseau fit (" << ReseauFitModelName(f.model) << "): " << f.used << " crosses, " << f.rejected
              << " rejected, rms " << f.rms_mm * 1e3 << " um\n"
              << "scale x " << f.scale_x.value << " +- " << f.scale_x.sigma << ", y " << f.scale_y.value << " +- "
              << f.scale_y.sigma << ", non-orthogonality " << f.non_orthogonality_rad.value * kRadToArcsec << " +- "
              << f.non_orthogonality_rad.sigma * kRadToArcsec << " arcsec\n"
              << "scale discrepancy " << (f.mean_scale.value - 1.0) * 1e6 << " +- " << f.mean_scale.sigma * 1e6
              << " ppm, as emulsion depth " << report.emulsion_depth_reading_um.value << " +- "
              << report.emulsion_depth_reading_um.sigma << " um\n"
              << json << "\n" << png << "\n";
  });
}

}  // namespace

void RegisterMeasureCommand(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("measure", "detect, correct (thermal, emulsion depth, reseau fit, local reseau) and write plate mm");
  auto o = AddOptions(cmd);
  AddFeatureOptions(o->detect);
  MeasureOptions& m = *o;
  m.measure.Option("--emulsion-depth-um", [](MeasureRequest& r) -> auto& { return r.emulsion_depth_um; },
                   "depth of the image centroid in the emulsion (0: no correction)");
  m.measure.Flag("--no-local-reseau", [](MeasureRequest& r) -> auto& { return r.no_local; },
                 "skip the bilinear local reseau correction");
  m.measure.Flag("--fiducial-orientation", [](MeasureRequest& r) -> auto& { return r.fiducial_orientation; },
                 "reseau cameras: also fit the fiducials and map every point into their frame (fiducial-only cameras always)");
  m.measure.Option("--min-cross-fraction", [](MeasureRequest& r) -> auto& { return r.min_cross_fraction; },
                   "share of the grid's crosses the reseau fit must use, else the scan fails (0.5)");
  m.measure.Option("--second-scan", [](MeasureRequest& r) -> auto& { return r.second_scan; },
                   "the plate scanned a second time (rotated 180 deg): both corrected, then meaned");
  m.measure.Option("--second-orientation", [](MeasureRequest& r) -> auto& { return r.second_orientation; },
                   "the second scan's known orientation (e.g. 180)");
  cmd->callback([o, &global] {
    const MeasureRequest request = o->Resolve("measure");
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    std::cout << RunMeasure(request, registry).message;
  });
  RegisterValidate(app, global);
}

}  // namespace platemeter::cli
