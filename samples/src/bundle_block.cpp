// Simulated blocks for the bundle adjustment: shared steps (attitudes,
// projection, observations with noise, approximations) and the lunar orbits of
// seed 000. The planar target and the aerial block: bundle_block_scenes.cpp.
#include "platemeter/samples/bundle_block.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/core/error.h"
#include "platemeter/core/why.h"

namespace platemeter::sim {

namespace bundle_internal {

std::uint64_t DeriveSeed(std::uint64_t seed, Stream stream) {
  // splitmix64 of the seed and the stream's tag: independent streams, so that
  // e.g. changing the noise leaves the points where they were.
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(stream) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

[[noreturn]] void Throw(const std::string& why) { throw Error("bundle simulator", why); }

double WrapDeg(double deg) {
  double a = std::fmod(deg, 360.0);
  if (a <= -180.0) a += 360.0;
  if (a > 180.0) a -= 360.0;
  return a;
}

Eigen::Matrix3d AttitudeFromAxis(const Eigen::Vector3d& axis, const Eigen::Vector3d& reference, double roll_deg) {
  const Eigen::Vector3d w = axis.normalized();
  Eigen::Vector3d u = reference - reference.dot(w) * w;
  if (!(u.norm() > 1e-9 * reference.norm())) Throw("the reference direction is parallel to an optical axis");
  u.normalize();
  const Eigen::Vector3d v = w.cross(u);
  Eigen::Matrix3d t0;
  t0.row(0) = u.transpose();
  t0.row(1) = v.transpose();
  t0.row(2) = w.transpose();
  const double ck = std::cos(Rad(roll_deg)), sk = std::sin(Rad(roll_deg));
  Eigen::Matrix3d r3;
  r3 << ck, sk, 0.0, -sk, ck, 0.0, 0.0, 0.0, 1.0;  // rotations.h R3(kappa)
  return r3 * t0;
}

bool InsideFormat(const BundleCameraTruth& camera, const Eigen::Vector2d& p, double margin_mm) {
  return std::abs(p.x()) <= 0.5 * camera.format_width_mm - margin_mm &&
         std::abs(p.y()) <= 0.5 * camera.format_height_mm - margin_mm;
}

bool SeenInFormat(const BundleCameraTruth& camera, const StationTruth& station, const Eigen::Vector3d& point_m,
                  double margin_mm) {
  Eigen::Vector2d p;
  return ProjectPoint(camera, station.image_from_object, station.position_m, point_m, &p) &&
         InsideFormat(camera, p, margin_mm);
}

bool CheckSigmas(double sigma_um, double weight_sigma_um, std::string* why) {
  if (!std::isfinite(sigma_um) || sigma_um < 0.0) return Fail(why, "sigma_um must be >= 0");
  if (!std::isfinite(weight_sigma_um) || weight_sigma_um < 0.0) return Fail(why, "weight_sigma_um must be >= 0");
  if (sigma_um == 0.0 && weight_sigma_um == 0.0) {
    return Fail(why, "with sigma_um = 0 (no noise) weight_sigma_um must give the observations' sigma");
  }
  return true;
}

SimulatedBlock Assemble(const AssembleInput& in) {
  SimulatedBlock block;
  BundleTruth& truth = block.truth;
  truth.camera = in.camera;
  truth.stations = in.stations;
  truth.points = in.points;
  truth.sigma_mm = in.sigma_um * 1e-3;
  const double weight_mm = (in.weight_sigma_um > 0.0 ? in.weight_sigma_um : in.sigma_um) * 1e-3;

  // Frame-major order: every frame's points in point order.
  std::vector<std::vector<int>> points_of_frame(in.stations.size());
  for (std::size_t p = 0; p < in.frames_of_point.size(); ++p) {
    for (int f : in.frames_of_point[p]) points_of_frame[f].push_back(static_cast<int>(p));
  }
  std::mt19937_64 noise_random(DeriveSeed(in.seed, Stream::kNoise));
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t f = 0; f < in.stations.size(); ++f) {
    std::sort(points_of_frame[f].begin(), points_of_frame[f].end());
    const StationTruth& station = in.stations[f];
    for (int p : points_of_frame[f]) {
      Eigen::Vector2d xy;
      if (!ProjectPoint(in.camera, station.image_from_object, station.position_m, in.points[p].position_m, &xy)) {
        Throw("point " + in.points[p].id + " does not project into frame " + station.id);
      }
      ImageObservation o;
      o.frame = station.id;
      o.point_id = in.points[p].id;
      o.x_mm = xy.x();
      o.y_mm = xy.y();
      o.sigma_x_mm = weight_mm;
      o.sigma_y_mm = weight_mm;
      truth.observations.push_back(o);
      o.x_mm += truth.sigma_mm * normal(noise_random);
      o.y_mm += truth.sigma_mm * normal(noise_random);
      block.input.observations.push_back(std::move(o));
    }
  }

  // Approximations: truth, or truth perturbed.
  const ApproximationOptions& a = in.approximations;
  std::mt19937_64 approx_random(DeriveSeed(in.seed, Stream::kApproximations));
  CameraSetup camera;
  camera.name = in.camera_name;
  camera.values = in.camera.Values();
  camera.values[0] += a.principal_distance_sigma_mm * normal(approx_random);
  camera.values[1] += a.principal_point_sigma_mm * normal(approx_random);
  camera.values[2] += a.principal_point_sigma_mm * normal(approx_random);
  if (a.zero_distortion) {
    for (int i = 3; i < kBundleCameraParams; ++i) camera.values[i] = 0.0;
  }
  camera.format_width_mm = in.camera.format_width_mm;
  camera.format_height_mm = in.camera.format_height_mm;
  block.input.cameras.push_back(camera);

  const double angle_sigma_rad = Rad(a.angle_sigma_deg);
  for (const StationTruth& s : in.stations) {
    FrameSetup frame;
    frame.id = s.id;
    frame.camera = in.camera_name;
    Eigen::Vector3d position = s.position_m;
    for (int i = 0; i < 3; ++i) position[i] += a.station_sigma_m * normal(approx_random);
    PhiOmegaKappaT angles = s.angles;
    angles.phi_rad += angle_sigma_rad * normal(approx_random);
    angles.omega_rad += angle_sigma_rad * normal(approx_random);
    angles.kappa_rad += angle_sigma_rad * normal(approx_random);
    frame.position_m = position;
    frame.angles = angles;
    block.input.frames.push_back(std::move(frame));
  }
  for (const PointTruth& p : in.points) {
    GroundPoint g;
    g.id = p.id;
    g.position_m = p.position_m;
    for (int i = 0; i < 3; ++i) g.position_m[i] += a.point_sigma_m * normal(approx_random);
    block.input.ground_points.push_back(std::move(g));  // sigmas nullopt: free tie points
  }
  return block;
}

}  // namespace bundle_internal

using namespace bundle_internal;

// ---------------------------------------------------------------------------
// Camera, approximations, helpers.

std::array<double, kBundleCameraParams> BundleCameraTruth::Values() const {
  return {c_mm, xp_mm, yp_mm, k1_per_mm2, k2_per_mm4, k3_per_mm6, p1_per_mm, p2_per_mm, b1, b2};
}

bool BundleCameraTruth::Check(std::string* why) const {
  for (double v : Values()) {
    if (!std::isfinite(v)) return Fail(why, "camera values must be finite");
  }
  if (!(c_mm > 0.0)) return Fail(why, "camera c_mm must be positive");
  if (!(format_width_mm > 0.0) || !(format_height_mm > 0.0)) {
    return Fail(why, "camera format_width_mm and format_height_mm must be positive");
  }
  return true;
}

bool ApproximationOptions::Check(std::string* why) const {
  for (double v : {station_sigma_m, angle_sigma_deg, point_sigma_m, principal_distance_sigma_mm,
                   principal_point_sigma_mm}) {
    if (!std::isfinite(v) || v < 0.0) return Fail(why, "approximation sigmas must be >= 0");
  }
  return true;
}

bool ProjectPoint(const BundleCameraTruth& camera, const Eigen::Matrix3d& image_from_object,
                  const Eigen::Vector3d& station_m, const Eigen::Vector3d& point_m, Eigen::Vector2d* plate_mm) {
  const std::array<double, kBundleCameraParams> values = camera.Values();
  double rotation[9];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation[3 * r + c] = image_from_object(r, c);
  }
  const Eigen::Vector3d direction = point_m - station_m;
  double x = 0.0, y = 0.0;
  if (!ProjectDirectionT<BrownAffine>(values.data(), values.data() + 3, rotation, direction.data(), &x, &y)) {
    return false;
  }
  *plate_mm = Eigen::Vector2d(x, y);
  return true;
}

double ConvergenceAngleDeg(const StationTruth& a, const StationTruth& b) {
  const double cosine = std::clamp(a.OpticalAxis().normalized().dot(b.OpticalAxis().normalized()), -1.0, 1.0);
  return Deg(std::acos(cosine));
}

double RollAboutAxisDeg(const Eigen::Matrix3d& image_from_object, const Eigen::Vector3d& reference) {
  // T = R3(roll) T0 puts the reference at (cos roll, -sin roll) |ref_perp| in the image.
  const double along_x = image_from_object.row(0).dot(reference);
  const double along_y = image_from_object.row(1).dot(reference);
  return WrapDeg(Deg(std::atan2(-along_y, along_x)));
}

// ---------------------------------------------------------------------------
// Lunar orbits (seed 000 sections 3 and 4).

bool LunarBlockOptions::Check(std::string* why) const {
  if (!camera.Check(why)) return false;
  if (!approximations.Check(why)) return false;
  if (!(moon_radius_m > 0.0) || !(altitude_m > 0.0)) return Fail(why, "moon_radius_m and altitude_m must be positive");
  if (revolutions.empty()) return Fail(why, "revolutions must name at least one orbit");
  if (!std::isfinite(track_spacing_m) || track_spacing_m < 0.0) return Fail(why, "track_spacing_m must be >= 0");
  if (exposures_per_orbit < 2) return Fail(why, "exposures_per_orbit must be at least 2");
  if (!(convergence_deg > 0.0) || !(convergence_deg < 170.0)) return Fail(why, "convergence_deg must be in (0, 170)");
  if (!std::isfinite(kappa_start_deg) || !std::isfinite(kappa_increment_deg)) return Fail(why, "kappa angles must be finite");
  const int frames = static_cast<int>(revolutions.size()) * exposures_per_orbit;
  if (passpoints < 1) return Fail(why, "passpoints must be at least 1");
  if (min_frames_per_point < 0 || min_frames_per_point > frames) {
    return Fail(why, "min_frames_per_point must be in 0.." + std::to_string(frames) + " (0 = all frames)");
  }
  if (!std::isfinite(relief_m) || relief_m < 0.0 || relief_m >= altitude_m) {
    return Fail(why, "relief_m must be >= 0 and below the altitude");
  }
  if (!std::isfinite(format_margin_mm) || format_margin_mm < 0.0 ||
      2.0 * format_margin_mm >= std::min(camera.format_width_mm, camera.format_height_mm)) {
    return Fail(why, "format_margin_mm must be >= 0 and smaller than half the format");
  }
  if (!CheckSigmas(sigma_um, weight_sigma_um, why)) return false;
  if (!frame_ids.empty() && static_cast<int>(frame_ids.size()) != frames) {
    return Fail(why, "frame_ids must be empty or name all " + std::to_string(frames) + " frames");
  }
  return true;
}

LunarBlockOptions Seed000Table9Options(double focal_length_mm) {
  LunarBlockOptions o;
  o.camera.c_mm = focal_length_mm;
  o.camera.format_width_mm = 55.0;
  o.camera.format_height_mm = 55.0;
  o.sigma_um = 15.0;
  o.passpoints = 215;
  o.rolls_continue_across_orbits = true;
  return o;
}

LunarBlockOptions Seed000Table10Options() {
  LunarBlockOptions o;
  o.camera.c_mm = 76.2;  // 3 inch
  o.camera.format_width_mm = 114.3;  // 4.5 inch
  o.camera.format_height_mm = 114.3;
  o.sigma_um = 5.0;
  o.passpoints = 215;
  o.rolls_continue_across_orbits = true;
  return o;
}

LunarBlockOptions Apollo14Section3Options() {
  LunarBlockOptions o;
  // Table 1 (pure self-calibration) in Gaussian form: c = c' / (1 + k0'),
  // k1 = k1' / (1 + k0') with c' = 502.630 mm, k0' = -0.14065e-1,
  // k1' = 0.15614e-4 / mm^2; p1, p2 as printed; xp, yp were held at zero.
  const double k0 = -0.14065e-1;
  o.camera.c_mm = 502.630 / (1.0 + k0);
  o.camera.xp_mm = 0.0;
  o.camera.yp_mm = 0.0;
  o.camera.k1_per_mm2 = 0.15614e-4 / (1.0 + k0);
  o.camera.k2_per_mm4 = 0.0;
  o.camera.k3_per_mm6 = 0.0;
  o.camera.p1_per_mm = 0.3604e-5;
  o.camera.p2_per_mm = 0.2998e-5;
  o.camera.format_width_mm = 55.0;
  o.camera.format_height_mm = 55.0;
  o.revolutions = {27, 28, 30};
  o.kappa_increment_deg = 0.0;
  o.sigma_um = 15.0;
  o.passpoints = 170;  // "approximately 170 passpoints"
  o.frame_ids = {"R27-9515", "R27-9525", "R27-9535", "R28-9556", "R28-9565",
                 "R28-9574", "R30-9595", "R30-9601", "R30-9615"};
  return o;
}

namespace {

// Ground point at gnomonic tangent coordinates (e along X, n along Y, metres on
// the tangent plane at G = (0, 0, R)) and a height above the sphere.
Eigen::Vector3d SurfacePoint(double radius_m, double e_m, double n_m, double height_m) {
  return Eigen::Vector3d(e_m, n_m, radius_m).normalized() * (radius_m + height_m);
}

// Tangent coordinates of the sphere hit of a frame's corner ray (distortion
// ignored: only bounds the search), false if the ray misses the sphere.
bool CornerOnGround(const StationTruth& s, const BundleCameraTruth& camera, double sx, double sy, double radius_m,
                    double* e_m, double* n_m) {
  const Eigen::Vector3d ray =
      (s.image_from_object.transpose() *
       Eigen::Vector3d(sx * 0.5 * camera.format_width_mm - camera.xp_mm,
                       sy * 0.5 * camera.format_height_mm - camera.yp_mm, camera.c_mm))
          .normalized();
  const double b = s.position_m.dot(ray);
  const double disc = b * b - (s.position_m.squaredNorm() - radius_m * radius_m);
  if (disc < 0.0) return false;
  const double t = -b - std::sqrt(disc);
  if (!(t > 0.0)) return false;
  const Eigen::Vector3d hit = s.position_m + t * ray;
  if (!(hit.z() > 0.1 * radius_m)) return false;
  *e_m = radius_m * hit.x() / hit.z();
  *n_m = radius_m * hit.y() / hit.z();
  return true;
}

int FramesSeeing(const BundleCameraTruth& camera, const std::vector<StationTruth>& stations,
                 const Eigen::Vector3d& point, double margin_mm, std::vector<int>* frames) {
  int count = 0;
  for (std::size_t f = 0; f < stations.size(); ++f) {
    if (SeenInFormat(camera, stations[f], point, margin_mm)) {
      ++count;
      if (frames) frames->push_back(static_cast<int>(f));
    }
  }
  return count;
}

// Orbit angle of the end frames that gives `convergence_rad` between their axes.
double EndFrameAngle(double radius_m, double orbit_radius_m, double beta_rad, double convergence_rad) {
  const Eigen::Vector3d target(0.0, 0.0, radius_m);
  auto station = [&](double theta) {
    return Eigen::Vector3d(std::sin(theta), std::cos(theta) * std::sin(beta_rad), std::cos(theta) * std::cos(beta_rad)) *
           orbit_radius_m;
  };
  auto angle = [&](double theta) {
    const Eigen::Vector3d a = (target - station(-theta)).normalized();
    const Eigen::Vector3d b = (target - station(theta)).normalized();
    return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
  };
  // The target stays above the station's horizon while cos(theta) cos(beta) > R / rho.
  const double limit = radius_m / (orbit_radius_m * std::cos(beta_rad));
  if (!(limit < 1.0)) Throw("the common ground area is below the horizon of an orbit (track spacing too large)");
  double lo = 0.0, hi = 0.999 * std::acos(limit);
  if (angle(hi) < convergence_rad) Throw("the convergence angle cannot be reached from this altitude");
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (angle(mid) < convergence_rad ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

SimulatedBlock SimulateLunarBlock(const LunarBlockOptions& options) {
  std::string why;
  if (!options.Check(&why)) Throw(why);
  const BundleCameraTruth& camera = options.camera;
  const double radius = options.moon_radius_m;
  const double orbit_radius = radius + options.altitude_m;
  const Eigen::Vector3d target(0.0, 0.0, radius);

  // Stations: one great circle per revolution, offset across the track.
  double mean_revolution = 0.0;
  for (int r : options.revolutions) mean_revolution += r;
  mean_revolution /= static_cast<double>(options.revolutions.size());
  std::vector<StationTruth> stations;
  const int n = options.exposures_per_orbit;
  for (std::size_t k = 0; k < options.revolutions.size(); ++k) {
    const int revolution = options.revolutions[k];
    const double beta = (revolution - mean_revolution) * options.track_spacing_m / radius;
    const double theta_end = EndFrameAngle(radius, orbit_radius, beta, Rad(options.convergence_deg));
    for (int j = 0; j < n; ++j) {
      const double theta = -theta_end + 2.0 * theta_end * j / (n - 1);
      StationTruth s;
      s.position_m = orbit_radius * Eigen::Vector3d(std::sin(theta), std::cos(theta) * std::sin(beta),
                                                    std::cos(theta) * std::cos(beta));
      s.velocity_direction = Eigen::Vector3d(std::cos(theta), -std::sin(theta) * std::sin(beta),
                                             -std::sin(theta) * std::cos(beta));
      const int exposure = options.rolls_continue_across_orbits ? static_cast<int>(k) * n + j : j;
      s.roll_deg = WrapDeg(options.kappa_start_deg + exposure * options.kappa_increment_deg);
      s.image_from_object = AttitudeFromAxis(target - s.position_m, s.velocity_direction, s.roll_deg);
      s.angles = AnglesFromTMatrix(s.image_from_object);
      s.group = static_cast<int>(k);
      s.index_in_group = j;
      const int index = static_cast<int>(stations.size());
      if (!options.frame_ids.empty()) {
        s.id = options.frame_ids[index];
      } else {
        s.id = "R" + std::to_string(revolution) + "-E" + std::to_string(j + 1);
      }
      stations.push_back(std::move(s));
    }
  }
  const int need = options.min_frames_per_point > 0 ? options.min_frames_per_point : static_cast<int>(stations.size());
  const double margin = options.format_margin_mm;

  // Search box: the frames' footprints (corner rays on the sphere).
  double e_lo = 0.0, e_hi = 0.0, n_lo = 0.0, n_hi = 0.0;
  for (const StationTruth& s : stations) {
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        double e = 0.0, nn = 0.0;
        if (!CornerOnGround(s, camera, sx, sy, radius, &e, &nn)) {
          e = nn = 0.5 * radius;  // beyond the horizon: the cap below bounds it
          e *= sx;
          nn *= sy;
        }
        e_lo = std::min(e_lo, e), e_hi = std::max(e_hi, e);
        n_lo = std::min(n_lo, nn), n_hi = std::max(n_hi, nn);
      }
    }
  }
  const double cap = 0.5 * radius;
  e_lo = std::max(e_lo, -cap), e_hi = std::min(e_hi, cap);
  n_lo = std::max(n_lo, -cap), n_hi = std::min(n_hi, cap);

  // Coarse pass (datum heights): where on the ground enough frames see.
  const int coarse = 200;
  const double ce = (e_hi - e_lo) / coarse, cn = (n_hi - n_lo) / coarse;
  double fe_lo = std::numeric_limits<double>::max(), fe_hi = -fe_lo, fn_lo = fe_lo, fn_hi = -fe_lo;
  for (int i = 0; i <= coarse; ++i) {
    for (int j = 0; j <= coarse; ++j) {
      const double e = e_lo + i * ce, nn = n_lo + j * cn;
      if (FramesSeeing(camera, stations, SurfacePoint(radius, e, nn, 0.0), 0.0, nullptr) >= need) {
        fe_lo = std::min(fe_lo, e - ce), fe_hi = std::max(fe_hi, e + ce);
        fn_lo = std::min(fn_lo, nn - cn), fn_hi = std::max(fn_hi, nn + cn);
      }
    }
  }
  if (fe_lo > fe_hi) {
    Throw("no ground is seen by " + std::to_string(need) + " frames: lower min_frames_per_point or change the geometry");
  }

  // Fine pass: jittered candidates with relief, kept where `need` frames see them.
  std::mt19937_64 placement(DeriveSeed(options.seed, Stream::kPlacement));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // ~40 candidates per passpoint (at most 500 x 500).
  const int grid = std::min(500, static_cast<int>(std::ceil(std::sqrt(std::max(40.0 * options.passpoints, 4000.0)))));
  const double ge = (fe_hi - fe_lo) / grid, gn = (fn_hi - fn_lo) / grid;
  struct Candidate {
    double e, n, height;
  };
  std::vector<Candidate> eligible;
  for (int i = 0; i < grid; ++i) {
    for (int j = 0; j < grid; ++j) {
      const Candidate c{fe_lo + (i + unit(placement)) * ge, fn_lo + (j + unit(placement)) * gn,
                        options.relief_m * (unit(placement) - 0.5)};
      if (FramesSeeing(camera, stations, SurfacePoint(radius, c.e, c.n, c.height), margin, nullptr) >= need) {
        eligible.push_back(c);
      }
    }
  }
  if (static_cast<int>(eligible.size()) < options.passpoints) {
    Throw("only " + std::to_string(eligible.size()) + " candidate places are seen by " + std::to_string(need) +
          " frames; ask for fewer passpoints or a lower min_frames_per_point");
  }

  // Farthest-point sampling over the ground: an even spread that reaches the
  // edges of the eligible area, so the points fill the formats.
  double ce_mean = 0.0, cn_mean = 0.0;
  for (const Candidate& c : eligible) ce_mean += c.e, cn_mean += c.n;
  ce_mean /= eligible.size(), cn_mean /= eligible.size();
  std::vector<double> distance(eligible.size(), std::numeric_limits<double>::max());
  std::size_t next = 0;
  double farthest = -1.0;
  for (std::size_t i = 0; i < eligible.size(); ++i) {
    const double d = std::hypot(eligible[i].e - ce_mean, eligible[i].n - cn_mean);
    if (d > farthest) farthest = d, next = i;
  }
  std::vector<PointTruth> points;
  std::vector<std::vector<int>> frames_of_point;
  for (int k = 0; k < options.passpoints; ++k) {
    const Candidate c = eligible[next];
    PointTruth p;
    char id[32];
    std::snprintf(id, sizeof(id), "P%03d", k + 1);
    p.id = id;
    p.position_m = SurfacePoint(radius, c.e, c.n, c.height);
    frames_of_point.emplace_back();
    FramesSeeing(camera, stations, p.position_m, margin, &frames_of_point.back());
    points.push_back(std::move(p));
    farthest = -1.0;
    for (std::size_t i = 0; i < eligible.size(); ++i) {
      distance[i] = std::min(distance[i], std::hypot(eligible[i].e - c.e, eligible[i].n - c.n));
      if (distance[i] > farthest) farthest = distance[i], next = i;
    }
  }

  AssembleInput in{camera,  "camera", std::move(stations), std::move(points), std::move(frames_of_point),
                   options.sigma_um, options.weight_sigma_um, options.approximations, options.seed};
  SimulatedBlock block = Assemble(in);
  char line[400];
  std::snprintf(line, sizeof(line),
                "lunar block (seed 000): %zu frames on %zu orbits at %.1f km, convergence %.1f deg, kappa %+.0f deg "
                "per exposure%s, c = %.1f mm on %.1f x %.1f mm, %zu passpoints, %zu observations, sigma %.1f um",
                block.truth.stations.size(), options.revolutions.size(), options.altitude_m * 1e-3,
                options.convergence_deg, options.kappa_increment_deg,
                options.rolls_continue_across_orbits ? " (continuing across orbits)" : "", camera.c_mm,
                camera.format_width_mm,
                camera.format_height_mm, block.truth.points.size(), block.truth.observations.size(), options.sigma_um);
  block.summary = line;
  return block;
}

}  // namespace platemeter::sim
