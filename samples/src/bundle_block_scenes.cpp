// Simulated blocks for the bundle adjustment: the planar target field (with
// its OpenCV view) and the large aerial block (docs/bundle-simulator.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "platemeter/samples/bundle_block.h"

namespace platemeter::sim {

using namespace bundle_internal;

// ---------------------------------------------------------------------------
// Pixels (OpenCV's convention).

Eigen::Vector2d PixelMapping::PixelFromPlate(const Eigen::Vector2d& point_mm) const {
  const double pixel_mm = pixel_size_um * 1e-3;
  return Eigen::Vector2d(point_mm.x() / pixel_mm + 0.5 * (width_px - 1), point_mm.y() / pixel_mm + 0.5 * (height_px - 1));
}

Eigen::Vector2d PixelMapping::PlateFromPixel(const Eigen::Vector2d& point_px) const {
  const double pixel_mm = pixel_size_um * 1e-3;
  return Eigen::Vector2d((point_px.x() - 0.5 * (width_px - 1)) * pixel_mm, (point_px.y() - 0.5 * (height_px - 1)) * pixel_mm);
}

PixelMapping MakePixelMapping(const BundleCameraTruth& camera, double pixel_size_um) {
  if (!(pixel_size_um > 0.0)) Throw("pixel_size_um must be positive");
  PixelMapping m;
  m.pixel_size_um = pixel_size_um;
  m.width_px = static_cast<int>(std::lround(camera.format_width_mm / (pixel_size_um * 1e-3)));
  m.height_px = static_cast<int>(std::lround(camera.format_height_mm / (pixel_size_um * 1e-3)));
  if (m.width_px < 2 || m.height_px < 2) Throw("the pixel size leaves fewer than 2 pixels across the format");
  return m;
}

OpenCvIntrinsics OpenCvIntrinsicsFromCamera(const BundleCameraTruth& camera, const PixelMapping& pixels) {
  const double pixel_mm = pixels.pixel_size_um * 1e-3;
  OpenCvIntrinsics k;
  k.fx_px = k.fy_px = camera.c_mm / pixel_mm;
  const Eigen::Vector2d principal = pixels.PixelFromPlate(Eigen::Vector2d(camera.xp_mm, camera.yp_mm));
  k.cx_px = principal.x();
  k.cy_px = principal.y();
  return k;
}

// ---------------------------------------------------------------------------
// c) Planar target.

BundleCameraTruth PlanarTargetOptions::DefaultPlanarCamera() {
  BundleCameraTruth c;
  c.c_mm = 16.0;
  c.xp_mm = 0.03;
  c.yp_mm = -0.02;
  c.k1_per_mm2 = 5.0e-5;   // ~63 um at the 10.8 mm half diagonal
  c.k2_per_mm4 = -1.0e-7;  // ~-15 um there
  c.k3_per_mm6 = 0.0;
  c.p1_per_mm = 2.0e-5;
  c.p2_per_mm = -1.5e-5;
  c.b1 = 0.0;
  c.b2 = 0.0;
  c.format_width_mm = 18.0;
  c.format_height_mm = 12.0;
  return c;
}

bool PlanarTargetOptions::Check(std::string* why) const {
  if (!camera.Check(why)) return false;
  if (!approximations.Check(why)) return false;
  if (columns < 2 || rows < 2) return Fail(why, "the target needs at least 2 x 2 points");
  if (!(spacing_m > 0.0)) return Fail(why, "spacing_m must be positive");
  if (views < 1) return Fail(why, "views must be at least 1");
  if (!(min_tilt_deg >= 0.0) || !(max_tilt_deg >= min_tilt_deg) || !(max_tilt_deg < 80.0)) {
    return Fail(why, "tilts must satisfy 0 <= min_tilt_deg <= max_tilt_deg < 80");
  }
  if (!(max_roll_deg >= 0.0) || !(max_roll_deg <= 180.0)) return Fail(why, "max_roll_deg must be in [0, 180]");
  if (!(aim_jitter_m >= 0.0)) return Fail(why, "aim_jitter_m must be >= 0");
  if (!(min_distance_m > 0.0)) return Fail(why, "min_distance_m must be positive");
  if (!(pixel_size_um > 0.0)) return Fail(why, "pixel_size_um must be positive");
  if (!(format_margin_mm >= 0.0) ||
      !(2.0 * format_margin_mm < std::min(camera.format_width_mm, camera.format_height_mm))) {
    return Fail(why, "format_margin_mm must be >= 0 and smaller than half the format");
  }
  return CheckSigmas(sigma_um, weight_sigma_um, why);
}

PlanarTargetBlock SimulatePlanarTarget(const PlanarTargetOptions& options) {
  std::string why;
  if (!options.Check(&why)) Throw(why);
  const BundleCameraTruth& camera = options.camera;

  std::vector<PointTruth> points;
  for (int j = 0; j < options.rows; ++j) {
    for (int i = 0; i < options.columns; ++i) {
      PointTruth p;
      p.id = "B" + std::to_string(i) + "-" + std::to_string(j);
      p.position_m = Eigen::Vector3d(i * options.spacing_m, j * options.spacing_m, 0.0);
      points.push_back(std::move(p));
    }
  }
  const Eigen::Vector3d centre(0.5 * (options.columns - 1) * options.spacing_m,
                               0.5 * (options.rows - 1) * options.spacing_m, 0.0);

  std::mt19937_64 random(DeriveSeed(options.seed, Stream::kPoses));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<StationTruth> stations;
  for (int k = 0; k < options.views; ++k) {
    const double tilt = Rad(options.min_tilt_deg + (options.max_tilt_deg - options.min_tilt_deg) * unit(random));
    const double azimuth = Rad(137.50776405003785 * k);  // the golden angle
    const double roll = options.max_roll_deg * (2.0 * unit(random) - 1.0);
    const Eigen::Vector3d aim = centre + Eigen::Vector3d(options.aim_jitter_m * (2.0 * unit(random) - 1.0),
                                                         options.aim_jitter_m * (2.0 * unit(random) - 1.0), 0.0);
    const Eigen::Vector3d out(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    StationTruth s;
    char id[32];
    std::snprintf(id, sizeof(id), "V%02d", k + 1);
    s.id = id;
    s.index_in_group = k;
    s.roll_deg = roll;
    s.velocity_direction = Eigen::Vector3d::UnitX();  // the roll's reference: the target's x axis
    s.image_from_object = AttitudeFromAxis(-out, Eigen::Vector3d::UnitX(), roll);
    s.angles = AnglesFromTMatrix(s.image_from_object);
    double distance = options.min_distance_m;
    bool fits = false;
    for (int attempt = 0; attempt < 400 && !fits; ++attempt) {
      s.position_m = aim + distance * out;
      fits = std::all_of(points.begin(), points.end(), [&](const PointTruth& p) {
        return SeenInFormat(camera, s, p.position_m, options.format_margin_mm);
      });
      if (!fits) distance *= 1.02;
    }
    if (!fits) Throw("view " + s.id + ": the target does not fit the format from any distance tried");
    stations.push_back(std::move(s));
  }
  std::vector<std::vector<int>> frames_of_point(points.size());
  for (auto& frames : frames_of_point) {
    for (int f = 0; f < options.views; ++f) frames.push_back(f);
  }

  AssembleInput in{camera, "camera", std::move(stations), std::move(points), std::move(frames_of_point),
                   options.sigma_um, options.weight_sigma_um, options.approximations, options.seed};
  PlanarTargetBlock out;
  out.block = Assemble(in);
  out.pixels = MakePixelMapping(camera, options.pixel_size_um);
  out.intrinsics = OpenCvIntrinsicsFromCamera(camera, out.pixels);

  // Per-view OpenCV lists (observations are frame-major, points in order).
  const BundleTruth& truth = out.block.truth;
  std::size_t o = 0;
  for (const StationTruth& s : truth.stations) {
    PlanarTargetView view;
    view.frame = s.id;
    view.rotation = s.image_from_object;
    view.translation_m = -(s.image_from_object * s.position_m);
    for (const PointTruth& p : truth.points) {
      const ImageObservation& noisy = out.block.input.observations[o];
      const ImageObservation& exact = truth.observations[o];
      ++o;
      view.point_ids.push_back(p.id);
      view.object_points_m.push_back(p.position_m);
      view.image_points_px.push_back(out.pixels.PixelFromPlate(Eigen::Vector2d(noisy.x_mm, noisy.y_mm)));
      view.true_image_points_px.push_back(out.pixels.PixelFromPlate(Eigen::Vector2d(exact.x_mm, exact.y_mm)));
    }
    out.views.push_back(std::move(view));
  }
  char line[300];
  std::snprintf(line, sizeof(line),
                "planar target: %d x %d points at %.0f mm, %d views, c = %.1f mm on %.1f x %.1f mm, %d x %d px of "
                "%.1f um, %zu observations, sigma %.2f um",
                options.columns, options.rows, options.spacing_m * 1e3, options.views, camera.c_mm,
                camera.format_width_mm, camera.format_height_mm, out.pixels.width_px, out.pixels.height_px,
                options.pixel_size_um, truth.observations.size(), options.sigma_um);
  out.block.summary = line;
  return out;
}

// ---------------------------------------------------------------------------
// d) Aerial block.

BundleCameraTruth AerialBlockOptions::DefaultAerialCamera() {
  BundleCameraTruth c;
  c.c_mm = 153.0;
  c.xp_mm = 0.015;
  c.yp_mm = -0.010;
  c.k1_per_mm2 = -1.0e-8;   // ~ -41 um at 160 mm
  c.k2_per_mm4 = 1.0e-13;   // ~ +10 um there
  c.k3_per_mm6 = 0.0;
  c.p1_per_mm = 2.0e-7;     // ~ 15 um at the corner
  c.p2_per_mm = -1.0e-7;
  c.b1 = 0.0;
  c.b2 = 0.0;
  c.format_width_mm = 230.0;
  c.format_height_mm = 230.0;
  return c;
}

bool AerialBlockOptions::Check(std::string* why) const {
  if (!camera.Check(why)) return false;
  if (!approximations.Check(why)) return false;
  if (strips < 1 || frames_per_strip < 2) return Fail(why, "the block needs at least 1 strip of 2 frames");
  if (!(forward_overlap >= 0.0 && forward_overlap <= 0.95) || !(side_overlap >= 0.0 && side_overlap <= 0.95)) {
    return Fail(why, "overlaps must be in [0, 0.95]");
  }
  if (!(flying_height_m > 0.0)) return Fail(why, "flying_height_m must be positive");
  if (!(tilt_deg >= 0.0 && tilt_deg < 60.0)) return Fail(why, "tilt_deg must be in [0, 60)");
  if (!std::isfinite(kappa_increment_deg)) return Fail(why, "kappa_increment_deg must be finite");
  if (points < 1) return Fail(why, "points must be at least 1");
  if (!(point_area_extension >= 0.0 && point_area_extension <= 2.0)) {
    return Fail(why, "point_area_extension must be in [0, 2]");
  }
  if (min_frames_per_point < 1 || min_frames_per_point > strips * frames_per_strip) {
    return Fail(why, "min_frames_per_point must be in 1..frames");
  }
  if (!(relief_m >= 0.0) || !(relief_m < flying_height_m)) return Fail(why, "relief_m must be in [0, flying_height_m)");
  if (!(format_margin_mm >= 0.0) ||
      !(2.0 * format_margin_mm < std::min(camera.format_width_mm, camera.format_height_mm))) {
    return Fail(why, "format_margin_mm must be >= 0 and smaller than half the format");
  }
  return CheckSigmas(sigma_um, weight_sigma_um, why);
}

SimulatedBlock SimulateAerialBlock(const AerialBlockOptions& options) {
  std::string why;
  if (!options.Check(&why)) Throw(why);
  const BundleCameraTruth& camera = options.camera;
  const double height = options.flying_height_m;
  const double footprint = std::min(camera.format_width_mm, camera.format_height_mm) / camera.c_mm * height;
  const double base = footprint * (1.0 - options.forward_overlap);
  const double spacing = footprint * (1.0 - options.side_overlap);
  const double tilt = Rad(options.tilt_deg);

  std::vector<StationTruth> stations;
  std::vector<Eigen::Vector2d> centres;  // where each optical axis meets the datum
  std::vector<double> reach;             // from the centre to the farthest corner on the lowest ground, m
  const double lowest = -0.5 * options.relief_m;
  for (int j = 0; j < options.strips; ++j) {
    const bool reverse = (j % 2) == 1;
    const double heading = reverse ? 180.0 : 0.0;
    for (int i = 0; i < options.frames_per_strip; ++i) {
      const int column = reverse ? options.frames_per_strip - 1 - i : i;
      StationTruth s;
      char id[32];
      std::snprintf(id, sizeof(id), "S%02dF%02d", j + 1, i + 1);
      s.id = id;
      s.group = j;
      s.index_in_group = i;
      s.position_m = Eigen::Vector3d(column * base, j * spacing, height);
      s.velocity_direction = Eigen::Vector3d(std::cos(Rad(heading)), std::sin(Rad(heading)), 0.0);
      const double azimuth = Rad(heading + 90.0 * (i % 4));  // forward, left, back, right
      const Eigen::Vector3d axis(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), -std::cos(tilt));
      s.roll_deg = WrapDeg(i * options.kappa_increment_deg);
      s.image_from_object = AttitudeFromAxis(axis, s.velocity_direction, s.roll_deg);
      s.angles = AnglesFromTMatrix(s.image_from_object);
      const Eigen::Vector3d centre = s.position_m + (height / std::cos(tilt)) * axis;
      double far = 0.0;
      for (double sx : {-1.0, 1.0}) {
        for (double sy : {-1.0, 1.0}) {
          const Eigen::Vector3d ray = s.image_from_object.transpose() *
                                      Eigen::Vector3d(sx * 0.5 * camera.format_width_mm, sy * 0.5 * camera.format_height_mm,
                                                      camera.c_mm);
          const Eigen::Vector3d hit = s.position_m + ((s.position_m.z() - lowest) / -ray.z()) * ray;
          far = std::max(far, (hit - centre).head<2>().norm());
        }
      }
      centres.push_back(centre.head<2>());
      reach.push_back(1.1 * far + 0.1 * footprint);
      stations.push_back(std::move(s));
    }
  }

  // Points: uniform over the stations' rectangle, kept when seen often enough.
  std::mt19937_64 placement(DeriveSeed(options.seed, Stream::kPlacement));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double extension = options.point_area_extension * footprint;
  const double x_span = (options.frames_per_strip - 1) * base + 2.0 * extension;
  const double y_span = (options.strips - 1) * spacing + 2.0 * extension;
  std::vector<PointTruth> points;
  std::vector<std::vector<int>> frames_of_point;
  std::vector<int> seen;
  const long max_attempts = 50L * options.points + 1000;
  long attempts = 0;
  while (static_cast<int>(points.size()) < options.points) {
    if (++attempts > max_attempts) {
      Throw("only " + std::to_string(points.size()) + " of " + std::to_string(options.points) +
            " points are seen by " + std::to_string(options.min_frames_per_point) + " frames");
    }
    const Eigen::Vector3d p(x_span * unit(placement) - extension, y_span * unit(placement) - extension,
                            options.relief_m * (unit(placement) - 0.5));
    seen.clear();
    for (std::size_t f = 0; f < stations.size(); ++f) {
      if ((p.head<2>() - centres[f]).norm() > reach[f]) continue;
      if (SeenInFormat(camera, stations[f], p, options.format_margin_mm)) seen.push_back(static_cast<int>(f));
    }
    if (static_cast<int>(seen.size()) < options.min_frames_per_point) continue;
    PointTruth point;
    char id[32];
    std::snprintf(id, sizeof(id), "T%05zu", points.size() + 1);
    point.id = id;
    point.position_m = p;
    points.push_back(std::move(point));
    frames_of_point.push_back(seen);
  }

  AssembleInput in{camera, "camera", std::move(stations), std::move(points), std::move(frames_of_point),
                   options.sigma_um, options.weight_sigma_um, options.approximations, options.seed};
  SimulatedBlock block = Assemble(in);
  char line[400];
  std::snprintf(line, sizeof(line),
                "aerial block: %d strips x %d frames, overlaps %.0f/%.0f %%, H = %.0f m, tilt %.0f deg, kappa %+.0f "
                "deg per frame, c = %.1f mm on %.0f x %.0f mm, %zu points, %zu observations (%.1f per point), sigma %.1f um",
                options.strips, options.frames_per_strip, 100.0 * options.forward_overlap, 100.0 * options.side_overlap,
                height, options.tilt_deg, options.kappa_increment_deg, camera.c_mm, camera.format_width_mm,
                camera.format_height_mm, block.truth.points.size(), block.truth.observations.size(),
                static_cast<double>(block.truth.observations.size()) / block.truth.points.size(), options.sigma_um);
  block.summary = line;
  return block;
}

}  // namespace platemeter::sim
