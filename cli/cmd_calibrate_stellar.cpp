// platemeter calibrate stellar (cmd_calibrate_stellar.h).
#include "cmd_calibrate_stellar.h"

#include "written_outputs.h"

#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "platemeter/core/output_set.h"
#include "platemeter/calib/stellar_job.h"
#include "platemeter/calib/stellar_report.h"
#include "platemeter/grids/registry.h"
#include "platemeter/report/stellar_html_report.h"

namespace platemeter::cli {
namespace {

struct StellarCommandOptions {
  std::string job;
  std::string output_dir;
  bool quiet = false;
};

void PrintCamera(const std::string& what, DistortionModelId lens, const StellarCamera& values,
                 const StellarCamera& sigmas) {
  const ReportedCamera c = ReportCamera(lens, values, sigmas);
  std::cout << what << " (" << c.frame << "):";
  for (size_t i = 0; i < c.names.size(); ++i)
    std::cout << fmt::format(" {} = {:.6g} +- {:.3g};", c.names[i], c.value[i], c.sigma[i]);
  std::cout << '\n';
}

void RunStellar(const StellarCommandOptions& o, const GlobalOptions& global) {
  const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
  const StellarJob job = ReadStellarJob(o.job, registry);
  AdjustmentProgress progress;
  if (!o.quiet) {
    progress = [last = std::string()](const std::string& stage, double) mutable {
      if (stage != last) std::cerr << "calibrate stellar: " << stage << "...\n";
      last = stage;
    };
  }
  const StellarJobResult result = RunStellarJob(job, progress);
  std::vector<const MasterGrid*> grids;
  for (const CameraDefinition& camera : job.cameras) grids.push_back(registry.FindGrid(camera.grid));
  const auto html = report::FormatStellarHtmlReport(job, result, grids);
  const std::vector<std::string> written = WriteStellarOutputs(o.output_dir, job, result, html);
  RemoveStalePlots(o.output_dir, written);
  for (const StellarPlateResult& s : result.singles) {
    std::cout << fmt::format("plate {}: {} images of {} catalog and {} unknown stars, {} rejected; m_o = {:.3f} with "
                             "{:.0f} degrees of freedom, m_p = {:.2f} um\n",
                             s.plate_id, s.images, s.catalog_stars, s.unknown_stars, s.rejected_images, s.m_o,
                             s.adjustment.dof, s.m_p_um);
  }
  for (const StellarCombination& c : result.combinations) {
    std::cout << fmt::format("combination {}: m_0 = {:.3f} with {:.0f} degrees of freedom\n", c.name, c.m_0, c.dof);
  }
  for (size_t k = 0; k < job.cameras.size(); ++k) {
    int combination = -1;
    for (size_t c = 0; c < result.combinations.size(); ++c) {
      if (result.combination_camera[c] == static_cast<int>(k)) combination = static_cast<int>(c);
    }
    if (combination >= 0) {
      const StellarCombination& c = result.combinations[combination];
      PrintCamera("camera " + job.cameras[k].name + " (" + c.name + ")", job.options.lens_model, c.camera,
                  c.camera_sigma);
      continue;
    }
    for (size_t i = 0; i < result.singles.size(); ++i) {
      if (job.plates[i].camera != static_cast<int>(k)) continue;
      PrintCamera("camera " + job.cameras[k].name + " (plate " + result.singles[i].plate_id + ")",
                  job.options.lens_model, result.singles[i].camera, result.singles[i].camera_sigma);
      break;
    }
  }
  if (result.interlock) {
    const StellarInterlockResult& r = *result.interlock;
    std::cout << fmt::format("cameras exposed together ({} exposures): sigma0 = {:.3f} with {:.0f} degrees of freedom\n",
                             r.exposures, r.adjustment.sigma0, r.adjustment.dof);
    for (const CameraInterlockResult& i : r.interlocks)
      std::cout << "interlock " << i.from << " -> " << i.to << ": " << i.angles.summary << '\n';
  }
  PrintWritten(o.output_dir, written);
}

}  // namespace

void RegisterCalibrateStellar(CLI::App* calibrate, GlobalOptions& global) {
  auto o = std::make_shared<StellarCommandOptions>();
  auto* stellar = calibrate->add_subcommand(
      "stellar", "stellar calibration of star plates (seed 001): identification, per-plate adjustment, weighted mean, "
                 "cameras exposed together (seed 004) (docs/stellar-job.md)");
  stellar->add_option("JOB", o->job, "stellar job file (TOML)")->required()->check(CLI::ExistingFile);
  stellar->add_option("-o,--output", o->output_dir, "output folder")->required();
  stellar->add_flag("--quiet", o->quiet, "no progress on stderr");
  stellar->callback([o, &global] {
    InstallOutputSetInterruptCleanup();
    RunStellar(*o, global);
  });
}

}  // namespace platemeter::cli
