// platemeter simulate SPEC.toml -o DIR [--full-size] [--seed N]: renders a
// simulated plate scan with its truth file and true geometry chain
// (docs/simulator.md); a block spec (a file with a [block] table) renders every
// frame of a block with the files measure, batch and the bundle need
// (docs/block-simulator.md).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "commands.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/block_render.h"
#include "platemeter/samples/block_spec.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace platemeter::cli {
namespace {

// A block spec: lay the block out, render every frame, write the block's files.
void SimulateBlock(const std::string& path, const std::string& out_dir, bool full_size, std::optional<uint64_t> seed,
                   const GlobalOptions& global) {
  sim::BlockSpec spec = sim::ReadBlockSpec(path);
  if (seed) spec.seed = *seed;
  const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
  const sim::BlockLayout layout = sim::LayOutBlock(spec, registry);
  std::cerr << "simulate: " << layout.summary << "\n";
  sim::BlockRenderOptions options;
  options.full_size = full_size;
  const auto start = std::chrono::steady_clock::now();
  const sim::BlockOutputs out =
      sim::WriteSimulatedBlock(spec, layout, registry, out_dir, options,
                               [&](std::size_t index, std::size_t count, const std::string& frame) {
                                 std::cerr << "simulate: frame " << index + 1 << " of " << count << ": " << frame
                                           << " (" << layout.frames[index].points.size() << " passpoints)\n";
                               });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t f = 0; f < out.frames.size(); ++f) std::cout << "scan: " << out.frames[f].image_path << '\n';
  std::cout << "manifest: " << out.manifest_path << '\n'
            << "ground points: " << out.ground_points_path << '\n'
            << "bundle job: " << out.job_path << '\n'
            << "truth: " << out.truth_path << '\n';
  std::fprintf(stderr, "simulate: %zu frames rendered in %.1f s; next:\n", out.frames.size(), seconds);
  std::cerr << "  platemeter batch " << out.manifest_path << " -o " << out.measured_dir << "\n"
            << "  platemeter calibrate bundle " << out.job_path << " -o OUT\n";
}

}  // namespace

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
      "simulate", "render a simulated plate scan with its truth file and true geometry chain (docs/simulator.md), or every "
      "frame of a block spec with its manifest, bundle job and truth (docs/block-simulator.md)");
  cmd->add_option("SPEC", args->spec, "the spec (TOML), e.g. samples/specs/orbigon-stellar.toml, or a block spec "
                 "(samples/blocks/hasselblad-block.toml)")->required();
  cmd->add_option("-o,--output", args->out_dir, "output folder (created if missing)")->required();
  cmd->add_flag("--full-size", args->full_size, "render at the spec's full_size_pixel_size_um instead of pixel_size_um");
  cmd->add_option("--seed", args->seed, "replaces the spec's seed (all random choices derive from it)");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  cmd->callback([args, &global] {
    if (sim::IsBlockSpecFile(args->spec)) {
      SimulateBlock(args->spec, args->out_dir, args->full_size, args->seed, global);
      return;
    }
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
