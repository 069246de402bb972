// One plate's stellar calibration (stellar_plate.h): prepare, adjust, and read
// the engine's result into seed 001 Table 2's quantities.
#include "platemeter/calib/stellar_plate.h"

#include <cmath>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "platemeter/core/error.h"
#include "stellar_internal.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {

using stellar_internal::PlateBlocks;
using stellar_internal::PreparedPlate;


int Index(const AdjustmentResult& result, const std::string& block, const std::string& name) {
  const int i = result.Find(block, name);
  if (i < 0) throw Error("stellar calibration", fmt::format("internal: no parameter '{} {}'", block, name));
  return i;
}

double SigmaOf(const AdjustmentResult& result, int i) { return result.parameters[i].sigma.value_or(0.0); }

// The inverse of the cofactor block over the estimable parameters; zero rows elsewhere.
Eigen::MatrixXd InformationOf(const AdjustmentResult& result, const std::vector<int>& indices) {
  const Eigen::MatrixXd q = result.Covariance(indices, false);
  std::vector<int> estimable;
  for (int k = 0; k < static_cast<int>(indices.size()); ++k) {
    if (result.covariance_row[indices[k]] >= 0) estimable.push_back(k);
  }
  return stellar_internal::InverseOverRows(q, estimable);
}

OrientationSetResult OrientationOf(const AdjustmentResult& result, const std::string& label, int index,
                                   const Eigen::Matrix3d& m0) {
  OrientationSetResult set;
  set.index = index;
  const int omega = Index(result, label, "omega_rad");
  const OmegaPhiKappa angles{result.parameters[omega].value, result.parameters[omega + 1].value,
                             result.parameters[omega + 2].value};
  set.camera_from_enu = MatrixFromOmegaPhiKappa(angles) * m0;
  const Eigen::Vector3d axis = set.camera_from_enu.row(2).transpose();
  const Eigen::Vector3d plate_x = set.camera_from_enu.row(0).transpose();
  set.axis_azimuth_deg = std::atan2(axis.x(), axis.y()) * kDegPerRad;
  if (set.axis_azimuth_deg < 0) set.axis_azimuth_deg += 360.0;
  set.axis_altitude_deg = std::asin(std::clamp(axis.z(), -1.0, 1.0)) * kDegPerRad;
  set.roll_deg = std::atan2(plate_x.y(), plate_x.x()) * kDegPerRad;
  for (int k = 0; k < 3; ++k) set.sigma_arcsec[k] = SigmaOf(result, omega + k) * kArcsecPerRad;
  return set;
}

void FillDeformation(const AdjustmentResult& result, const std::string& plate_id, int c_index,
                     StellarPlateResult* out) {
  const std::string label = fmt::format("plate {} deformation", plate_id);
  const int s = Index(result, label, "s");
  const int e = Index(result, label, "epsilon_rad");
  const double c = result.parameters[c_index].value;
  const double scale = result.parameters[s].value;
  out->cx_mm = c * (1.0 + scale);
  out->cy_mm = c * (1.0 - scale);
  out->epsilon_rad = result.parameters[e].value;
  out->epsilon_sigma_rad = SigmaOf(result, e);
  const Eigen::Matrix2d cov = result.Covariance({c_index, s});
  const Eigen::RowVector2d jx(1.0 + scale, c), jy(1.0 - scale, -c);
  out->cx_sigma_mm = std::sqrt(std::max(0.0, (jx * cov * jx.transpose())(0, 0)));
  out->cy_sigma_mm = std::sqrt(std::max(0.0, (jy * cov * jy.transpose())(0, 0)));
}

StellarPlateResult ReadResult(const StellarPlate& plate, const PreparedPlate& prepared, const PlateBlocks& blocks,
                              const std::string& camera_label, DistortionModelId lens, AdjustmentResult adjustment) {
  StellarPlateResult out;
  out.plate_id = plate.id;
  out.group = plate.group;
  std::vector<int> camera_indices;
  for (const std::string& name : StellarCameraParamNames(lens)) {
    const int k = Index(adjustment, camera_label, name);
    camera_indices.push_back(k);
    out.camera.push_back(adjustment.parameters[k].value);
    out.camera_sigma.push_back(SigmaOf(adjustment, k));
    out.camera_row.push_back(adjustment.covariance_row[k]);
  }
  out.camera_information = InformationOf(adjustment, camera_indices);
  CanonicalDecentering(&out.camera, &out.camera_information, lens);
  FillDeformation(adjustment, plate.id, camera_indices[0], &out);
  for (size_t j = 0; j < blocks.sets.size(); ++j) {
    if (blocks.sets[j] < 0) continue;
    OrientationSetResult set =
        OrientationOf(adjustment, fmt::format("plate {} set {}", plate.id, j + 1), static_cast<int>(j) + 1,
                      prepared.set_m0[j]);
    set.start_s = prepared.set_span_s[j].first;
    set.end_s = prepared.set_span_s[j].second;
    for (const auto& image : prepared.images) set.images += image.set == static_cast<int>(j) ? 1 : 0;
    out.orientation_sets.push_back(set);
  }
  for (const auto& a : out.orientation_sets) {
    for (const auto& b : out.orientation_sets) {
      const double angle = Eigen::AngleAxisd(a.camera_from_enu * b.camera_from_enu.transpose()).angle();
      out.largest_motion_arcsec = std::max(out.largest_motion_arcsec, angle * kArcsecPerRad);
    }
  }
  for (const auto& star : prepared.stars) (star.known ? out.catalog_stars : out.unknown_stars) += 1;
  out.images = static_cast<int>(prepared.images.size());
  out.rejected_images = adjustment.rejected;
  out.m_o = adjustment.sigma0;
  out.unit_sigma_um = prepared.unit_sigma_um;
  out.m_p_um = adjustment.sigma0 * prepared.unit_sigma_um;
  out.adjustment = std::move(adjustment);
  return out;
}

}  // namespace

bool StellarOptions::Check(std::string* why) const {
  if (orientation_sets < 1 || orientation_sets > 3) {
    *why = fmt::format("orientation_sets must be 1, 2 or 3 (got {})", orientation_sets);
    return false;
  }
  if (!IsStellarLensModel(lens_model)) {
    *why = fmt::format("lens_model must be one of {} (got {})", StellarLensModelNames(), DistortionModelName(lens_model));
    return false;
  }
  const std::vector<std::string> names = StellarCameraParamNames(lens_model);
  for (const auto& [name, state] : camera_states) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      *why = fmt::format("unknown {} camera parameter '{}' (expected one of {})", DistortionModelName(lens_model), name,
                         fmt::join(names, ", "));
      return false;
    }
  }
  return adjustment.Check(why);
}

StellarPlateResult RunStellarPlate(const StellarPlate& plate, const StellarCatalog& catalog,
                                   const StellarCamera& initial, const StellarOptions& options,
                                   const std::optional<Eigen::Matrix3d>& approx_camera_from_enu,
                                   const AdjustmentProgress& progress) {
  std::string why;
  if (!options.Check(&why)) throw Error("stellar options", why);
  stellar_internal::CheckCamera(initial, options, "stellar calibration");
  const PreparedPlate prepared = stellar_internal::PreparePlate(plate, catalog, initial, options, approx_camera_from_enu);
  AdjustmentProblem problem;
  const std::string camera_label = "camera";
  const int camera = stellar_internal::AddCameraBlock(camera_label, initial, options, &problem);
  const PlateBlocks blocks = stellar_internal::AddPlateToProblem(plate, prepared, options, camera, &problem);
  return ReadResult(plate, prepared, blocks, camera_label, options.lens_model,
                    problem.Solve(options.adjustment, progress));
}

}  // namespace platemeter
