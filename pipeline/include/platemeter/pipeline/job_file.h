#pragma once
// Job definition files (docs/job.md): the options of `platemeter measure` for a
// set of scans, in TOML; read by `detect --job`, `measure --job` and `batch`
// (batch/measure_batch.h), with a manifest's per-scan overrides.
#include <string>
#include <vector>

#include "platemeter/pipeline/measure_run.h"

namespace platemeter::pipeline {

struct JobDefinition {
  MeasureRequest measure;  // scan and out_dir empty
  std::string source;      // the file it came from
};

// Reads a job TOML file (docs/job.md). Throws Error(path, "line N: reason") for unknown keys, wrong types, bad values.
JobDefinition LoadJobFile(const std::string& path);
// The same for the file's text; `path` names it in errors and anchors its relative paths.
JobDefinition ParseJobFile(const std::string& text, const std::string& path);

// Applies one per-scan override (a manifest column), e.g. key "orientation" value "90m", "temperature_degC" "21.5",
// "trails.start_utc" "1972-05-12T05:30:00Z", "pixel_size_um" "12.5". Throws Error("manifest", ...) for an unknown
// key or bad value.
void ApplyJobOverride(JobDefinition& job, const std::string& key, const std::string& value);

// The keys ApplyJobOverride accepts (for docs/errors).
const std::vector<std::string>& JobOverrideKeys();

}  // namespace platemeter::pipeline
