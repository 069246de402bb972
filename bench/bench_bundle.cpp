// The speed bar of the self-calibrating bundle adjustment: the large simulated
// aerial block (samples/bundle_block.h SimulateAerialBlock: 200 frames, 20 000
// points, ~400 000 observations, 3 um noise) solved with the whole inner cone
// free by
//   (i)   bare Ceres in this program: AutoDiffCostFunction of seed 000's
//         collinearity (calib CollinearityResidualT<BrownAffine>), c, xp, yp,
//         k1..k3, p1, p2 free (b1, b2 held at 0), datum = the first frame's
//         pose and the second frame's X held at their true values, SPARSE_SCHUR
//         (or DENSE_SCHUR), then ceres::Covariance (SPARSE_QR) of the inner
//         cone and of every frame's exterior orientation;
//   (ii)  COLMAP's `colmap bundle_adjuster` on the same block written as a
//         COLMAP model (one shared OPENCV camera in pixels, poses as
//         world-to-camera quaternion + translation, the 2D points, points3D),
//         converted to binary first, with --BundleAdjustment.refine_principal_point 1,
//         once with COLMAP's default tolerances (0: it iterates until the steps
//         vanish) and once with bare Ceres' tolerances;
//   (iii) the platemeter engine: a marked slot (RunPlatemeterEngine) to be
//         filled in when calib's bundle adjustment exists.
// Every method runs as its own process under /usr/bin/time, so its wall time
// and peak RSS are its own; the in-program methods re-simulate the block
// (deterministic) in their process, and a "simulation only" row gives that
// baseline. Bare Ceres' RSS column is its peak before the covariance (the
// process's peak, with the sparse QR, is in the notes). Both solvers start
// from the same perturbed approximations (stations 5 m, angles 0.1 deg,
// points 2 m, c 1 mm, xp/yp 0.05 mm, distortion 0).
//
//   bench_bundle [--pixel-um 10] [--solver sparse|dense] [--threads 2] [--no-covariance]
//                [--no-colmap] [--small] [--work DIR]
//   bench_bundle --table9     the lunar blocks' inner-cone sigmas next to seed 000's Tables 9 and 10
//
// Pixels for COLMAP: column = x_mm / pixel + W_px / 2, row = y_mm / pixel +
// H_px / 2 (docs/bundle-simulator.md: OpenCV's mapping plus COLMAP's half
// pixel, whose top-left pixel centre is (0.5, 0.5)); the camera frame is seed
// 000's image frame, so COLMAP's R is the T matrix and t = -T * station.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>
#include <ceres/ceres.h>

#include "bench_process.h"
#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/calib/rotations.h"
#include "platemeter/samples/bundle_block.h"

namespace {

namespace fs = std::filesystem;
using namespace platemeter;
using platemeter::bench::RunProcess;
using platemeter::bench::ToolRun;

struct Args {
  double pixel_um = 10.0;
  bool dense = false;
  int threads = 2;
  bool covariance = true;
  bool colmap = true;
  bool small = false;
  bool table9 = false;
  std::string work = "/tmp/bench_bundle";
  std::string child;   // internal: run one method in this process
  std::string result;  // internal: where the child writes its key = value lines
};

sim::AerialBlockOptions BlockOptions(const Args& args) {
  sim::AerialBlockOptions o;
  if (args.small) {
    o.strips = 4;
    o.frames_per_strip = 8;
    o.points = 2000;
  }
  o.approximations.station_sigma_m = 5.0;
  o.approximations.angle_sigma_deg = 0.1;
  o.approximations.point_sigma_m = 2.0;
  o.approximations.principal_distance_sigma_mm = 1.0;
  o.approximations.principal_point_sigma_mm = 0.05;
  o.approximations.zero_distortion = true;
  return o;
}

// The block with the datum frames' approximations set to the truth (the first
// frame's pose, the second frame's position), so both solvers' datums are the
// true one where they hold those.
sim::SimulatedBlock MakeBlock(const Args& args) {
  sim::SimulatedBlock block = sim::SimulateAerialBlock(BlockOptions(args));
  for (int i = 0; i < 2; ++i) {
    block.input.frames[i].position_m = block.truth.stations[i].position_m;
    block.input.frames[i].angles = block.truth.stations[i].angles;
  }
  return block;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// ---------------------------------------------------------------------------
// Results passed from a child process: "key value..." lines.
using Result = std::map<std::string, std::vector<double>>;

void WriteResult(const std::string& path, const Result& r, const std::string& note) {
  std::ofstream out(path);
  out.precision(17);
  for (const auto& [key, values] : r) {
    out << key;
    for (double v : values) out << ' ' << v;
    out << '\n';
  }
  out << "note " << note << '\n';
}

Result ReadResult(const std::string& path, std::string* note) {
  Result r;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "note") {
      std::getline(s, *note);
      continue;
    }
    double v;
    while (s >> v) r[key].push_back(v);
  }
  return r;
}

// ---------------------------------------------------------------------------
// (i) Bare Ceres.

// The camera block is held in scaled units, value * CameraScale(r0), so that
// every column of the Jacobian is of the size of an image displacement at the
// radius r0 (the format's half diagonal): k3's raw column (~r^7) would be 1e15
// times c's and ceres::Covariance's sparse QR would then see rank 3.
std::array<double, kBundleCameraParams> CameraScale(double r0_mm) {
  return {1.0, 1.0, 1.0, std::pow(r0_mm, 2), std::pow(r0_mm, 4), std::pow(r0_mm, 6), r0_mm, r0_mm, 1.0, 1.0};
}

struct CollinearityCost {
  double x_mm, y_mm, sigma_x_mm, sigma_y_mm;
  std::array<double, kBundleCameraParams> scale;  // CameraScale
  template <typename T>
  bool operator()(const T* scaled_camera, const T* pose, const T* point, T* residual) const {
    T camera[kBundleCameraParams];
    for (int i = 0; i < kBundleCameraParams; ++i) camera[i] = scaled_camera[i] / scale[i];
    T rotation[9];
    TMatrixT(pose[0], pose[1], pose[2], rotation);  // seed 000's T(phi, omega, kappa)
    const T direction[3] = {point[0] - pose[3], point[1] - pose[4], point[2] - pose[5]};
    T r[2];
    if (!CollinearityResidualT<BrownAffine>(camera, camera + 3, rotation, direction, T(x_mm), T(y_mm), r)) {
      return false;
    }
    residual[0] = r[0] / sigma_x_mm;
    residual[1] = r[1] / sigma_y_mm;
    return true;
  }
};

Result RunBareCeres(const BundleInput& input, const Args& args, std::string* note) {
  Result result;
  const CameraSetup& setup = input.cameras.at(0);
  const auto scale = CameraScale(0.5 * std::hypot(setup.format_width_mm, setup.format_height_mm));
  std::array<double, kBundleCameraParams> camera = setup.values;
  for (int i = 0; i < kBundleCameraParams; ++i) camera[i] *= scale[i];
  std::vector<std::array<double, 6>> poses;
  std::map<std::string, int> frame_index;
  for (const FrameSetup& f : input.frames) {
    frame_index[f.id] = static_cast<int>(poses.size());
    poses.push_back({f.angles->phi_rad, f.angles->omega_rad, f.angles->kappa_rad, f.position_m->x(),
                     f.position_m->y(), f.position_m->z()});
  }
  std::vector<std::array<double, 3>> points;
  std::map<std::string, int> point_index;
  for (const GroundPoint& g : input.ground_points) {
    point_index[g.id] = static_cast<int>(points.size());
    points.push_back({g.position_m.x(), g.position_m.y(), g.position_m.z()});
  }

  const auto build_start = std::chrono::steady_clock::now();
  ceres::Problem problem;
  for (const ImageObservation& o : input.observations) {
    auto* cost = new ceres::AutoDiffCostFunction<CollinearityCost, 2, kBundleCameraParams, 6, 3>(
        new CollinearityCost{o.x_mm, o.y_mm, o.sigma_x_mm, o.sigma_y_mm, scale});
    problem.AddResidualBlock(cost, nullptr, camera.data(), poses[frame_index.at(o.frame)].data(),
                             points[point_index.at(o.point_id)].data());
  }
  // Inner cone: c, xp, yp, k1..k3, p1, p2 free; b1, b2 held (truth 0).
  problem.SetManifold(camera.data(), new ceres::SubsetManifold(kBundleCameraParams, {8, 9}));
  // Datum: the first frame's pose, the second frame's X (scale).
  problem.SetParameterBlockConstant(poses[0].data());
  problem.SetManifold(poses[1].data(), new ceres::SubsetManifold(6, {3}));
  // Schur elimination order: points first.
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (auto& p : points) ordering->AddElementToGroup(p.data(), 0);
  for (auto& p : poses) ordering->AddElementToGroup(p.data(), 1);
  ordering->AddElementToGroup(camera.data(), 1);

  ceres::Solver::Options options;
  options.linear_solver_type = args.dense ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  options.linear_solver_ordering.reset(ordering);
  options.num_threads = args.threads;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-10;
  options.gradient_tolerance = 1e-12;
  options.parameter_tolerance = 1e-10;
  const double build_s = Seconds(build_start);
  ceres::Solver::Summary summary;
  const auto solve_start = std::chrono::steady_clock::now();
  ceres::Solve(options, &problem, &summary);
  const double solve_s = Seconds(solve_start);
  std::printf("%s\n", summary.FullReport().c_str());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  result["rss_solve_mb"] = {usage.ru_maxrss / 1024.0};

  // RMS of the residuals in mm (per axis).
  double sum2 = 0.0;
  for (const ImageObservation& o : input.observations) {
    const CollinearityCost cost{o.x_mm, o.y_mm, 1.0, 1.0, scale};
    double r[2];
    cost(camera.data(), poses[frame_index.at(o.frame)].data(), points[point_index.at(o.point_id)].data(), r);
    sum2 += r[0] * r[0] + r[1] * r[1];
  }
  const double rms_mm = std::sqrt(sum2 / (2.0 * input.observations.size()));
  const double dof = 2.0 * input.observations.size() - (8 + 6 * (poses.size() - 1) - 1 + 3 * points.size());
  const double sigma0 = std::sqrt(2.0 * summary.final_cost / dof);
  result["wall_s"] = {build_s + solve_s};
  result["solve_s"] = {solve_s};
  result["iterations"] = {static_cast<double>(summary.iterations.size() - 1)};
  result["rms_um"] = {rms_mm * 1e3};
  result["sigma0"] = {sigma0};
  std::vector<double> values;
  for (int i = 0; i < kBundleCameraParams; ++i) values.push_back(camera[i] / scale[i]);
  result["camera"] = values;
  std::vector<double> stations;
  for (const auto& p : poses) stations.insert(stations.end(), {p[3], p[4], p[5]});
  result["stations"] = stations;
  *note = std::string(args.dense ? "DENSE_SCHUR" : "SPARSE_SCHUR") + ", " + std::to_string(args.threads) +
          " threads, " + ceres::TerminationTypeToString(summary.termination_type) + ": " + summary.message;

  if (args.covariance) {
    const auto cov_start = std::chrono::steady_clock::now();
    ceres::Covariance::Options cov_options;
    cov_options.num_threads = args.threads;
    cov_options.algorithm_type = ceres::SPARSE_QR;
    ceres::Covariance covariance(cov_options);
    std::vector<std::pair<const double*, const double*>> blocks;
    blocks.emplace_back(camera.data(), camera.data());
    for (std::size_t i = 1; i < poses.size(); ++i) blocks.emplace_back(poses[i].data(), poses[i].data());
    const bool ok = covariance.Compute(blocks, &problem);
    result["covariance_s"] = {Seconds(cov_start)};
    result["covariance_ok"] = {ok ? 1.0 : 0.0};
    if (ok) {
      double c[kBundleCameraParams * kBundleCameraParams];
      covariance.GetCovarianceBlock(camera.data(), camera.data(), c);
      std::vector<double> sigmas;
      for (int i = 0; i < kBundleCameraParams; ++i) {
        sigmas.push_back(std::sqrt(std::max(0.0, c[i * kBundleCameraParams + i])) / scale[i]);
      }
      result["camera_sigma"] = sigmas;
      std::vector<double> position_sigma, angle_sigma;
      for (std::size_t i = 1; i < poses.size(); ++i) {
        double p[36];
        covariance.GetCovarianceBlock(poses[i].data(), poses[i].data(), p);
        angle_sigma.push_back(std::sqrt((p[0] + p[7] + p[14]) / 3.0));
        position_sigma.push_back(std::sqrt((p[21] + p[28] + p[35]) / 3.0));
      }
      std::sort(position_sigma.begin(), position_sigma.end());
      std::sort(angle_sigma.begin(), angle_sigma.end());
      result["pose_sigma_median"] = {position_sigma[position_sigma.size() / 2],
                                     angle_sigma[angle_sigma.size() / 2] * 206264.806};
      result["pose_sigma_max"] = {position_sigma.back(), angle_sigma.back() * 206264.806};
    }
  }
  return result;
}

// ---------------------------------------------------------------------------
// --table9: the geometry check of the lunar blocks against seed 000's Tables 9
// and 10. The posterior sigmas of xp, yp and c of a pure self-calibration (no
// priors; inner cone c, xp, yp, k1..k3, p1, p2 free), i.e. ceres::Covariance
// at the true values with the a-priori image sigma (a precision simulation, as
// the seed's), datum: the middle orbit's centre frame fixed and the along-track
// coordinate of that orbit's first frame (scale; any minimal datum gives the
// same inner-cone sigmas). Printed next to the seed's. c is Gaussian here,
// the seed prints the balanced c'.
void RunTable9(const Args& args) {
  struct Case {
    std::string name;
    sim::LunarBlockOptions options;
    double seed_xp_um, seed_yp_um, seed_c_um;
  };
  const std::vector<Case> cases = {
      {"Table 9, 50 mm", sim::Seed000Table9Options(50.0), 9, 6, 14},
      {"Table 9, 80 mm", sim::Seed000Table9Options(80.0), 21, 14, 26},
      {"Table 9, 150 mm", sim::Seed000Table9Options(150.0), 70, 44, 70},
      {"Table 9, 500 mm", sim::Seed000Table9Options(500.0), 740, 460, 701},
      {"Table 10, 76.2 mm terrain", sim::Seed000Table10Options(), 2, 2, 3},
      {"Apollo 14 (section 3), 500 mm", sim::Apollo14Section3Options(), 0, 0, 0},
  };
  std::printf("seed 000 Tables 9 and 10: posterior sigmas (um) of a pure self-calibration of the simulated blocks\n");
  std::printf("%-32s %9s %9s %9s   %9s %9s %9s   %s\n", "case", "xp", "yp", "c", "seed xp", "seed yp", "seed c'",
              "observations");
  for (const Case& k : cases) {
    const sim::SimulatedBlock block = sim::SimulateLunarBlock(k.options);
    const auto scale = CameraScale(0.5 * std::hypot(k.options.camera.format_width_mm, k.options.camera.format_height_mm));
    std::array<double, kBundleCameraParams> camera = block.truth.camera.Values();
    for (int i = 0; i < kBundleCameraParams; ++i) camera[i] *= scale[i];
    std::vector<std::array<double, 6>> poses;
    std::map<std::string, int> frame_index;
    for (const sim::StationTruth& st : block.truth.stations) {
      frame_index[st.id] = static_cast<int>(poses.size());
      poses.push_back({st.angles.phi_rad, st.angles.omega_rad, st.angles.kappa_rad, st.position_m.x(),
                       st.position_m.y(), st.position_m.z()});
    }
    std::vector<std::array<double, 3>> points;
    std::map<std::string, int> point_index;
    for (const sim::PointTruth& p : block.truth.points) {
      point_index[p.id] = static_cast<int>(points.size());
      points.push_back({p.position_m.x(), p.position_m.y(), p.position_m.z()});
    }
    ceres::Problem problem;
    for (const ImageObservation& o : block.truth.observations) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CollinearityCost, 2, kBundleCameraParams, 6, 3>(
                                   new CollinearityCost{o.x_mm, o.y_mm, o.sigma_x_mm, o.sigma_y_mm, scale}),
                               nullptr, camera.data(), poses[frame_index.at(o.frame)].data(),
                               points[point_index.at(o.point_id)].data());
    }
    problem.SetManifold(camera.data(), new ceres::SubsetManifold(kBundleCameraParams, {8, 9}));
    const int centre = static_cast<int>(poses.size()) / 2;  // the middle orbit's centre frame
    problem.SetParameterBlockConstant(poses[centre].data());
    problem.SetManifold(poses[centre - 1].data(), new ceres::SubsetManifold(6, {3}));
    ceres::Covariance::Options cov_options;
    // SPARSE_QR inverts the whole normal matrix. (DENSE_SVD with null_space_rank
    // -1 drops the near-null directions, i.e. exactly the xp-attitude
    // compensation: it printed xp sigmas of 2 um for the Apollo 14 case.)
    cov_options.algorithm_type = ceres::SPARSE_QR;
    cov_options.num_threads = args.threads;
    ceres::Covariance covariance(cov_options);
    std::vector<std::pair<const double*, const double*>> blocks = {{camera.data(), camera.data()}};
    double sx = NAN, sy = NAN, sc = NAN;
    if (covariance.Compute(blocks, &problem)) {
      double c[kBundleCameraParams * kBundleCameraParams];
      covariance.GetCovarianceBlock(camera.data(), camera.data(), c);
      sc = std::sqrt(c[0]) / scale[0] * 1e3;
      sx = std::sqrt(c[kBundleCameraParams + 1]) / scale[1] * 1e3;
      sy = std::sqrt(c[2 * kBundleCameraParams + 2]) / scale[2] * 1e3;
    }
    if (k.seed_xp_um > 0) {
      std::printf("%-32s %9.1f %9.1f %9.1f   %9.0f %9.0f %9.0f   %zu\n", k.name.c_str(), sx, sy, sc, k.seed_xp_um,
                  k.seed_yp_um, k.seed_c_um, block.truth.observations.size());
    } else {
      std::printf("%-32s %9.1f %9.1f %9.1f   %9s %9s %9s   %zu (xp, yp not recoverable, section 2.3)\n",
                  k.name.c_str(), sx, sy, sc, "-", "-", "-", block.truth.observations.size());
    }
  }
}

// ---------------------------------------------------------------------------
// (iii) The platemeter engine (calib/bundle_adjustment.h RunBundleAdjustment)
// on `input` with the same adjustment as bare Ceres above: the inner cone c, xp,
// yp, k1..k3, p1, p2 free, b1 and b2 held; the datum the first frame held plus
// the distance from it to the second frame (bare Ceres holds that frame's X:
// the same seven degrees of freedom). Its wall time includes everything it
// reports: the covariance of the inner cone, of every frame and of every point,
// the rank report and the residuals.
struct EngineRun {
  bool ran = false;
  Result values;
  std::string note;
};
EngineRun RunPlatemeterEngine(const BundleInput& block_input, int threads) {
  BundleInput input = block_input;
  for (int i = 0; i < 8; ++i) input.cameras[0].states[i] = ParameterState::Free();
  input.frames[0].fixed = true;
  const double baseline_m = (*input.frames[1].position_m - *input.frames[0].position_m).norm();
  input.distances.push_back({input.frames[0].id, input.frames[1].id, baseline_m, 0.0});
  BundleOptions options;
  options.adjustment.num_threads = threads;
  const auto start = std::chrono::steady_clock::now();
  const BundleResult result = RunBundleAdjustment(input, options);
  EngineRun run;
  run.ran = true;
  run.values["wall_s"] = {Seconds(start)};
  run.values["solve_s"] = {result.adjustment.solve_seconds};
  run.values["covariance_s"] = {result.adjustment.covariance_seconds};
  run.values["iterations"] = {static_cast<double>(result.adjustment.iterations)};
  run.values["sigma0"] = {result.adjustment.sigma0};
  double sum2 = 0.0;
  long n = 0;
  for (const ObservationResidual& r : result.adjustment.residuals) {
    if (r.residual.size() != 2) continue;
    sum2 += r.residual[0] * r.residual[0] + r.residual[1] * r.residual[1];
    n += 2;
  }
  run.values["rms_um"] = {1e3 * std::sqrt(sum2 / std::max(1L, n))};
  const BundleCameraResult& camera = result.cameras[0];
  run.values["camera"] = std::vector<double>(camera.values.begin(), camera.values.end());
  std::vector<double> sigmas;
  for (const auto& s : camera.sigmas) sigmas.push_back(s.value_or(0.0));
  run.values["camera_sigma"] = sigmas;
  std::vector<double> stations;
  for (const BundleFrameResult& f : result.frames) stations.insert(stations.end(), {f.position_m.x(), f.position_m.y(), f.position_m.z()});
  run.values["stations"] = stations;
  run.note = std::to_string(threads) + " threads, " + result.adjustment.summary + " Solve " +
             std::to_string(result.adjustment.solve_seconds) + " s, covariance (inner cone, every frame and point) " +
             std::to_string(result.adjustment.covariance_seconds) + " s.";
  return run;
}

// ---------------------------------------------------------------------------
// (ii) COLMAP.

struct ColmapCamera {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0, k1 = 0, k2 = 0, p1 = 0, p2 = 0;
};

// Pixel (COLMAP convention) of plate mm.
Eigen::Vector2d ColmapPixel(const sim::PixelMapping& m, double x_mm, double y_mm) {
  return m.PixelFromPlate(Eigen::Vector2d(x_mm, y_mm)) + Eigen::Vector2d(0.5, 0.5);
}

void WriteColmapModel(const sim::SimulatedBlock& block, const sim::PixelMapping& pixels, const fs::path& dir) {
  fs::create_directories(dir);
  const BundleInput& input = block.input;
  const CameraSetup& camera = input.cameras.at(0);
  const double pixel_mm = pixels.pixel_size_um * 1e-3;
  {
    std::ofstream out(dir / "cameras.txt");
    out.precision(17);
    out << "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
    const Eigen::Vector2d principal = ColmapPixel(pixels, camera.values[1], camera.values[2]);
    // Starting distortion: the approximations' (zero in the bench), converted to first order.
    const double c = camera.values[0];
    out << "1 OPENCV " << pixels.width_px << ' ' << pixels.height_px << ' ' << c / pixel_mm << ' ' << c / pixel_mm
        << ' ' << principal.x() << ' ' << principal.y() << ' ' << -camera.values[3] * c * c << ' '
        << -camera.values[4] * c * c * c * c << ' ' << -camera.values[7] * c << ' ' << -camera.values[6] * c << '\n';
  }
  std::map<std::string, int> image_id, point_id;
  for (std::size_t i = 0; i < input.frames.size(); ++i) image_id[input.frames[i].id] = static_cast<int>(i) + 1;
  for (std::size_t i = 0; i < input.ground_points.size(); ++i) point_id[input.ground_points[i].id] = static_cast<int>(i) + 1;
  // Observations are frame-major: each frame's 2D points in file order.
  std::vector<std::vector<const ImageObservation*>> per_frame(input.frames.size());
  for (const ImageObservation& o : input.observations) per_frame[image_id.at(o.frame) - 1].push_back(&o);
  std::vector<std::vector<std::pair<int, int>>> tracks(input.ground_points.size());
  {
    std::ofstream out(dir / "images.txt");
    out.precision(17);
    out << "# Image list with two lines of data per image:\n"
           "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
    for (std::size_t i = 0; i < input.frames.size(); ++i) {
      const FrameSetup& f = input.frames[i];
      const Eigen::Matrix3d r = TMatrixFromAngles(*f.angles);  // world to camera
      const Eigen::Quaterniond q(r);
      const Eigen::Vector3d t = -(r * *f.position_m);
      out << i + 1 << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << t.x() << ' ' << t.y()
          << ' ' << t.z() << " 1 " << f.id << '\n';
      int index = 0;
      for (const ImageObservation* o : per_frame[i]) {
        const Eigen::Vector2d px = ColmapPixel(pixels, o->x_mm, o->y_mm);
        const int pid = point_id.at(o->point_id);
        out << (index ? " " : "") << px.x() << ' ' << px.y() << ' ' << pid;
        tracks[pid - 1].emplace_back(static_cast<int>(i) + 1, index++);
      }
      out << '\n';
    }
  }
  {
    std::ofstream out(dir / "points3D.txt");
    out.precision(17);
    out << "# 3D point list with one line of data per point:\n"
           "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
    for (std::size_t i = 0; i < input.ground_points.size(); ++i) {
      const Eigen::Vector3d& p = input.ground_points[i].position_m;
      out << i + 1 << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << " 128 128 128 0";
      for (const auto& [image, index] : tracks[i]) out << ' ' << image << ' ' << index;
      out << '\n';
    }
  }
}

std::vector<std::string> DataLines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '#') continue;
    lines.push_back(line);
  }
  return lines;
}

// Reads the adjusted model (text) and computes the RMS reprojection error of
// the observations it holds through COLMAP's OPENCV model.
bool ReadColmapResult(const fs::path& dir, ColmapCamera* camera, double* rms_px, long* observations) {
  const std::vector<std::string> cams = DataLines(dir / "cameras.txt");
  if (cams.empty()) return false;
  {
    std::istringstream s(cams[0]);
    int id;
    std::string model;
    s >> id >> model >> camera->width >> camera->height >> camera->fx >> camera->fy >> camera->cx >> camera->cy >>
        camera->k1 >> camera->k2 >> camera->p1 >> camera->p2;
    if (model != "OPENCV" || !s) return false;
  }
  std::map<long, Eigen::Vector3d> points;
  for (const std::string& line : DataLines(dir / "points3D.txt")) {
    if (line.empty()) continue;
    std::istringstream s(line);
    long id;
    Eigen::Vector3d p;
    s >> id >> p.x() >> p.y() >> p.z();
    points[id] = p;
  }
  const std::vector<std::string> images = DataLines(dir / "images.txt");
  double sum2 = 0.0;
  long n = 0;
  for (std::size_t i = 0; i + 1 < images.size(); i += 2) {
    if (images[i].empty()) {  // tolerate a blank line between records
      --i;
      continue;
    }
    std::istringstream head(images[i]);
    long id;
    double qw, qx, qy, qz, tx, ty, tz;
    head >> id >> qw >> qx >> qy >> qz >> tx >> ty >> tz;
    const Eigen::Matrix3d r = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    const Eigen::Vector3d t(tx, ty, tz);
    std::istringstream obs(images[i + 1]);
    double u, v;
    long pid;
    while (obs >> u >> v >> pid) {
      if (pid < 0) continue;
      const auto it = points.find(pid);
      if (it == points.end()) continue;
      const Eigen::Vector3d xc = r * it->second + t;
      const double x = xc.x() / xc.z(), y = xc.y() / xc.z();
      const double r2 = x * x + y * y, radial = 1.0 + r2 * (camera->k1 + r2 * camera->k2);
      const double xd = x * radial + 2.0 * camera->p1 * x * y + camera->p2 * (r2 + 2.0 * x * x);
      const double yd = y * radial + camera->p1 * (r2 + 2.0 * y * y) + 2.0 * camera->p2 * x * y;
      const double du = camera->fx * xd + camera->cx - u, dv = camera->fy * yd + camera->cy - v;
      sum2 += du * du + dv * dv;
      ++n;
    }
  }
  if (n == 0) return false;
  *rms_px = std::sqrt(sum2 / (2.0 * n));
  *observations = n;
  return true;
}

// ---------------------------------------------------------------------------
// The focal-plane error of a fitted camera: over a 21 x 21 grid of directions
// filling the format, |measured position by the fit - by the truth| (um).
struct FieldError {
  double rms_um = 0.0, max_um = 0.0;
};

template <typename Project>
FieldError CompareField(const sim::BundleCameraTruth& truth, Project fitted) {
  const auto values = truth.Values();
  FieldError e;
  double sum2 = 0.0;
  int n = 0;
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 20; ++j) {
      const double xi = (i / 20.0 - 0.5) * truth.format_width_mm * 0.98;
      const double yi = (j / 20.0 - 0.5) * truth.format_height_mm * 0.98;
      double mx, my;
      if (!MeasuredFromIdeal<BrownAffine>(values.data() + 3, xi, yi, &mx, &my)) continue;
      mx += truth.xp_mm, my += truth.yp_mm;
      const Eigen::Vector2d f = fitted(xi / truth.c_mm, yi / truth.c_mm);  // normalized direction
      const double d = std::hypot(f.x() - mx, f.y() - my) * 1e3;
      sum2 += d * d;
      e.max_um = std::max(e.max_um, d);
      ++n;
    }
  }
  e.rms_um = std::sqrt(sum2 / n);
  return e;
}

std::string Fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof(b), format, v);
  return b;
}

// ---------------------------------------------------------------------------

int RunChild(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  sim::SimulatedBlock block = MakeBlock(args);
  const double simulate_s = Seconds(start);
  Result result;
  std::string note;
  if (args.child == "none") {
    result["wall_s"] = {0.0};
    note = "simulation only";
  } else if (args.child == "ceres") {
    result = RunBareCeres(block.input, args, &note);
  } else if (args.child == "platemeter") {
    EngineRun run = RunPlatemeterEngine(block.input, args.threads);
    result = run.values;
    result["ran"] = {run.ran ? 1.0 : 0.0};
    note = run.note;
  } else {
    std::fprintf(stderr, "bench_bundle: unknown --child %s\n", args.child.c_str());
    return 2;
  }
  result["simulate_s"] = {simulate_s};
  WriteResult(args.result, result, note);
  return 0;
}

struct Row {
  std::string method;
  std::string label;  // short, for the inner-cone columns
  bool ran = false;
  double wall_s = 0, rss_mb = 0, rms_um = 0, rms_px = 0;
  std::array<double, kBundleCameraParams> camera{};
  bool has_camera = false;
  FieldError field;
  std::string note;
};

// Runs `args` under /usr/bin/time; returns the tool's wall (s) and peak RSS (MB).
ToolRun TimedRun(const std::vector<std::string>& args, const fs::path& log, const fs::path& time_file) {
  std::vector<std::string> full = {"/usr/bin/time", "-f", "%e %M", "-o", time_file.string()};
  full.insert(full.end(), args.begin(), args.end());
  ToolRun run = RunProcess(full, log.string());
  std::ifstream in(time_file);
  double wall = 0, kb = 0;
  std::string first;
  std::getline(in, first);
  if (first.rfind("Command", 0) == 0) std::getline(in, first);  // "Command exited with non-zero status"
  std::istringstream(first) >> wall >> kb;
  run.seconds = wall;
  run.peak_rss_mb = kb / 1024.0;
  return run;
}

// COLMAP's bundle_adjuster on the block written as a COLMAP model: its
// defaults, then bare Ceres' tolerances; one row each.
void RunColmap(const Args& args, const fs::path& work, const sim::SimulatedBlock& block,
               const sim::PixelMapping& pixels, std::vector<Row>* rows_out) {
  std::vector<Row>& rows = *rows_out;
  const sim::BundleTruth& truth = block.truth;
  const double pixel_mm = args.pixel_um * 1e-3;
  const fs::path text = work / "colmap-input-txt", bin = work / "colmap-input";
  for (const fs::path& d : {text, bin}) fs::remove_all(d), fs::create_directories(d);
  WriteColmapModel(block, pixels, text);
  const std::string colmap = "/usr/bin/colmap";
  bool converted = false;
  if (fs::exists(colmap)) {
    converted = RunProcess({colmap, "model_converter", "--input_path", text.string(), "--output_path", bin.string(),
                            "--output_type", "BIN"},
                           (work / "colmap-convert.log").string())
                    .ok;
  }
  // COLMAP's defaults (all tolerances 0: it iterates until the steps vanish),
  // then the tolerances bare Ceres uses.
  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {"COLMAP bundle_adjuster (default tolerances)", {}},
      {"COLMAP bundle_adjuster (Ceres' tolerances)",
       {"--BundleAdjustment.function_tolerance", "1e-10", "--BundleAdjustment.gradient_tolerance", "1e-12",
        "--BundleAdjustment.parameter_tolerance", "1e-10"}}};
  for (std::size_t v = 0; v < variants.size(); ++v) {
    Row row;
    row.method = variants[v].first;
    row.label = v == 0 ? "COLMAP (defaults)" : "COLMAP (Ceres' tol.)";
    const std::string tag = "colmap-" + std::to_string(v + 1);
    const fs::path out = work / (tag + "-output"), out_text = work / (tag + "-output-txt");
    for (const fs::path& d : {out, out_text}) fs::remove_all(d), fs::create_directories(d);
    if (!fs::exists(colmap)) {
      row.note = "not run: /usr/bin/colmap missing (apt-get install -y --no-install-recommends colmap)";
      rows.push_back(row);
      continue;
    }
    std::printf("running %s ...\n", row.method.c_str());
    std::vector<std::string> cmd = {colmap, "bundle_adjuster", "--input_path", bin.string(), "--output_path",
                                    out.string(), "--BundleAdjustment.refine_principal_point", "1"};
    cmd.insert(cmd.end(), variants[v].second.begin(), variants[v].second.end());
    const ToolRun run = TimedRun(cmd, work / (tag + ".log"), work / (tag + ".time"));
    const ToolRun back = RunProcess({colmap, "model_converter", "--input_path", out.string(), "--output_path",
                                     out_text.string(), "--output_type", "TXT"},
                                    (work / (tag + "-convert-back.log")).string());
    ColmapCamera cam;
    double rms_px = 0;
    long n = 0;
    if (!converted || !run.ok || !back.ok || !ReadColmapResult(out_text, &cam, &rms_px, &n)) {
      row.note = "failed, see " + (work / (tag + ".log")).string();
      rows.push_back(row);
      continue;
    }
    row.ran = true;
    row.wall_s = run.seconds;
    row.rss_mb = run.peak_rss_mb;
    row.rms_px = rms_px;
    row.rms_um = rms_px * args.pixel_um;
    // Inner cone in plate terms: c = f * pixel, xp = (cx - W/2) * pixel; the
    // distortion converted to Brown's correction form to first order (k2 to second).
    const double c = 0.5 * (cam.fx + cam.fy) * pixel_mm;
    row.camera = {c,
                  (cam.cx - 0.5 * cam.width) * pixel_mm,
                  (cam.cy - 0.5 * cam.height) * pixel_mm,
                  -cam.k1 / (c * c),
                  (3.0 * cam.k1 * cam.k1 - cam.k2) / std::pow(c, 4),
                  0.0,
                  -cam.p2 / c,
                  -cam.p1 / c,
                  -(cam.fx - cam.fy) / (cam.fx + cam.fy),  // ~ x-scale affinity b1
                  0.0};
    row.has_camera = true;
    row.field = CompareField(truth.camera, [&](double nx, double ny) {
      // COLMAP's projection of the same direction, in plate mm.
      const double r2 = nx * nx + ny * ny, radial = 1.0 + r2 * (cam.k1 + r2 * cam.k2);
      const double xd = nx * radial + 2.0 * cam.p1 * nx * ny + cam.p2 * (r2 + 2.0 * nx * nx);
      const double yd = ny * radial + cam.p1 * (r2 + 2.0 * ny * ny) + 2.0 * cam.p2 * nx * ny;
      return Eigen::Vector2d((cam.fx * xd + cam.cx - 0.5 * cam.width) * pixel_mm,
                             (cam.fy * yd + cam.cy - 0.5 * cam.height) * pixel_mm);
    });
    char note[300];
    std::snprintf(note, sizeof(note),
                  "OPENCV fx %.2f fy %.2f cx %.2f cy %.2f k1 %.4g k2 %.4g p1 %.4g p2 %.4g (px); %ld observations",
                  cam.fx, cam.fy, cam.cx, cam.cy, cam.k1, cam.k2, cam.p1, cam.p2, n);
    row.note = note;
    // Iterations, time and termination from COLMAP's report.
    std::ifstream log(work / (tag + ".log"));
    std::string line;
    while (std::getline(log, line)) {
      for (const char* key : {"Iterations :", "Time :", "Termination :"}) {
        const auto at = line.find(key);
        if (at != std::string::npos) row.note += "; " + line.substr(line.find_first_not_of(' '));
      }
    }
    rows.push_back(row);
  }
}

// The table of every method, then the inner cone against the truth and each
// method's details, the covariance costs and the speed ratios.
void PrintResults(const std::vector<Row>& rows, const sim::BundleTruth& truth, const Result& ceres_result,
                  const Result& engine_result) {
  // ---- The table ----
  const auto tv = truth.camera.Values();
  std::printf("\n%-46s %8s %9s %14s %10s %9s %9s %14s\n", "method", "wall s", "RSS MB", "RMS um (px)", "c mm",
              "xp um", "yp um", "field err um");
  std::printf("%-46s %8s %9s %14s %10.4f %9.2f %9.2f %14s\n", "truth", "", "", "", tv[0], tv[1] * 1e3, tv[2] * 1e3,
              "rms / max");
  for (const Row& r : rows) {
    std::string rms = r.rms_um > 0 ? Fmt("%.3f", r.rms_um) + " (" + Fmt("%.3f", r.rms_px) + ")" : "";
    if (!r.ran && r.method.rfind("simulation", 0) != 0) {
      std::printf("%-46s %8s %9s %14s  %s\n", r.method.c_str(), "-", "-", "-", r.note.c_str());
      continue;
    }
    std::printf("%-46s %8.2f %9.1f %14s", r.method.c_str(), r.wall_s, r.rss_mb, rms.c_str());
    if (r.has_camera) {
      std::printf(" %10.4f %9.2f %9.2f %7.2f / %.2f", r.camera[0], r.camera[1] * 1e3, r.camera[2] * 1e3,
                  r.field.rms_um, r.field.max_um);
    }
    std::printf("\n");
  }

  // ---- Details ----
  std::printf("\ninner cone, truth vs fitted (COLMAP's distortion converted to Brown's correction form, first order):\n");
  std::printf("%-12s %14s", "parameter", "truth");
  for (const Row& r : rows) {
    if (r.has_camera) std::printf(" %22s", r.label.c_str());
  }
  std::printf("\n");
  const auto ceres_sigma = ceres_result.count("camera_sigma") ? ceres_result.at("camera_sigma") : std::vector<double>{};
  for (int i = 0; i < 8; ++i) {
    std::printf("%-12s %14.6g", kBundleCameraParamNames[i], tv[i]);
    for (const Row& r : rows) {
      if (r.has_camera) std::printf(" %22.6g", r.camera[i]);
    }
    if (ceres_sigma.size() == kBundleCameraParams) std::printf("   (Ceres sigma %.3g)", ceres_sigma[i]);
    std::printf("\n");
  }
  for (const Row& r : rows) std::printf("%s: %s\n", r.method.c_str(), r.note.c_str());
  if (ceres_result.count("iterations")) {
    std::printf("bare Ceres: %.0f iterations, solve %.2f s, sigma0 %.3f", ceres_result.at("iterations")[0],
                ceres_result.at("solve_s")[0], ceres_result.at("sigma0")[0]);
    if (ceres_result.count("stations")) {
      const auto& s = ceres_result.at("stations");
      double sum2 = 0;
      for (std::size_t i = 0; i < truth.stations.size(); ++i) {
        for (int k = 0; k < 3; ++k) sum2 += std::pow(s[3 * i + k] - truth.stations[i].position_m[k], 2);
      }
      std::printf(", station RMS error vs truth %.3f m", std::sqrt(sum2 / (3.0 * truth.stations.size())));
    }
    std::printf("\n");
  }
  if (ceres_result.count("covariance_s")) {
    std::printf("ceres::Covariance (SPARSE_QR) of the inner cone and %zu frames: %s in %.2f s",
                truth.stations.size() - 1, ceres_result.at("covariance_ok")[0] > 0 ? "ok" : "FAILED",
                ceres_result.at("covariance_s")[0]);
    if (ceres_result.count("pose_sigma_median")) {
      std::printf("; frame sigmas median %.3f m / %.2f arcsec, max %.3f m / %.2f arcsec",
                  ceres_result.at("pose_sigma_median")[0], ceres_result.at("pose_sigma_median")[1],
                  ceres_result.at("pose_sigma_max")[0], ceres_result.at("pose_sigma_max")[1]);
    }
    std::printf("\n");
  }
  if (engine_result.count("covariance_s")) {
    std::printf("platemeter engine: %.0f iterations, solve %.2f s, covariance of the inner cone, every frame and "
                "every point %.2f s (%.2f x the solve), sigma0 %.3f\n",
                engine_result.at("iterations")[0], engine_result.at("solve_s")[0], engine_result.at("covariance_s")[0],
                engine_result.at("covariance_s")[0] / engine_result.at("solve_s")[0], engine_result.at("sigma0")[0]);
    double engine_wall = 0.0;
    for (const Row& r : rows) {
      if (r.method == "platemeter engine") engine_wall = r.wall_s;
    }
    for (const Row& r : rows) {
      if (r.ran && engine_wall > 0.0 && r.method.rfind("COLMAP", 0) == 0) {
        std::printf("%s / platemeter engine (covariances included), wall time: %.1f x\n", r.method.c_str(),
                    r.wall_s / engine_wall);
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_bundle: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--pixel-um") args.pixel_um = std::stod(next());
    else if (a == "--solver") {
      const std::string s = next();
      if (s != "sparse" && s != "dense") {
        std::fprintf(stderr, "bench_bundle: --solver is sparse or dense\n");
        return 2;
      }
      args.dense = s == "dense";
    } else if (a == "--threads") args.threads = std::stoi(next());
    else if (a == "--no-covariance") args.covariance = false;
    else if (a == "--no-colmap") args.colmap = false;
    else if (a == "--small") args.small = true;
    else if (a == "--table9") args.table9 = true;
    else if (a == "--work") args.work = next();
    else if (a == "--child") args.child = next();
    else if (a == "--result") args.result = next();
    else {
      std::fprintf(stderr,
                   "usage: bench_bundle [--pixel-um 10] [--solver sparse|dense] [--threads 2] [--no-covariance]\n"
                   "                    [--no-colmap] [--small] [--work DIR]\n"
                   "       bench_bundle --table9\n");
      return 2;
    }
  }
  if (!args.child.empty()) return RunChild(args);
  if (args.table9) {
    RunTable9(args);
    return 0;
  }

  const fs::path work = args.work;
  fs::create_directories(work);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::string> child_common = {self, "--pixel-um", std::to_string(args.pixel_um), "--solver",
                                           args.dense ? "dense" : "sparse", "--threads", std::to_string(args.threads)};
  if (!args.covariance) child_common.push_back("--no-covariance");
  if (args.small) child_common.push_back("--small");

  const auto sim_start = std::chrono::steady_clock::now();
  const sim::SimulatedBlock block = MakeBlock(args);
  const sim::BundleTruth& truth = block.truth;
  std::printf("block: %s (simulated in %.2f s)\n", block.summary.c_str(), Seconds(sim_start));
  const sim::PixelMapping pixels = sim::MakePixelMapping(truth.camera, args.pixel_um);
  const double pixel_mm = args.pixel_um * 1e-3;
  std::printf("pixels for COLMAP: %.1f um, %d x %d px; noise %.2f px\n", args.pixel_um, pixels.width_px,
              pixels.height_px, truth.sigma_mm / pixel_mm);

  std::vector<Row> rows;
  auto run_child = [&](const std::string& method, const std::string& label) {
    const fs::path result = work / (method + ".result");
    fs::remove(result);
    std::vector<std::string> cmd = child_common;
    cmd.insert(cmd.end(), {"--child", method, "--result", result.string()});
    std::printf("running %s ...\n", label.c_str());
    const ToolRun run = TimedRun(cmd, work / (method + ".log"), work / (method + ".time"));
    Row row;
    row.method = label;
    row.label = method == "ceres" ? "bare Ceres" : method;
    std::string note;
    Result r = ReadResult(result.string(), &note);
    row.note = note;
    row.rss_mb = run.peak_rss_mb;
    if (!run.ok || r.empty()) {
      row.note = "failed (exit " + std::to_string(run.exit_code) + "), see " + (work / (method + ".log")).string();
      rows.push_back(row);
      return r;
    }
    row.ran = !(r.count("ran") && r["ran"][0] == 0.0);
    if (r.count("wall_s")) row.wall_s = r["wall_s"][0];
    if (r.count("rss_solve_mb")) {  // the peak before the covariance; the process's peak in the note
      row.note += "; peak RSS " + Fmt("%.0f", run.peak_rss_mb) + " MB with the covariance";
      row.rss_mb = r["rss_solve_mb"][0];
    }
    if (r.count("rms_um")) row.rms_um = r["rms_um"][0], row.rms_px = row.rms_um * 1e-3 / pixel_mm;
    if (r.count("camera") && r["camera"].size() == kBundleCameraParams) {
      std::copy(r["camera"].begin(), r["camera"].end(), row.camera.begin());
      row.has_camera = true;
      sim::BundleCameraTruth fit = truth.camera;
      fit.c_mm = row.camera[0], fit.xp_mm = row.camera[1], fit.yp_mm = row.camera[2];
      fit.k1_per_mm2 = row.camera[3], fit.k2_per_mm4 = row.camera[4], fit.k3_per_mm6 = row.camera[5];
      fit.p1_per_mm = row.camera[6], fit.p2_per_mm = row.camera[7], fit.b1 = row.camera[8], fit.b2 = row.camera[9];
      const auto values = fit.Values();
      row.field = CompareField(truth.camera, [&](double nx, double ny) {
        double mx = 0, my = 0;
        MeasuredFromIdeal<BrownAffine>(values.data() + 3, fit.c_mm * nx, fit.c_mm * ny, &mx, &my);
        return Eigen::Vector2d(mx + fit.xp_mm, my + fit.yp_mm);
      });
    }
    rows.push_back(row);
    return r;
  };

  const Result baseline = run_child("none", "simulation only (baseline of the rows below)");
  (void)baseline;
  const Result ceres_result = run_child("ceres", "bare Ceres");
  const Result engine_result = run_child("platemeter", "platemeter engine");

  if (args.colmap) RunColmap(args, work, block, pixels, &rows);

  PrintResults(rows, truth, ceres_result, engine_result);
  std::printf("work files and logs: %s\n", work.c_str());
  return 0;
}
