#pragma once
// The plate simulator end to end: a spec (spec.h) and the camera definitions
// give the true geometry chain (geometry.h), a Scene for the renderer
// (scene.h, render.h) and the truth list; WriteSimulatedPlate renders the scan
// band by band and writes <name>.tif, <name>.truth.csv (measurement-file
// format, status truth, with the Cramer-Rao bounds) and <name>.chain.json.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/image_writer.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/geometry.h"
#include "platemeter/samples/scene.h"
#include "platemeter/samples/spec.h"

namespace platemeter::sim {

struct SimulateOptions {
  bool full_size = false;              // render at the spec's output.full_size_pixel_size_um
  std::optional<uint64_t> seed;        // replaces the spec's seed
  bool Check(std::string* why) const { return true; }
};

// Everything about a simulated plate except its pixels.
struct SimulatedPlate {
  std::string name;
  std::string spec_origin;
  std::string camera;
  uint64_t seed = 0;
  bool full_size = false;
  double pixel_size_um = 0.0;
  GeometryChain chain;
  Scene scene;
  ImageWriterOptions image;  // size, sample type, tiling, compression, pixel size
  // One truth point per reseau cross (missing ones flagged "absent"),
  // fiducial, passpoint and star, with true pixel position and true plate
  // position (master-grid / camera mm before the chain); CRB columns empty
  // until ComputeCramerRaoBounds.
  std::vector<MeasuredPoint> truth;
  std::vector<int> truth_mark;  // index into scene.marks of each truth point, -1 if not rendered
  // Defects for the chain file: the false marks' ids and scene indices etc.
  std::vector<int> false_marks, dust, scratches;
  // [star_field] summary for the chain file (JSON object text; empty without a star field).
  std::string star_field_json;
};

// Builds the plate; throws Error(spec file, reason) for an unknown camera or
// values that do not fit (unknown cross ids, DN beyond full scale, ...).
SimulatedPlate BuildSimulatedPlate(const SimulationSpec& spec, const DefinitionRegistry& registry,
                                   const SimulateOptions& options = {});

// Fills the CRB columns of plate.truth (renderer's CramerRaoBound per mark).
void ComputeCramerRaoBounds(SimulatedPlate* plate);

// The chain file's JSON text (docs/simulator.md).
std::string ChainFileJson(const SimulatedPlate& plate);

struct SimulateOutputs {
  std::string image_path;
  std::string truth_path;
  std::string chain_path;
};

// rows_done of rows_total rendered (called after each band).
using RenderProgress = std::function<void(long rows_done, long rows_total)>;

// Renders and writes the three files into out_dir (created if missing). Each
// file appears under its final name only when complete; the truth and chain
// files are written after the scan, so a failed render leaves nothing.
SimulateOutputs WriteSimulatedPlate(SimulatedPlate plate, const std::string& out_dir,
                                    const RenderProgress& progress = {});

}  // namespace platemeter::sim
