#pragma once
// The measure work of a batch (`platemeter batch`, docs/batch.md): every scan of a
// folder or manifest measured by the pipeline (pipeline::RunMeasure) with the job's
// options and the manifest's per-scan overrides. Planned first, so that everything
// that can be wrong with the input is found before the first scan starts; then
// RunBatch (batch_run.h) runs the plan's items with MeasureScanWork.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "platemeter/batch/batch_run.h"
#include "platemeter/batch/shard.h"
#include "platemeter/grids/registry.h"
#include "platemeter/pipeline/job_file.h"
#include "platemeter/pipeline/measure_run.h"

namespace platemeter {

struct MeasureBatchRequest {
  std::string input;              // a folder of scans or a manifest CSV
  bool recursive = false;         // also the scans in sub-folders of a folder
  std::string out_dir;            // OUT: scans inside it are not listed (its plots are .png files)
  Shard shard;                    // this process's share of the list
  pipeline::JobDefinition job;    // every scan's options (the command's flags applied), before the manifest's overrides
  std::vector<std::string> definition_files;  // --definitions: their digests join every scan's fingerprint
};

struct MeasureBatchPlan {
  std::vector<BatchItem> items;                               // this shard's scans, with their options text
  std::map<std::string, pipeline::MeasureRequest> requests;  // by stem: each scan's request (out_dir empty)
  size_t listed = 0;                                          // scans in the whole list (every shard)
};

// Lists the scans, applies each one's overrides and makes its fingerprint text (the options, the
// definition files' and the passpoint list's digests). Throws Error for an unreadable input, a bad
// manifest row (naming its line), duplicate stems, a scan without a camera.
MeasureBatchPlan PlanMeasureBatch(const MeasureBatchRequest& request);

// The work on one scan of `plan`: RunMeasure into the scan's folder. `plan` and `registry` must outlive it.
ScanWork MeasureScanWork(const MeasureBatchPlan& plan, const DefinitionRegistry& registry);

}  // namespace platemeter
