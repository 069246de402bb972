#pragma once
// platemeter calibrate stellar JOB.toml -o DIR: seed 001's stellar calibration
// of star plates (calib/stellar_job.h, docs/stellar-job.md).
#include <CLI/CLI.hpp>

#include "commands.h"

namespace platemeter::cli {

// Adds `stellar` to the `calibrate` command.
void RegisterCalibrateStellar(CLI::App* calibrate, GlobalOptions& global);

}  // namespace platemeter::cli
