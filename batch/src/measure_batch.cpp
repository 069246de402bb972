// The measure work of a batch (measure_batch.h): the plan from the listing, the
// job and the manifest, and the work on one scan through the pipeline.
#include "platemeter/batch/measure_batch.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <utility>

#include "platemeter/batch/scan_list.h"
#include "platemeter/core/error.h"
#include "platemeter/core/sha256.h"

namespace platemeter {
namespace {

// Outputs also depend on the definition files (a camera's grid, fiducials) and on the passpoint
// list's contents, which the options text names only by path: their digests join the fingerprint.
std::string DefinitionsFingerprintText(const std::vector<std::string>& definition_files) {
  std::ostringstream out;
  std::vector<std::string> files;
  if (const char* list = std::getenv("PLATEMETER_DEFINITIONS")) {
    std::stringstream s(list);
    for (std::string f; std::getline(s, f, ':');) {
      if (!f.empty()) files.push_back(f);
    }
  }
  files.insert(files.end(), definition_files.begin(), definition_files.end());
  for (const std::string& f : files) out << "definitions_sha256 = " << Sha256HexOfFile(f) << "\n";
  return out.str();
}

std::string PasspointListFingerprintText(const pipeline::MeasureRequest& m) {
  if (!m.detect.passpoints || m.detect.passpoints->list_file.empty()) return "";
  return "passpoint_list_sha256 = " + Sha256HexOfFile(m.detect.passpoints->list_file) + "\n";
}

ScanWorkResult ToWorkResult(const pipeline::MeasureSummary& s) {
  ScanWorkResult r;
  r.counts_by_status = s.counts_by_status;
  r.counts_by_kind = s.counts_by_kind;
  r.reseau_rms_um = s.reseau_rms_um;
  r.scale_x = s.scale_x;
  r.scale_y = s.scale_y;
  r.written_files = s.written_files;
  r.report_json = s.report_json;
  r.plot_png = s.plot_png;
  return r;
}

}  // namespace

MeasureBatchPlan PlanMeasureBatch(const MeasureBatchRequest& request) {
  std::vector<ScanInput> scans = ListScans(request.input, request.recursive, pipeline::JobOverrideKeys());
  // OUT inside INPUT (with --recursive): its plots are .png files, not scans.
  std::error_code ec;
  const std::string out_prefix = std::filesystem::weakly_canonical(request.out_dir, ec).string() + "/";
  std::erase_if(scans, [&](const ScanInput& s) {
    std::error_code e;
    return std::filesystem::weakly_canonical(s.path, e).string().rfind(out_prefix, 0) == 0;
  });
  if (scans.empty()) throw Error(request.input, "no scan files (.tif .tiff .png .jpg .jpeg .fits .fit)");
  CheckUniqueStems(scans);  // over the whole list, so every shard refuses the same archive
  MeasureBatchPlan plan;
  plan.listed = scans.size();
  const std::string definitions_text = DefinitionsFingerprintText(request.definition_files);
  for (size_t i : ShardPositions(scans.size(), request.shard)) {
    const ScanInput& scan = scans[i];
    pipeline::JobDefinition job = request.job;
    for (const auto& [key, value] : scan.overrides) {
      try {
        pipeline::ApplyJobOverride(job, key, value);
      } catch (const Error& e) {
        throw Error(request.input, "line " + std::to_string(scan.manifest_line) + ": " + e.reason());
      }
    }
    if (job.measure.detect.camera.empty() && job.measure.detect.grid.empty()) {
      throw Error(scan.path, "no camera: give --camera NAME or --job JOB.toml (or a camera column in the manifest)");
    }
    job.measure.detect.scan = scan.path;
    BatchItem item;
    item.input = scan;
    item.options_text =
        pipeline::CanonicalOptionsText(job.measure) + definitions_text + PasspointListFingerprintText(job.measure);
    plan.requests[scan.stem] = job.measure;
    plan.items.push_back(std::move(item));
  }
  return plan;
}

ScanWork MeasureScanWork(const MeasureBatchPlan& plan, const DefinitionRegistry& registry) {
  return [&plan, &registry](const BatchItem& item, const std::string& folder) {
    pipeline::MeasureRequest request = plan.requests.at(item.input.stem);
    request.out_dir = folder;
    return ToWorkResult(pipeline::RunMeasure(request, registry));
  };
}

}  // namespace platemeter
