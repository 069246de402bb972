// Several cameras exposed together, adjusted jointly (stellar_interlock.h):
// every plate prepared as a single plate is, the other cameras' plates
// aligned to the reference plate of their exposure, one engine problem.
#include "platemeter/calib/stellar_interlock.h"

#include <cmath>
#include <set>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter {
namespace {

using stellar_internal::PlateBlocks;
using stellar_internal::PreparedPlate;

void CheckInput(const std::vector<std::string>& names, const std::vector<StellarCamera>& initial,
                const std::vector<InterlockExposure>& exposures, const StellarOptions& options) {
  const std::string subject = "interlock";
  if (names.size() < 2) throw Error(subject, "needs at least two cameras");
  if (initial.size() != names.size()) throw Error(subject, "needs one starting camera per camera name");
  for (const StellarCamera& camera : initial) stellar_internal::CheckCamera(camera, options, subject);
  if (exposures.empty()) throw Error(subject, "has no exposures");
  std::set<std::string> plate_ids;
  std::vector<int> seen(names.size(), 0);
  for (const InterlockExposure& exposure : exposures) {
    const std::string where = fmt::format("exposure {}", exposure.id);
    if (exposure.plates.size() != names.size())
      throw Error(where, fmt::format("has {} plate slots for {} cameras", exposure.plates.size(), names.size()));
    if (exposure.plates[0].images.empty())
      throw Error(where, fmt::format("has no plate of the reference camera {}", names[0]));
    for (size_t k = 0; k < names.size(); ++k) {
      const StellarPlate& plate = exposure.plates[k];
      if (plate.images.empty()) continue;
      ++seen[k];
      if (!plate_ids.insert(plate.id).second)
        throw Error(where, fmt::format("plate id {} is used twice", plate.id));
    }
  }
  for (size_t k = 1; k < names.size(); ++k) {
    if (seen[k] == 0) throw Error(subject, fmt::format("camera {} has no plate in any exposure", names[k]));
  }
}

// camera k's result: values and scaled sigmas (canonical decentering), counts, residual RMS.
InterlockCameraResult CameraResult(const std::string& name, const std::string& label,
                                   const std::vector<std::pair<const StellarPlate*, const PreparedPlate*>>& plates,
                                   DistortionModelId lens, const AdjustmentResult& adjustment) {
  InterlockCameraResult out;
  out.name = name;
  std::vector<int> indices;
  for (const std::string& parameter : StellarCameraParamNames(lens)) {
    const int k = adjustment.Find(label, parameter);
    if (k < 0) throw Error("interlock", fmt::format("internal: no parameter '{} {}'", label, parameter));
    indices.push_back(k);
    out.camera.push_back(adjustment.parameters[k].value);
  }
  Eigen::MatrixXd covariance = adjustment.Covariance(indices);
  CanonicalDecentering(&out.camera, &covariance, lens);
  for (size_t i = 0; i < indices.size(); ++i)
    out.camera_sigma.push_back(std::sqrt(std::max(0.0, covariance(i, i))));
  std::set<std::string> groups;
  for (const auto& [plate, prepared] : plates) {
    ++out.plates;
    out.stars += static_cast<int>(prepared->stars.size());
    out.images += static_cast<int>(prepared->images.size());
    groups.insert(fmt::format("plate {}", plate->id));
  }
  double sum2_mm2 = 0.0;
  long used = 0;
  for (const ObservationResidual& r : adjustment.residuals) {
    if (!groups.count(r.group)) continue;
    if (r.status != ObservationStatus::kUsed) {
      ++out.rejected_images;
      continue;
    }
    sum2_mm2 += r.residual[0] * r.residual[0] + r.residual[1] * r.residual[1];
    ++used;
  }
  out.rms_residual_um = used > 0 ? 1000.0 * std::sqrt(sum2_mm2 / (2.0 * used)) : 0.0;
  return out;
}

CameraInterlockResult InterlockResult(const std::string& from, const std::string& to, const std::string& label,
                                      const AdjustmentResult& adjustment) {
  CameraInterlockResult out;
  out.from = from;
  out.to = to;
  const int omega = adjustment.Find(label, "omega_rad");
  if (omega < 0) throw Error("interlock", fmt::format("internal: no block '{}'", label));
  const OmegaPhiKappa angles{adjustment.parameters[omega].value, adjustment.parameters[omega + 1].value,
                             adjustment.parameters[omega + 2].value};
  out.matrix = MatrixFromOmegaPhiKappa(angles);
  const Eigen::Matrix3d covariance = adjustment.Covariance({omega, omega + 1, omega + 2});
  out.angles = InterlockAnglesFromRotationCovariance(out.matrix, covariance, InterlockCovarianceKind::kAngles);
  out.element_covariance = MatrixCovarianceFromAngleCovariance(out.angles.angles, out.angles.covariance_rad2);
  return out;
}

}  // namespace

StellarInterlockResult RunStellarInterlock(const std::vector<std::string>& names,
                                           const std::vector<StellarCamera>& initial,
                                           const std::vector<InterlockExposure>& exposures,
                                           const StellarCatalog& catalog, const StellarOptions& options,
                                           const AdjustmentProgress& progress) {
  std::string why;
  if (!options.Check(&why)) throw Error("stellar options", why);
  CheckInput(names, initial, exposures, options);
  const size_t cameras = names.size();

  // Prepared plates by exposure and camera; each interlock starts from the
  // first exposure that shows its camera (the plates' own starting rotations).
  std::vector<std::vector<std::optional<PreparedPlate>>> prepared(exposures.size());
  std::vector<std::optional<OmegaPhiKappa>> start(cameras);
  for (size_t e = 0; e < exposures.size(); ++e) {
    prepared[e].resize(cameras);
    for (size_t k = 0; k < cameras; ++k) {
      const StellarPlate& plate = exposures[e].plates[k];
      if (plate.images.empty()) continue;
      prepared[e][k] = stellar_internal::PreparePlate(plate, catalog, initial[k], options, std::nullopt);
      if (k == 0) continue;
      if (!start[k]) {
        start[k] = OmegaPhiKappaFromMatrix(prepared[e][k]->set_m0[0] * prepared[e][0]->set_m0[0].transpose());
      }
      stellar_internal::AlignToReference(*prepared[e][0], &*prepared[e][k]);
    }
  }

  AdjustmentProblem problem;
  std::vector<int> camera_blocks, interlock_blocks(cameras, -1);
  for (size_t k = 0; k < cameras; ++k) {
    camera_blocks.push_back(stellar_internal::AddCameraBlock("camera " + names[k], initial[k], options, &problem));
    if (k == 0) continue;
    interlock_blocks[k] = problem.AddBlock(fmt::format("interlock {} to {}", names[0], names[k]), "interlock",
                                           BlockKind::kGlobal, {"omega_rad", "phi_rad", "kappa_rad"},
                                           {start[k]->omega_rad, start[k]->phi_rad, start[k]->kappa_rad});
  }
  std::vector<std::vector<std::pair<const StellarPlate*, const PreparedPlate*>>> plates_of(cameras);
  for (size_t e = 0; e < exposures.size(); ++e) {
    const PlateBlocks reference = stellar_internal::AddPlateToProblem(exposures[e].plates[0], *prepared[e][0], options,
                                                                      camera_blocks[0], &problem);
    plates_of[0].emplace_back(&exposures[e].plates[0], &*prepared[e][0]);
    for (size_t k = 1; k < cameras; ++k) {
      if (!prepared[e][k]) continue;
      stellar_internal::AddInterlockedPlateToProblem(exposures[e].plates[k], *prepared[e][k], options,
                                                     camera_blocks[k], reference, interlock_blocks[k], &problem);
      plates_of[k].emplace_back(&exposures[e].plates[k], &*prepared[e][k]);
    }
  }

  StellarInterlockResult out;
  out.exposures = static_cast<int>(exposures.size());
  out.adjustment = problem.Solve(options.adjustment, progress);
  for (size_t k = 0; k < cameras; ++k) {
    out.cameras.push_back(
        CameraResult(names[k], "camera " + names[k], plates_of[k], options.lens_model, out.adjustment));
    if (k > 0) {
      out.interlocks.push_back(
          InterlockResult(names[0], names[k], fmt::format("interlock {} to {}", names[0], names[k]), out.adjustment));
    }
  }
  return out;
}

}  // namespace platemeter
