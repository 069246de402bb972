// EvaluatePrecision (precision_simulation.h): the plan's adjustment on a
// noise-free block, and the a-priori sigmas it implies.
#include "platemeter/calib/precision_simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/core/error.h"
#include "platemeter/core/angles.h"

namespace platemeter {
namespace {

constexpr const char* kPrecisionSimulationSubject = "precision simulation";

[[noreturn]] void Throw(const std::string& why) { throw Error(kPrecisionSimulationSubject, why); }

void CheckBlock(const PrecisionPlan& plan, const PrecisionBlock& block) {
  const BundleInput& in = block.input;
  if (in.cameras.size() != 1) Throw("the block must have exactly one camera");
  const size_t frames = in.frames.size();
  if (frames < 2) Throw("the block has fewer than two frames");
  if (block.frame_orbit.size() != frames || block.frame_velocity.size() != frames) {
    Throw("the block's frame_orbit and frame_velocity must have one entry per frame");
  }
  for (int o : block.frame_orbit) {
    if (o < 0 || o >= plan.orbits) Throw(fmt::format("a frame's orbit index {} is outside 0..{}", o, plan.orbits - 1));
  }
  for (const FrameSetup& f : in.frames) {
    if (!f.position_m || !f.angles) Throw("frame " + f.id + " has no position or attitude (the block gives the truth)");
  }
  if (in.observations.empty()) Throw("the block has no observations");
}

// The frames' a-priori station observations from the plan.
void AddStationConstraints(const PrecisionPlan& plan, const PrecisionBlock& block, BundleInput* input) {
  std::vector<int> constrained_by(input->frames.size(), -1);
  for (size_t k = 0; k < plan.station_constraints.size(); ++k) {
    const StationConstraint& c = plan.station_constraints[k];
    for (size_t f = 0; f < input->frames.size(); ++f) {
      const int orbit = block.frame_orbit[f] + 1;
      if (!c.orbits.empty() && std::find(c.orbits.begin(), c.orbits.end(), orbit) == c.orbits.end()) continue;
      if (constrained_by[f] >= 0) {
        Throw(fmt::format("orbit {} is constrained by two [[station_constraints]] tables ({} and {})", orbit,
                          constrained_by[f] + 1, k + 1));
      }
      constrained_by[f] = static_cast<int>(k);
      FrameSetup& frame = input->frames[f];
      frame.position_covariance_m2 = StationCovarianceFromTrack(*frame.position_m, block.frame_velocity[f],
                                                                c.sigma_in_track_m, c.sigma_cross_track_m,
                                                                c.sigma_radial_m);
      if (c.sigma_angle_deg) frame.angle_sigma_rad = Eigen::Vector3d::Constant(*c.sigma_angle_deg * kRadPerDeg);
    }
  }
}

std::string FreeList(const PrecisionPlan& plan) {
  std::vector<std::string> names;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (plan.free[i]) names.emplace_back(kBundleCameraParamNames[i]);
  }
  return fmt::format("{}", fmt::join(names, ", "));
}

}  // namespace

PrecisionSimulationResult EvaluatePrecision(const PrecisionPlan& plan, const PrecisionBlock& block) {
  std::string why;
  if (!plan.Check(&why)) Throw(why);
  CheckBlock(plan, block);
  const auto start = std::chrono::steady_clock::now();

  BundleInput input = block.input;
  CameraSetup& camera = input.cameras[0];
  for (int i = 0; i < kBundleCameraParams; ++i) {
    camera.states[i] = plan.free[i] ? ParameterState::Free() : ParameterState::Fixed();
  }
  for (FrameSetup& f : input.frames) {
    f.fixed = false;
    f.position_covariance_m2.reset();
    f.angle_sigma_rad.reset();
  }
  for (GroundPoint& g : input.ground_points) g.sigma_m = {};  // free tie points
  input.distances.clear();
  AddStationConstraints(plan, block, &input);

  PrecisionDatum datum = plan.datum;
  if (datum == PrecisionDatum::kAuto) {
    datum = plan.station_constraints.empty() ? PrecisionDatum::kInnerConstraints : PrecisionDatum::kStations;
  }
  BundleOptions options;
  // The a-priori station observations define the datum by themselves: no
  // gauge is imposed (the engine's "control" datum applies no S-transformation;
  // with no control points it is exactly "the priors alone").
  options.datum = datum == PrecisionDatum::kStations ? DatumKind::kControlPoints : DatumKind::kInnerConstraints;
  options.adjustment.correlation_threshold = plan.correlation_threshold;
  const BundleResult bundle = RunBundleAdjustment(input, options);
  const AdjustmentResult& a = bundle.adjustment;
  if (bundle.cameras.size() != 1) Throw("the adjustment returned no camera");
  const BundleCameraResult& cam = bundle.cameras[0];

  PrecisionSimulationResult result;
  result.plan = plan;
  result.geometry = block.summary;
  result.frames = static_cast<int>(input.frames.size());
  result.points = static_cast<int>(input.ground_points.size());
  result.observations = static_cast<int>(input.observations.size());
  result.frame_roll_deg = block.frame_roll_deg;
  if (datum == PrecisionDatum::kStations) {
    int constrained = 0;
    for (const FrameSetup& f : input.frames) constrained += f.position_covariance_m2 ? 1 : 0;
    result.datum_words = fmt::format("a-priori station positions (Gyer's in-track / cross-track / radial sigmas) on "
                                     "{} of {} frames",
                                     constrained, input.frames.size());
  } else {
    result.datum_words = bundle.datum_words;
  }

  const std::array<double, kBundleCameraParams>& truth_values = block.input.cameras[0].values;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    const ParameterEstimate& p = a.parameters[cam.parameter_index[i]];
    PrecisionParameter out;
    out.name = kBundleCameraParamNames[i];
    out.value = truth_values[i];  // the true value (the solution stays there)
    out.status = p.status;
    out.sigma = p.sigma_unscaled;
    result.camera.push_back(out);
  }
  auto um = [&](int i) -> std::optional<double> {
    if (!result.camera[i].sigma) return std::nullopt;
    return *result.camera[i].sigma * 1e3;
  };
  result.c_um = um(0);
  result.xp_um = um(1);
  result.yp_um = um(2);

  // The lens as an estimate: c and brown-affine's seven, unscaled covariance.
  std::vector<int> lens_indices = {cam.parameter_index[0]};
  for (int i = 3; i < kBundleCameraParams; ++i) lens_indices.push_back(cam.parameter_index[i]);
  // Values: the truth (the adjustment stays there up to rounding, and a
  // decentering of 1e-19 instead of 0 would pick an arbitrary direction for P).
  LensEstimate lens;
  lens.model = DistortionModelId::kBrownAffine;
  lens.principal_distance_mm = truth_values[0];
  for (int i = 3; i < kBundleCameraParams; ++i) lens.params.push_back(truth_values[i]);
  lens.covariance = a.Covariance(lens_indices, /*scaled=*/false);
  lens.covariance = 0.5 * (lens.covariance + lens.covariance.transpose());

  result.corner_radius_mm = plan.CornerRadius_mm();
  DistortionProfileOptions profile_options;
  profile_options.balance = plan.balance;
  profile_options.balance_radius_mm = plan.balance_radius_mm;
  profile_options.max_radius_mm = result.corner_radius_mm;
  profile_options.radii_mm = plan.radii_mm.empty()
                                 ? DefaultProfileRadii_mm(plan.format_width_mm, plan.format_height_mm)
                                 : plan.radii_mm;
  std::vector<double>& radii = profile_options.radii_mm;
  radii.erase(std::remove_if(radii.begin(), radii.end(),
                             [&](double r) { return std::abs(r - result.corner_radius_mm) < 1e-9; }),
              radii.end());
  radii.push_back(result.corner_radius_mm);  // the corner, exactly, last
  result.profile = ComputeDistortionProfile(lens, profile_options);
  result.calibrated_focal_length_mm = result.profile.calibrated_focal_length_mm;
  result.radial_corner_sigma_um = result.profile.rows.back().radial_sigma_um;
  result.decentering_corner_sigma_um = result.profile.rows.back().decentering_sigma_um;

  result.dof = a.dof;
  result.observation_rows = a.observation_rows;
  result.prior_rows = a.prior_rows;
  result.unknowns = a.unknowns;
  result.rank = a.rank;
  std::vector<int> free_indices;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (result.camera[i].sigma) {
      free_indices.push_back(cam.parameter_index[i]);
      result.correlation_names.push_back(kBundleCameraParamNames[i]);
    }
  }
  if (!free_indices.empty()) {
    const Eigen::MatrixXd q = a.Covariance(free_indices, /*scaled=*/false);
    const Eigen::VectorXd s = q.diagonal().cwiseMax(0.0).cwiseSqrt();
    result.correlation = Eigen::MatrixXd::Zero(q.rows(), q.cols());
    for (int i = 0; i < q.rows(); ++i) {
      for (int j = 0; j < q.cols(); ++j) {
        result.correlation(i, j) = s[i] > 0.0 && s[j] > 0.0 ? q(i, j) / (s[i] * s[j]) : 0.0;
      }
    }
    for (int i = 0; i < q.rows(); ++i) {
      for (int j = i + 1; j < q.cols(); ++j) {
        if (std::abs(result.correlation(i, j)) >= plan.correlation_threshold) {
          result.high_correlations.emplace_back(result.correlation_names[i], result.correlation_names[j],
                                                result.correlation(i, j));
        }
      }
    }
    std::sort(result.high_correlations.begin(), result.high_correlations.end(),
              [](const auto& x, const auto& y) { return std::abs(std::get<2>(x)) > std::abs(std::get<2>(y)); });
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<std::string> not_estimable;
  for (const PrecisionParameter& p : result.camera) {
    if (p.status == EstimateStatus::kNotEstimable) not_estimable.push_back(p.name);
  }
  auto show = [](const std::optional<double>& v) { return v ? fmt::format("{:.3g}", *v) : std::string("-"); };
  result.summary = fmt::format(
      "{} frames, {} passpoints, {} image points of {:g} um; free {}; datum: {}. A-priori sigmas (sigma0 = 1): "
      "xp {} um, yp {} um, c {} um, c' {:.3g} um, delta_r' {:.3g} um and P {:.3g} um at the corner (r = {:.1f} mm); "
      "{:g} degrees of freedom, rank {} of {}{}.",
      result.frames, result.points, result.observations, plan.image_sigma_um, FreeList(plan), result.datum_words,
      show(result.xp_um), show(result.yp_um), show(result.c_um), result.calibrated_focal_length_mm.sigma * 1e3,
      result.radial_corner_sigma_um, result.decentering_corner_sigma_um, result.corner_radius_mm, result.dof,
      result.rank.numerical_rank, result.rank.num_parameters,
      not_estimable.empty() ? std::string()
                            : fmt::format("; NOT ESTIMABLE: {} (see the rank report)", fmt::join(not_estimable, ", ")));
  return result;
}

}  // namespace platemeter
