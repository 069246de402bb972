// The block laid out without pixels: the lunar orbits of seed 000 section 4
// through the true camera (bundle_block.h), points too close together in some
// frame left out, control chosen, approximations and per-frame chain
// variations drawn (docs/block-simulator.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "platemeter/core/error.h"
#include "platemeter/samples/block_render.h"

namespace platemeter::sim {
namespace {

// splitmix64 of a seed and a stream tag: independent random streams.
std::uint64_t BlockSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
constexpr std::uint64_t kControlStream = 7001;
constexpr std::uint64_t kFrameStream = 8000;  // + frame index

const CameraDefinition& FrameCamera(const BlockSpec& spec, const DefinitionRegistry& registry) {
  const CameraDefinition* definition = registry.FindCamera(spec.frame_spec.camera);
  if (!definition) {
    std::string known;
    for (const std::string& name : registry.CameraNames()) known += (known.empty() ? "" : ", ") + name;
    throw Error(spec.frame_spec.origin, "unknown camera '" + spec.frame_spec.camera + "' (known: " + known + ")");
  }
  if (!definition->format_corners_as_fiducials && definition->fiducial_set.empty() && definition->grid.empty()) {
    throw Error(spec.origin, "the frame spec's camera '" + definition->name +
                                 "' has no fiducials and no reseau: measure could not map a frame into the camera frame");
  }
  return *definition;
}

// Points whose image lies within `separation_mm` of an earlier kept point's in
// some frame are left out (two marks that close make the point transfer ambiguous).
std::vector<bool> KeepSeparated(const SimulatedBlock& block, double separation_mm) {
  std::map<std::string, int> point_index, frame_index;
  for (std::size_t i = 0; i < block.truth.points.size(); ++i) point_index[block.truth.points[i].id] = static_cast<int>(i);
  for (std::size_t i = 0; i < block.truth.stations.size(); ++i) frame_index[block.truth.stations[i].id] = static_cast<int>(i);
  // Per point: (frame, image) pairs.
  std::vector<std::vector<std::pair<int, Eigen::Vector2d>>> images(block.truth.points.size());
  for (const ImageObservation& o : block.truth.observations) {
    images[point_index.at(o.point_id)].emplace_back(frame_index.at(o.frame), Eigen::Vector2d(o.x_mm, o.y_mm));
  }
  std::vector<std::vector<Eigen::Vector2d>> kept_in_frame(block.truth.stations.size());
  std::vector<bool> keep(block.truth.points.size(), false);
  for (std::size_t p = 0; p < images.size(); ++p) {
    bool clear = true;
    for (const auto& [frame, xy] : images[p]) {
      for (const Eigen::Vector2d& other : kept_in_frame[frame]) {
        if ((other - xy).norm() < separation_mm) clear = false;
      }
    }
    if (!clear) continue;
    keep[p] = true;
    for (const auto& [frame, xy] : images[p]) kept_in_frame[frame].push_back(xy);
  }
  return keep;
}

void AddGroundPoints(const BlockSpec& spec, const SimulatedBlock& block, BlockLayout* layout) {
  std::map<std::string, const GroundPoint*> approximation;
  for (const GroundPoint& g : block.input.ground_points) approximation[g.id] = &g;
  std::mt19937_64 random(BlockSeed(spec.seed, kControlStream));
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t i = 0; i < layout->points.size(); ++i) {
    const PointTruth& p = layout->points[i];
    GroundPoint g;
    g.id = p.id;
    if (layout->control[i]) {
      g.position_m = p.position_m;
      for (int k = 0; k < 3; ++k) {
        g.position_m[k] += spec.control.sigma_m * normal(random);
        g.sigma_m[k] = spec.control.sigma_m;
      }
    } else {
      g.position_m = approximation.at(p.id)->position_m;  // truth + approximations.point_sigma_m noise
    }
    layout->ground_points.push_back(std::move(g));
  }
}

void DrawFrameVariations(const BlockSpec& spec, BlockLayout* layout) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t f = 0; f < layout->frames.size(); ++f) {
    BlockFrame& frame = layout->frames[f];
    frame.seed = BlockSeed(spec.seed, kFrameStream + f);
    frame.transfer_seed = BlockSeed(frame.seed, 2);
    std::mt19937_64 random(BlockSeed(frame.seed, 1));
    frame.scanner_rotation_deg =
        spec.frame_spec.scanner.rotation_deg + spec.frames.scanner_rotation_sigma_deg * normal(random);
    frame.scanner_rotation_deg = std::clamp(frame.scanner_rotation_deg, -45.0, 45.0);
    for (int k = 0; k < 4; ++k) {
      frame.film_affine_ppm[k] = spec.frame_spec.film.affine_ppm[k] + spec.frames.film_affine_sigma_ppm * normal(random);
    }
  }
}

}  // namespace

BlockLayout LayOutBlock(const BlockSpec& spec, const DefinitionRegistry& registry) {
  const CameraDefinition& definition = FrameCamera(spec, registry);
  LunarBlockOptions options = spec.geometry;
  options.camera.format_width_mm = definition.format_width_mm;
  options.camera.format_height_mm = definition.format_height_mm;
  options.seed = spec.seed;
  std::string why;
  if (!options.Check(&why)) throw Error(spec.origin, why);
  SimulatedBlock block;
  try {
    block = SimulateLunarBlock(options);
  } catch (const Error& e) {
    throw Error(spec.origin, e.reason());
  }

  BlockLayout layout;
  layout.camera = options.camera;
  layout.camera_definition = definition.name;
  const std::vector<bool> keep = KeepSeparated(block, spec.min_separation_mm);
  std::map<std::string, int> kept_index;
  for (std::size_t p = 0; p < block.truth.points.size(); ++p) {
    if (!keep[p]) {
      layout.dropped.push_back(block.truth.points[p].id);
      continue;
    }
    kept_index[block.truth.points[p].id] = static_cast<int>(layout.points.size());
    layout.points.push_back(block.truth.points[p]);
  }
  if (static_cast<int>(layout.points.size()) < std::max(spec.control.count, 1)) {
    throw Error(spec.origin, "points: only " + std::to_string(layout.points.size()) + " of " +
                                 std::to_string(block.truth.points.size()) + " points are " +
                                 std::to_string(spec.min_separation_mm) +
                                 " mm apart in every frame; control.count is " + std::to_string(spec.control.count));
  }
  layout.control.assign(layout.points.size(), false);
  for (int i = 0; i < spec.control.count; ++i) layout.control[i] = true;

  std::map<std::string, int> frame_index;
  for (const StationTruth& s : block.truth.stations) {
    frame_index[s.id] = static_cast<int>(layout.frames.size());
    BlockFrame frame;
    frame.station = s;
    layout.frames.push_back(std::move(frame));
  }
  for (const ImageObservation& o : block.truth.observations) {  // frame-major, points ascending
    const auto kept = kept_index.find(o.point_id);
    if (kept == kept_index.end()) continue;
    BlockFrame& frame = layout.frames[frame_index.at(o.frame)];
    frame.points.push_back(kept->second);
    frame.plate_mm.emplace_back(o.x_mm, o.y_mm);
  }
  for (const BlockFrame& frame : layout.frames) {
    if (frame.points.size() < 3) {
      throw Error(spec.origin, "frame " + frame.station.id + " sees " + std::to_string(frame.points.size()) +
                                   " points: a frame needs at least 3 (more points, or a lower points.min_frames)");
    }
  }
  AddGroundPoints(spec, block, &layout);
  for (FrameSetup frame : block.input.frames) {
    frame.camera = definition.name;
    layout.approximations.push_back(std::move(frame));
  }
  DrawFrameVariations(spec, &layout);

  char line[512];
  std::snprintf(line, sizeof line,
                "rendered block '%s': %zu frames on %zu orbits at %.1f km, convergence %.1f deg, kappa %+.0f deg per "
                "exposure%s; true camera c = %.3f mm on %.1f x %.1f mm (%s); %zu points (%zu left out as too close), "
                "%d control",
                spec.name.c_str(), layout.frames.size(), options.revolutions.size(), options.altitude_m * 1e-3,
                options.convergence_deg, options.kappa_increment_deg,
                options.rolls_continue_across_orbits ? " continuing across orbits" : "", layout.camera.c_mm,
                layout.camera.format_width_mm, layout.camera.format_height_mm, definition.name.c_str(),
                layout.points.size(), layout.dropped.size(), spec.control.count);
  layout.summary = line;
  return layout;
}

}  // namespace platemeter::sim
