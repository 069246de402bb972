#pragma once
// A rendered block (docs/block-simulator.md): the block spec's geometry laid
// out through the true camera, then every frame rendered as a plate with the
// frame spec's look and the block's passpoints at their projected positions.
//
// The lens enters exactly once. LayOutBlock projects each ground point
// through the true camera (seed 000 eq. 1, bundle_block.h ProjectPoint: the
// distortion included) to its position in the camera frame, which is the
// plate frame of the simulator (mm, x right, y up, origin at the format's
// centre; the principal point at xp, yp). Those positions become the frame's
// explicit passpoints, and the plate simulator's chain (geometry.h) does not
// apply any lens to passpoints: it adds what a scan adds on top (thermal,
// emulsion depth, film deformation, scanner), which measure undoes with the
// frame spec's settings (the emulsion step at the true principal distance,
// the film and scanner affinities by the fiducial interior orientation). What
// measure writes for a passpoint is then the projected position plus
// measurement error, and the bundle recovers the lens from it.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/block_spec.h"
#include "platemeter/samples/bundle_block.h"
#include "platemeter/samples/simulate.h"

namespace platemeter::sim {

// One frame of the layout.
struct BlockFrame {
  StationTruth station;                  // true station, attitude (seed 000's T), roll, orbit, exposure
  std::vector<int> points;               // indices into BlockLayout::points seen in this frame, ascending
  std::vector<Eigen::Vector2d> plate_mm; // their true positions in the camera frame (distortion included), mm
  double scanner_rotation_deg = 0.0;     // this frame's scanner.rotation_deg (frame spec + variation)
  double film_affine_ppm[4] = {0, 0, 0, 0};  // this frame's film.affine_ppm
  std::uint64_t seed = 0;                // the frame's plate seed (noise, terrain)
  std::uint64_t transfer_seed = 0;       // the errors of its approximate passpoint list
};

struct BlockLayout {
  BundleCameraTruth camera;              // the true camera, its format the definition's
  std::string camera_definition;         // the frame spec's camera (measure, the job's [[camera]] from)
  std::vector<BlockFrame> frames;
  std::vector<PointTruth> points;        // true ground points (kept ones, generator order)
  std::vector<bool> control;             // per point: a control point
  std::vector<std::string> dropped;      // ids left out: closer than min_separation_mm to another in some frame
  std::vector<GroundPoint> ground_points;  // the ground points CSV: control (sigmas) and tie points (approximations)
  std::vector<FrameSetup> approximations;  // per frame: approximate station and angles for the job
  std::string summary;                   // one line: what the block is
};

// Lays the block out (no pixels). Throws Error(block file, ...) when the frame
// spec's camera is unknown or has no fiducials, when the geometry cannot be
// built, or when too few points are left for the control.
BlockLayout LayOutBlock(const BlockSpec& spec, const DefinitionRegistry& registry);

// The plate spec of frame `index`: the frame spec with the frame's name and
// seed, its chain variation, the emulsion step at the true principal distance,
// and the frame's points as explicit passpoints (ids = ground point ids;
// the frame spec's own passpoints and random count are replaced).
SimulationSpec FrameSimulationSpec(const BlockSpec& spec, const BlockLayout& layout, std::size_t index);

struct BlockRenderOptions {
  bool full_size = false;  // frames at the frame spec's full_size_pixel_size_um
  bool Check(std::string* why) const { return true; }
};

struct BlockOutputs {
  std::vector<SimulateOutputs> frames;         // per frame: scan, truth, chain
  std::vector<std::string> passpoint_lists;    // per frame: <frame>.passpoints.csv
  std::vector<double> frame_seconds;           // per frame: wall time of the render and its files, s
  std::string manifest_path;                   // <name>.manifest.csv (platemeter batch)
  std::string ground_points_path;              // <name>.ground_points.csv
  std::string job_path;                        // <name>.bundle.toml (platemeter calibrate bundle)
  std::string truth_path;                      // <name>.truth.json
  std::string measured_dir;                    // where batch must write for the job to find the frames
};

// Called before each frame is rendered: index, count, frame id.
using BlockProgress = std::function<void(std::size_t index, std::size_t count, const std::string& frame)>;

// Renders every frame (WriteSimulatedPlate) and writes the block's files into
// out_dir (created if missing); each file appears only when complete.
BlockOutputs WriteSimulatedBlock(const BlockSpec& spec, const BlockLayout& layout, const DefinitionRegistry& registry,
                                 const std::string& out_dir, const BlockRenderOptions& options = {},
                                 const BlockProgress& progress = {});

// The block's files alone (used by WriteSimulatedBlock once the frames exist):
// the approximate passpoint list of one frame from its rendered truth (the true
// pixel positions perturbed by transfer.sigma_px, seeded by the frame's seed).
std::string PasspointListCsv(const BlockSpec& spec, const BlockFrame& frame, const SimulatedPlate& plate);
// The batch manifest (docs/batch.md): one row per frame with the camera,
// orientation, emulsion and passpoint columns; list files by absolute path
// (a manifest's passpoints.list_file is taken as given, docs/job.md).
std::string BlockManifestCsv(const BlockSpec& spec, const BlockLayout& layout, const std::vector<std::string>& scans,
                             const std::vector<std::string>& list_paths);
// The bundle job (docs/bundle-job.md), paths relative to the job's folder.
std::string BlockBundleJobToml(const BlockSpec& spec, const BlockLayout& layout, const std::string& ground_points_file);
// The block truth (JSON): camera, frames, points, image positions, the files.
std::string BlockTruthJson(const BlockSpec& spec, const BlockLayout& layout, const BlockOutputs& outputs,
                           const BlockRenderOptions& options);

}  // namespace platemeter::sim
