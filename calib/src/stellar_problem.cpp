// A plate's blocks and equations in an engine problem (stellar_internal.h):
// shared by the single-plate adjustment and the simultaneous solution.
#include <cmath>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter::stellar_internal {

void CheckCamera(const StellarCamera& camera, const StellarOptions& options, const std::string& subject) {
  const int expected = StellarCameraParamCount(options.lens_model);
  if (static_cast<int>(camera.size()) != expected)
    throw Error(subject, fmt::format("a {} camera has {} values (got {})", DistortionModelName(options.lens_model),
                                     expected, camera.size()));
  for (double v : camera) {
    if (!std::isfinite(v)) throw Error(subject, "the starting camera has a non-finite value");
  }
  if (!(camera[0] > 0.0)) throw Error(subject, "the initial principal distance must be positive");
}

int AddCameraBlock(const std::string& label, const StellarCamera& values, const StellarOptions& options,
                   AdjustmentProblem* problem) {
  const std::vector<std::string> names = StellarCameraParamNames(options.lens_model);
  const int block = problem->AddBlock(label, "camera", BlockKind::kGlobal, names, values);
  for (size_t i = 0; i < names.size(); ++i) {
    auto it = options.camera_states.find(names[i]);
    problem->SetState(block, static_cast<int>(i), it == options.camera_states.end() ? ParameterState::Free() : it->second);
  }
  return block;
}

namespace {

// The plate's own blocks: deformation and stars (the catalog's a-priori places).
void AddDeformationAndStars(const StellarPlate& plate, const PreparedPlate& prepared, const StellarOptions& options,
                            AdjustmentProblem* problem, PlateBlocks* blocks) {
  blocks->deformation = problem->AddBlock(fmt::format("plate {} deformation", plate.id), "deformation",
                                          BlockKind::kStation, {"s", "epsilon_rad"}, {0.0, 0.0});
  if (!options.deformation) {
    problem->SetState(blocks->deformation, 0, ParameterState::Fixed());
    problem->SetState(blocks->deformation, 1, ParameterState::Fixed());
  }
  for (const PreparedStar& star : prepared.stars) {
    const int block = problem->AddBlock(fmt::format("plate {} star {}", plate.id, star.id), "star",
                                        BlockKind::kPoint, {"east_rad", "north_rad"}, {0.0, 0.0});
    blocks->stars.push_back(block);
    if (star.known) {
      problem->AddPrior(block, {0, 1}, Eigen::Vector2d::Zero(),
                        Eigen::Matrix2d::Identity() * star.sigma_rad * star.sigma_rad,
                        fmt::format("plate {} catalog place of {}", plate.id, star.id));
    }
  }
}

// Each image as an observation with its own sigmas; `cost` makes its equation.
template <typename MakeCost>
void AddImages(const StellarPlate& plate, const PreparedPlate& prepared, const MakeCost& cost,
               AdjustmentProblem* problem, PlateBlocks* blocks) {
  blocks->first_observation = -1;
  for (const PreparedImage& image : prepared.images) {
    const StarImageObservation& source = plate.images[image.source];
    const Eigen::Matrix2d covariance =
        Eigen::Vector2d(source.sigma_x_mm * source.sigma_x_mm, source.sigma_y_mm * source.sigma_y_mm).asDiagonal();
    const auto [equation, equation_blocks] = cost(image);
    const int index = problem->AddObservation(equation, equation_blocks, covariance, fmt::format("plate {}", plate.id),
                                              fmt::format("{} ({})", source.image_id, source.star_id), source.origin);
    if (blocks->first_observation < 0) blocks->first_observation = index;
  }
}

}  // namespace

PlateBlocks AddPlateToProblem(const StellarPlate& plate, const PreparedPlate& prepared, const StellarOptions& options,
                              int camera, AdjustmentProblem* problem) {
  PlateBlocks blocks;
  std::vector<int> images_in_set(prepared.set_m0.size(), 0);
  for (const PreparedImage& image : prepared.images) ++images_in_set[image.set];
  for (size_t j = 0; j < prepared.set_m0.size(); ++j) {
    blocks.sets.push_back(images_in_set[j] == 0
                              ? -1
                              : problem->AddBlock(fmt::format("plate {} set {}", plate.id, j + 1), "orientation",
                                                  BlockKind::kStation, {"omega_rad", "phi_rad", "kappa_rad"},
                                                  {0.0, 0.0, 0.0}));
  }
  AddDeformationAndStars(plate, prepared, options, problem, &blocks);
  AddImages(
      plate, prepared,
      [&](const PreparedImage& image) {
        return std::make_pair(CreateStellarImageCost(options.lens_model, image.equation),
                              std::vector<int>{camera, blocks.sets[image.set], blocks.deformation,
                                               blocks.stars[image.star]});
      },
      problem, &blocks);
  return blocks;
}

PlateBlocks AddInterlockedPlateToProblem(const StellarPlate& plate, const PreparedPlate& prepared,
                                         const StellarOptions& options, int camera, const PlateBlocks& reference,
                                         int interlock, AdjustmentProblem* problem) {
  PlateBlocks blocks;
  blocks.sets = reference.sets;
  for (const PreparedImage& image : prepared.images) {
    if (reference.sets[image.set] < 0)
      throw Error(fmt::format("plate {}", plate.id),
                  fmt::format("has images in orientation set {} of its exposure, in which the reference plate has none",
                              image.set + 1));
  }
  AddDeformationAndStars(plate, prepared, options, problem, &blocks);
  AddImages(
      plate, prepared,
      [&](const PreparedImage& image) {
        return std::make_pair(CreateInterlockedImageCost(options.lens_model, image.equation),
                              std::vector<int>{camera, reference.sets[image.set], interlock, blocks.deformation,
                                               blocks.stars[image.star]});
      },
      problem, &blocks);
  return blocks;
}

}  // namespace platemeter::stellar_internal
