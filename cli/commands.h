#pragma once
// The platemeter binary: thin subcommands over library calls. Each command
// lives in its own cmd_<name>.cpp and is registered in main.cpp.
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace platemeter::cli {

// Options every subcommand sees.
struct GlobalOptions {
  std::vector<std::string> definition_files;  // extra TOML definition files (--definitions)
  double cache_memory_mb = 128.0;             // MB; the shared image cache (--cache-mb); detection reuses few tiles
};

void RegisterInfoCommand(CLI::App& app, GlobalOptions& global);
void RegisterGridsCommand(CLI::App& app, GlobalOptions& global);
void RegisterSimulateCommand(CLI::App& app, GlobalOptions& global);
void RegisterDetectCommand(CLI::App& app, GlobalOptions& global);
void RegisterMeasureCommand(CLI::App& app, GlobalOptions& global);  // measure and validate
void RegisterBatchCommand(CLI::App& app, GlobalOptions& global);    // batch: whole archives (docs/batch.md)
void RegisterCamerasCommand(CLI::App& app, GlobalOptions& global);  // cameras profile (after RegisterGridsCommand)
void RegisterCalibrateCommand(CLI::App& app, GlobalOptions& global);  // calibrate bundle (docs/bundle-job.md)
void RegisterStarsCommand(CLI::App& app, GlobalOptions& global);  // stars apparent: observed places (docs/apparent-places.md)

}  // namespace platemeter::cli
