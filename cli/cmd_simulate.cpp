// platemeter simulate SPEC.toml -o DIR [--full-size] [--seed N]: renders a
// simulated plate scan with its truth file and true geometry chain
// (docs/simulator.md).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "commands.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace platemeter::cli {

void RegisterSimulateCommand(CLI::App& app, GlobalOptions& global) {
  struct Args {
    std::string spec;
    std::string out_dir;
    bool full_size = false;
    std::optional<uint64_t> seed;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "simulate", "render a simulated plate scan with its truth file and true geometry chain (docs/simulator.md)");
  cmd->add_option("SPEC", args->spec, "the spec (TOML), e.g. samples/specs/orbigon-stellar.toml")->required();
  cmd->add_option("-o,--output", args->out_dir, "output folder (created if missing)")->required();
  cmd->add_flag("--full-size", args->full_size, "render at the spec's full_size_pixel_size_um instead of pixel_size_um");
  cmd->add_option("--seed", args->seed, "replaces the spec's seed (all random choices derive from it)");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  cmd->callback([args, &global] {
    const sim::SimulationSpec spec = sim::ReadSimulationSpec(args->spec);
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    sim::SimulateOptions options;
    options.full_size = args->full_size;
    options.seed = args->seed;
    sim::SimulatedPlate plate = sim::BuildSimulatedPlate(spec, registry, options);
    const long width = plate.scene.width_px, height = plate.scene.height_px;
    std::cerr << "simulate: " << plate.name << ": " << width << " x " << height << " px at " << plate.pixel_size_um
              << " um, " << plate.scene.marks.size() << " marks, " << plate.truth.size() << " truth points\n";
    // Progress only where it helps: renders of more than ~50 Mpx.
    const bool show_progress = !args->quiet && double(width) * double(height) > 5e7;
    const auto start = std::chrono::steady_clock::now();
    int last_percent = -1;
    sim::RenderProgress progress = [&](long rows_done, long rows_total) {
      if (!show_progress) return;
      const int percent = static_cast<int>(100.0 * rows_done / rows_total);
      if (percent / 5 != last_percent / 5 || rows_done == rows_total) {
        last_percent = percent;
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "simulate: rendered %3d %% (%ld of %ld rows, %.0f s)\n", percent, rows_done, rows_total,
                     seconds);
      }
    };
    const sim::SimulateOutputs out = sim::WriteSimulatedPlate(std::move(plate), args->out_dir, progress);
    std::cout << "scan: " << out.image_path << '\n'
              << "truth: " << out.truth_path << '\n'
              << "chain: " << out.chain_path << '\n';
  });
}

}  // namespace platemeter::cli
