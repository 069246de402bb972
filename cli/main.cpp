// platemeter: digital comparator and calibration workbench for metric-camera plates.
#include <glog/logging.h>

#include <exception>
#include <iostream>

#include "commands.h"
#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/version.h"

int main(int argc, char** argv) {
  using namespace platemeter;
  // The solvers' own log lines (Ceres through glog) would break the one-line error policy; every
  // failure they report is checked and turned into platemeter's own status or message.
  FLAGS_minloglevel = google::GLOG_FATAL;
  CLI::App app{"platemeter: measure and calibrate scanned metric-camera plates and films"};
  app.set_version_flag("--version", std::string("platemeter ") + kVersion);
  app.require_subcommand(1);
  app.fallthrough();

  cli::GlobalOptions global;
  app.add_option("--definitions", global.definition_files,
                 "extra TOML definition file(s) of grids, fiducial sets and cameras (docs/definitions.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--cache-mb", global.cache_memory_mb, "memory for the shared image tile cache, in MB")
      ->check(CLI::Range(16.0, 1.0e6));
  app.parse_complete_callback([&global] {
    ImageCacheOptions cache;
    cache.max_memory_mb = global.cache_memory_mb;
    ConfigureImageCache(cache);
  });

  cli::RegisterInfoCommand(app, global);
  cli::RegisterGridsCommand(app, global);
  cli::RegisterSimulateCommand(app, global);
  cli::RegisterDetectCommand(app, global);
  cli::RegisterMeasureCommand(app, global);
  cli::RegisterBatchCommand(app, global);
  cli::RegisterCamerasCommand(app, global);
  cli::RegisterCalibrateCommand(app, global);
  cli::RegisterStarsCommand(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own exit code (batch: 1 some scan failed, 130 interrupted, ...)
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; any usage error 2 (CLI11's own codes vary by error).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const Error& e) {
    std::cerr << "platemeter: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "platemeter: error: " << OneLine(e.what()) << '\n';
    return 1;
  }
  return 0;
}
