// Every frame of a laid-out block rendered as a plate (simulate.h) with the
// block's passpoints, its approximate passpoint list, then the block's files
// (docs/block-simulator.md).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/samples/block_render.h"

namespace platemeter::sim {

SimulationSpec FrameSimulationSpec(const BlockSpec& spec, const BlockLayout& layout, std::size_t index) {
  const BlockFrame& frame = layout.frames.at(index);
  SimulationSpec s = spec.frame_spec;
  s.name = frame.station.id;
  s.description = "frame " + frame.station.id + " of the rendered block '" + spec.name + "'";
  s.seed = frame.seed;
  s.scanner.rotation_deg = frame.scanner_rotation_deg;
  for (int k = 0; k < 4; ++k) s.film.affine_ppm[k] = frame.film_affine_ppm[k];
  // The rear nodal point lies the true principal distance above the emulsion.
  s.emulsion.principal_distance_mm = layout.camera.c_mm;
  s.passpoints.count = 0;
  s.passpoints.points.clear();
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    SpecPoint p;
    p.id = layout.points[frame.points[i]].id;
    p.x_mm = frame.plate_mm[i].x();
    p.y_mm = frame.plate_mm[i].y();
    s.passpoints.points.push_back(std::move(p));
  }
  return s;
}

std::string PasspointListCsv(const BlockSpec& spec, const BlockFrame& frame, const SimulatedPlate& plate) {
  std::mt19937_64 random(frame.transfer_seed);
  std::normal_distribution<double> normal(0.0, spec.transfer.sigma_px);
  std::ostringstream out;
  out << "# approximate passpoint positions of frame " << frame.station.id << " (block '" << spec.name
      << "'): the true marks perturbed by " << spec.transfer.sigma_px
      << " px per axis, as an operator's point transfer gives them (docs/passpoints.md)\n"
      << "id,x_px,y_px\n";
  char line[160];
  for (const MeasuredPoint& t : plate.truth) {
    if (t.kind != PointKind::kPasspoint) continue;
    const double x = *t.x_px + normal(random), y = *t.y_px + normal(random);
    std::snprintf(line, sizeof line, "%s,%.2f,%.2f\n", t.id.c_str(), x, y);
    out << line;
  }
  return out.str();
}

namespace {

// Every passpoint must land on the scan (its mark rendered whole): the
// frame spec's margin is too small otherwise.
void CheckPasspointsOnScan(const BlockSpec& spec, const SimulatedPlate& plate) {
  for (const MeasuredPoint& t : plate.truth) {
    if (t.kind != PointKind::kPasspoint) continue;
    for (const std::string& flag : t.flags) {
      if (flag == "outside_image") {
        throw Error(spec.frame_spec_path, "frame " + plate.name + ": passpoint " + t.id +
                                              " falls outside the scan: give output.margin_mm or the block's "
                                              "points.format_margin_mm more room");
      }
    }
  }
}

}  // namespace

BlockOutputs WriteSimulatedBlock(const BlockSpec& spec, const BlockLayout& layout, const DefinitionRegistry& registry,
                                 const std::string& out_dir, const BlockRenderOptions& options,
                                 const BlockProgress& progress) {
  namespace fs = std::filesystem;
  const fs::path dir(out_dir);
  BlockOutputs out;
  out.measured_dir = (dir / spec.bundle.measured_dir).string();

  // Every frame's plate first (no pixels): a frame that does not fit its
  // camera stops the run before any file is written.
  std::vector<SimulatedPlate> plates;
  std::vector<std::string> lists, scans;  // scans: file names, relative to out_dir (the manifest's folder)
  for (std::size_t f = 0; f < layout.frames.size(); ++f) {
    const BlockFrame& frame = layout.frames[f];
    SimulateOptions plate_options;
    plate_options.full_size = options.full_size;
    plates.push_back(BuildSimulatedPlate(FrameSimulationSpec(spec, layout, f), registry, plate_options));
    plates.back().spec_origin = spec.origin + " (frame " + frame.station.id + ")";
    CheckPasspointsOnScan(spec, plates.back());
    lists.push_back(PasspointListCsv(spec, frame, plates.back()));
    scans.push_back(frame.station.id + ".tif");
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) throw Error(out_dir, "cannot create the output folder");
  for (std::size_t f = 0; f < layout.frames.size(); ++f) {
    const std::string& id = layout.frames[f].station.id;
    if (progress) progress(f, layout.frames.size(), id);
    const auto start = std::chrono::steady_clock::now();
    out.frames.push_back(WriteSimulatedPlate(std::move(plates[f]), out_dir));
    const std::string list_path = (dir / (id + ".passpoints.csv")).string();
    WriteFileAtomically(list_path, lists[f]);
    out.passpoint_lists.push_back(list_path);
    out.frame_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  std::vector<std::string> absolute_lists;
  for (const std::string& list : out.passpoint_lists) absolute_lists.push_back(fs::absolute(list).lexically_normal().string());
  out.manifest_path = (dir / (spec.name + ".manifest.csv")).string();
  WriteFileAtomically(out.manifest_path, BlockManifestCsv(spec, layout, scans, absolute_lists));
  const std::string ground_points_file = spec.name + ".ground_points.csv";
  out.ground_points_path = (dir / ground_points_file).string();
  WriteGroundPointsCsv(out.ground_points_path, layout.ground_points);
  out.job_path = (dir / (spec.name + ".bundle.toml")).string();
  WriteFileAtomically(out.job_path, BlockBundleJobToml(spec, layout, ground_points_file));
  out.truth_path = (dir / (spec.name + ".truth.json")).string();
  WriteFileAtomically(out.truth_path, BlockTruthJson(spec, layout, out, options));
  return out;
}

}  // namespace platemeter::sim
