#pragma once
// The block spec: one TOML file (with a [block] table) describing a RENDERED
// photogrammetric block for the self-calibrating bundle adjustment
// (docs/block-simulator.md). It names
//   - a frame spec: a plate spec (spec.h, docs/simulator.md) saying how every
//     frame looks -- camera definition (format, fiducials), film, scanner,
//     marks, background, noise, pixel size. Its passpoint table gives the
//     marks' look; the points themselves come from the block;
//   - the true camera (seed 000 eq. 1, BundleCameraTruth), the geometry
//     (seed 000 section 4's lunar orbits, bundle_block.h LunarBlockOptions),
//     the control points, the operator's point transfer, the approximations the
//     bundle job starts from, and the job's free parameters.
// Every key, its unit and its default: docs/block-simulator.md. Unknown keys
// are errors; every problem is an Error "<file>: line N: <table>: <problem>".
// The rendering: block_render.h.
#include <cstdint>
#include <string>
#include <vector>

#include "platemeter/samples/bundle_block.h"
#include "platemeter/samples/spec.h"

namespace platemeter::sim {

// Per-frame differences of the chain (each frame lies on the film and the
// scanner in its own way): Gaussian, added to the frame spec's values. Both
// are affine, so the fiducial interior orientation of measure removes them.
struct BlockFrameVariation {
  double scanner_rotation_sigma_deg = 0.0;  // deg; added to scanner.rotation_deg
  double film_affine_sigma_ppm = 0.0;       // ppm; added to each of film.affine_ppm's four terms
};

// Control points: the first `count` points of the layout (the generator
// places them edges first, so they span the area).
struct BlockControl {
  int count = 4;         // points with a-priori coordinates (XYZ); the others are free tie points
  double sigma_m = 0.0;  // m; 0 = fixed at the truth; > 0 = weighted, the CSV holds the truth perturbed by it
};

// The operator's point transfer: the approximate passpoint lists (docs/passpoints.md).
struct BlockTransfer {
  double sigma_px = 3.0;  // px; Gaussian error of each listed position, per axis, about the true mark
};

// What the written bundle job frees and where it finds the measurement files.
struct BlockBundle {
  // Free camera parameters, short names (c, xp, yp, k1, k2, k3, p1, p2, b1, b2);
  // the others are held at the camera definition's values.
  std::vector<std::string> free = {"c", "xp", "yp", "k1", "k2", "p1", "p2"};
  // Folder (relative to the output folder) that `platemeter batch MANIFEST -o`
  // fills: the job's frames are <measured_dir>/<frame>/<frame>.measurements.csv.
  std::string measured_dir = "measured";
  std::string title;     // the report's title ("" = a sentence from the block)
  std::string datum = "auto";  // the job's adjustment.datum
};

struct BlockSpec {
  std::string origin;           // the block file (for messages)
  std::string name;             // base name of the block's files (letters, digits, '.', '_', '-')
  std::string description;      // one line
  std::string frame_spec_path;  // the frame spec, as resolved (relative to the block file's folder)
  SimulationSpec frame_spec;    // read from frame_spec_path (ReadBlockSpec)
  std::uint64_t seed = 1;       // every random choice of the block and its frames derives from it
  // Geometry and true camera. camera's format is the frame spec camera
  // definition's (filled by LayOutBlock); sigma_um is 0 (the images are rendered).
  LunarBlockOptions geometry;
  double min_separation_mm = 1.5;  // mm; two passpoints closer than this in any frame: the later is left out
  BlockFrameVariation frames;
  BlockControl control;
  BlockTransfer transfer;
  BlockBundle bundle;
};

// Parses block spec text; `origin` names the file in errors and is the base of
// the relative frame_spec path. Does not read the frame spec.
BlockSpec ParseBlockSpec(const std::string& text, const std::string& origin);
// Reads a block spec file and its frame spec (errors in the frame spec name that file).
BlockSpec ReadBlockSpec(const std::string& path);
// True when the TOML file has a top-level [block] table (a block spec), false
// for a plate spec; an unreadable file or a TOML syntax error is an Error naming it.
bool IsBlockSpecFile(const std::string& path);

// The bundle parameter name of a short name ("k1" -> "k1_per_mm2"); "" if unknown.
std::string BundleParameterName(const std::string& short_name);

}  // namespace platemeter::sim
