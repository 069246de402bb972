// platemeter: digital comparator and calibration workbench for metric-camera plates.
#include <exception>
#include <iostream>

#include "commands.h"
#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/version.h"

int main(int argc, char** argv) {
  using namespace platemeter;
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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const Error& e) {
    std::cerr << "platemeter: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "platemeter: error: " << OneLine(e.what()) << '\n';
    return 1;
  }
  return 0;
}
