// A plate's normal equations reduced to the camera, and the plate's own
// Gauss-Newton step (stellar_internal.h): the building blocks of the
// weighted mean (stellar_combination.h), which lets each plate's orientation
// sets, deformation and stars "assume new values without solving for them
// explicitly" (seed 001).
#include <map>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <fmt/format.h>

#include "stellar_internal.h"

namespace platemeter::stellar_internal {
namespace {

// The image equation's whitened Jacobian blocks and residual at the state.
struct Linearized {
  Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> camera;
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> set;
  Eigen::Matrix<double, 2, 2, Eigen::RowMajor> deformation, star;
  Eigen::Vector2d residual;
};

bool LinearizeImage(const StellarPlate& plate, const PreparedImage& image, const PlateState& state,
                    const StellarCamera& camera, DistortionModelId lens, Linearized* out) {
  const StarImageObservation& source = plate.images[image.source];
  const std::unique_ptr<ceres::CostFunction> cost(CreateStellarImageCost(lens, image.equation));
  out->camera.resize(2, static_cast<Eigen::Index>(camera.size()));
  const double* parameters[4] = {camera.data(), state.sets[image.set].data(), state.deformation.data(),
                                 state.stars[image.star].data()};
  double* jacobians[4] = {out->camera.data(), out->set.data(), out->deformation.data(), out->star.data()};
  if (!cost->Evaluate(parameters, out->residual.data(), jacobians)) return false;
  const Eigen::Vector2d w(1.0 / source.sigma_x_mm, 1.0 / source.sigma_y_mm);
  out->camera = w.asDiagonal() * out->camera;
  out->set = w.asDiagonal() * out->set;
  out->deformation = w.asDiagonal() * out->deformation;
  out->star = w.asDiagonal() * out->star;
  out->residual = w.asDiagonal() * out->residual;
  return true;
}

}  // namespace

bool CameraParameterFixed(const StellarOptions& options, int i) {
  auto it = options.camera_states.find(StellarCameraParamNames(options.lens_model)[i]);
  return it != options.camera_states.end() && it->second.kind == ParameterState::Kind::kFixed;
}

PlateState InitialPlateState(const PreparedPlate& prepared, const StellarPlateResult& single) {
  PlateState state;
  const Eigen::Matrix3d m0 = prepared.set_m0.front();
  state.sets.assign(prepared.set_m0.size(), Eigen::Vector3d::Zero());
  for (const OrientationSetResult& set : single.orientation_sets) {
    const OmegaPhiKappa a = OmegaPhiKappaFromMatrix(set.camera_from_enu * m0.transpose());
    state.sets[set.index - 1] = Eigen::Vector3d(a.omega_rad, a.phi_rad, a.kappa_rad);
  }
  const double s = (single.cx_mm - single.cy_mm) / (single.cx_mm + single.cy_mm);
  state.deformation = Eigen::Vector2d(s, single.epsilon_rad);
  std::map<std::string, Eigen::Vector2d> star_values;
  for (const auto& point : single.adjustment.points) star_values[point.label] = point.value.head<2>();
  for (const PreparedStar& star : prepared.stars) {
    // An unknown star's correction is relative to a place taken through the
    // starting camera, which differs here: it starts at zero.
    auto it = star_values.find(fmt::format("plate {} star {}", single.plate_id, star.id));
    state.stars.push_back(it == star_values.end() || !star.known ? Eigen::Vector2d::Zero() : it->second);
  }
  for (size_t k = 0; k < prepared.images.size(); ++k) {
    state.used.push_back(k < single.adjustment.residuals.size() &&
                         single.adjustment.residuals[k].status == ObservationStatus::kUsed);
  }
  return state;
}

PlateLinearization LinearizePlate(const StellarPlate& plate, const PreparedPlate& prepared, const PlateState& state,
                                  const StellarCamera& camera, const StellarOptions& options) {
  const int num_sets = static_cast<int>(prepared.set_m0.size());
  const int k = static_cast<int>(camera.size());
  const int m = k + 3 * num_sets + 2;  // camera | sets | deformation
  const int deformation_offset = k + 3 * num_sets;
  const int num_stars = static_cast<int>(prepared.stars.size());
  PlateLinearization out;
  out.n_gg = Eigen::MatrixXd::Zero(m, m);
  out.b_g = Eigen::VectorXd::Zero(m);
  std::vector<Eigen::Matrix2d> n_ss(num_stars, Eigen::Matrix2d::Zero());
  out.n_sg.assign(num_stars, Eigen::MatrixXd::Zero(2, m));
  out.b_s.assign(num_stars, Eigen::Vector2d::Zero());
  std::vector<int> images_in_set(num_sets, 0);

  for (int s = 0; s < num_stars; ++s) {  // the catalog priors
    if (!prepared.stars[s].known) continue;
    const double w = 1.0 / (prepared.stars[s].sigma_rad * prepared.stars[s].sigma_rad);
    n_ss[s] += w * Eigen::Matrix2d::Identity();
    out.b_s[s] += w * state.stars[s];
    out.vtpv += w * state.stars[s].squaredNorm();
  }
  Linearized x;
  Eigen::MatrixXd j_g = Eigen::MatrixXd::Zero(2, m);
  for (size_t i = 0; i < prepared.images.size(); ++i) {
    const PreparedImage& image = prepared.images[i];
    if (!state.used[i] || !LinearizeImage(plate, image, state, camera, options.lens_model, &x)) continue;
    ++images_in_set[image.set];
    j_g.setZero();
    j_g.leftCols(k) = x.camera;
    j_g.middleCols(k + 3 * image.set, 3) = x.set;
    j_g.middleCols(deformation_offset, 2) = x.deformation;
    out.n_gg.noalias() += j_g.transpose() * j_g;
    out.b_g.noalias() += j_g.transpose() * x.residual;
    n_ss[image.star] += x.star.transpose() * x.star;
    out.n_sg[image.star].noalias() += x.star.transpose() * j_g;
    out.b_s[image.star] += x.star.transpose() * x.residual;
    out.vtpv += x.residual.squaredNorm();
  }
  out.n_ss_inverse.resize(num_stars);
  for (int s = 0; s < num_stars; ++s) {  // each star on its own (a 2 x 2 block)
    out.n_ss_inverse[s] = n_ss[s].inverse();
    out.n_gg.noalias() -= out.n_sg[s].transpose() * out.n_ss_inverse[s] * out.n_sg[s];
    out.b_g.noalias() -= out.n_sg[s].transpose() * (out.n_ss_inverse[s] * out.b_s[s]);
  }
  // Fixed parameters drop out: zero rows and columns, a unit diagonal for the plate's own.
  for (int i = 0; i < m; ++i) {
    const bool fixed = i < k ? CameraParameterFixed(options, i)
                       : i >= deformation_offset ? !options.deformation
                                                 : images_in_set[(i - k) / 3] == 0;
    if (!fixed) continue;
    out.n_gg.row(i).setZero();
    out.n_gg.col(i).setZero();
    out.b_g[i] = 0.0;
    if (i >= k) out.n_gg(i, i) = 1.0;
  }
  const int p = m - k;
  const Eigen::LDLT<Eigen::MatrixXd> n_pp(out.n_gg.bottomRightCorner(p, p));
  const Eigen::MatrixXd n_cp = out.n_gg.topRightCorner(k, p);
  out.n = out.n_gg.topLeftCorner(k, k) - n_cp * n_pp.solve(n_cp.transpose());
  out.b = out.b_g.head(k) - n_cp * n_pp.solve(out.b_g.tail(p));
  return out;
}

void StepPlate(const PlateLinearization& lin, const Eigen::VectorXd& camera_step, PlateState* state) {
  const int k = static_cast<int>(camera_step.size()), p = static_cast<int>(lin.n_gg.rows()) - k;
  const Eigen::VectorXd step_p = -Eigen::LDLT<Eigen::MatrixXd>(lin.n_gg.bottomRightCorner(p, p))
                                      .solve(lin.b_g.tail(p) + lin.n_gg.bottomLeftCorner(p, k) * camera_step);
  Eigen::VectorXd step_g(k + p);
  step_g << camera_step, step_p;
  for (size_t j = 0; j < state->sets.size(); ++j) state->sets[j] += step_p.segment<3>(3 * j);
  state->deformation += step_p.tail<2>();
  for (size_t s = 0; s < state->stars.size(); ++s)
    state->stars[s] -= lin.n_ss_inverse[s] * (lin.b_s[s] + lin.n_sg[s] * step_g);
}

}  // namespace platemeter::stellar_internal
