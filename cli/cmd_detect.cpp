// platemeter detect SCAN (--camera NAME | --grid NAME | --job JOB.toml) -o DIR: reseau
// crosses and fiducial marks with ids, positions, sigmas and statuses (and stars,
// trails, passpoints on request), into a measurement file and a JSON summary (the
// flow is the pipeline's RunDetection, pipeline/detect_run.h; the options detect_options.cpp's).
#include <iostream>
#include <memory>

#include "commands.h"
#include "detect_options.h"
#include "platemeter/core/output_set.h"
#include "platemeter/pipeline/detect_run.h"
#include "platemeter/pipeline/job_file.h"

namespace platemeter::cli {

void RegisterDetectCommand(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("detect", "find the reseau crosses and fiducials of a scan and measure them");
  auto overlay = std::make_shared<OptionOverlay<DetectRequest>>(cmd);
  auto scan = std::make_shared<std::string>();
  auto out_dir = std::make_shared<std::string>();
  auto job_file = std::make_shared<std::string>();
  cmd->add_option("SCAN", *scan, "the scan")->required();
  auto* camera = overlay->Option("--camera", [](DetectRequest& r) -> auto& { return r.camera; },
                                 "camera definition (its grid and fiducials are searched)");
  auto* grid = overlay->Option("--grid", [](DetectRequest& r) -> auto& { return r.grid; },
                               "master grid to search for (no fiducials)");
  camera->excludes(grid);
  overlay->OnGiven(camera, [](DetectRequest& r) { r.grid.clear(); });  // over a job's grid
  overlay->OnGiven(grid, [](DetectRequest& r) { r.camera.clear(); });  // over a job's camera
  AddScanOptions(*overlay);
  AddFeatureOptions(*overlay);
  cmd->add_option("--job", *job_file, "job definition file (docs/job.md); options given here override its values");
  cmd->add_option("-o,--output", *out_dir, "output folder")->required();
  cmd->callback([overlay, scan, out_dir, job_file, &global] {
    DetectRequest request =
        overlay->Resolve(job_file->empty() ? DetectRequest{} : pipeline::LoadJobFile(*job_file).measure.detect);
    request.scan = *scan;
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    pipeline::CheckDetectOptions(request);
    InstallOutputSetInterruptCleanup();
    OutputSet outputs(*out_dir, pipeline::DetectSetMembers(request.scan));
    const pipeline::DetectRun run = pipeline::RunDetection(request, registry);
    const pipeline::DetectFiles files = pipeline::WriteDetectRun(run, request.scan, &outputs);
    std::cout << run.messages << files.measurements_csv << "\n" << files.summary_json << "\n";
  });
}

}  // namespace platemeter::cli
