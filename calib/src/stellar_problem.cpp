// A plate's blocks and equations in an engine problem (stellar_internal.h):
// shared by the single-plate adjustment and the simultaneous solution.
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter::stellar_internal {

int AddCameraBlock(const std::string& label, const StellarCamera& values, const StellarOptions& options,
                   AdjustmentProblem* problem) {
  const std::vector<std::string> names(kStellarCameraParamNames.begin(), kStellarCameraParamNames.end());
  const int block = problem->AddBlock(label, "camera", BlockKind::kGlobal, names,
                                      std::vector<double>(values.begin(), values.end()));
  for (int i = 0; i < kStellarCameraParams; ++i) {
    auto it = options.camera_states.find(kStellarCameraParamNames[i]);
    problem->SetState(block, i, it == options.camera_states.end() ? ParameterState::Free() : it->second);
  }
  return block;
}

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
  blocks.deformation = problem->AddBlock(fmt::format("plate {} deformation", plate.id), "deformation",
                                         BlockKind::kStation, {"s", "epsilon_rad"}, {0.0, 0.0});
  if (!options.deformation) {
    problem->SetState(blocks.deformation, 0, ParameterState::Fixed());
    problem->SetState(blocks.deformation, 1, ParameterState::Fixed());
  }
  for (const PreparedStar& star : prepared.stars) {
    const int block = problem->AddBlock(fmt::format("plate {} star {}", plate.id, star.id), "star",
                                        BlockKind::kPoint, {"east_rad", "north_rad"}, {0.0, 0.0});
    blocks.stars.push_back(block);
    if (star.known) {
      problem->AddPrior(block, {0, 1}, Eigen::Vector2d::Zero(),
                        Eigen::Matrix2d::Identity() * star.sigma_rad * star.sigma_rad,
                        fmt::format("plate {} catalog place of {}", plate.id, star.id));
    }
  }
  blocks.first_observation = -1;
  for (const PreparedImage& image : prepared.images) {
    const StarImageObservation& source = plate.images[image.source];
    const Eigen::Matrix2d covariance =
        Eigen::Vector2d(source.sigma_x_mm * source.sigma_x_mm, source.sigma_y_mm * source.sigma_y_mm).asDiagonal();
    const int index = problem->AddObservation(
        StellarImageEquation::Create(image.equation),
        {camera, blocks.sets[image.set], blocks.deformation, blocks.stars[image.star]}, covariance,
        fmt::format("plate {}", plate.id), fmt::format("{} ({})", source.image_id, source.star_id), source.origin);
    if (blocks.first_observation < 0) blocks.first_observation = index;
  }
  return blocks;
}

}  // namespace platemeter::stellar_internal
