// platemeter measure SCAN --camera NAME ... -o DIR: detect, then the comparator
// corrections into a measurement file with plate millimetres and a JSON report
// (the flow is the pipeline's RunMeasure, pipeline/measure_run.h); platemeter validate
// SCAN ...: the reseau check alone (RunValidate; docs/measure.md). Both take
// --job JOB.toml (docs/job.md).
#include <iostream>
#include <memory>

#include "commands.h"
#include "detect_options.h"
#include "platemeter/core/error.h"
#include "platemeter/core/output_set.h"
#include "platemeter/grids/registry.h"
#include "platemeter/pipeline/job_file.h"
#include "platemeter/pipeline/measure_run.h"

namespace platemeter::cli {
namespace {

using pipeline::MeasureRequest;

// The options of measure and validate: the scan's detection part and the corrections part, each laid
// over the --job file's values.
struct MeasureOptions {
  explicit MeasureOptions(CLI::App* cmd) : detect(cmd), measure(cmd) {}
  OptionOverlay<DetectRequest> detect;
  OptionOverlay<MeasureRequest> measure;
  std::string scan, out_dir, job_file;

  MeasureRequest Resolve(const std::string& command) const {
    MeasureRequest request = job_file.empty() ? MeasureRequest{} : pipeline::LoadJobFile(job_file).measure;
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
    InstallOutputSetInterruptCleanup();
    pipeline::RunValidate(request, registry, std::cout);
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
                 "never apply the bilinear local reseau correction (by default it is applied where the crosses' residuals show film deformation beyond their measuring noise)");
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
    InstallOutputSetInterruptCleanup();
    std::cout << pipeline::RunMeasure(request, registry).message;
  });
  RegisterValidate(app, global);
}

}  // namespace platemeter::cli
