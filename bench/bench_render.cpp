// Renders a full simulated plate band by band through core's ImageWriter
// (tiled TIFF, 256 px tiles, zip) and prints wall time, Mpixel/s and peak RSS.
// The bar: a 16000 x 16000 16-bit plate with peak RSS under 600 MB.
//   bench_render [--size N] [--out DIR] [--keep]
// The scene: an 11 x 11 grid of reseau crosses filling the plate (600 um
// crosses, 5 um/px scan, scanner rotated 1.5 mrad), four corner fiducials and
// four dot fiducials, stars, duty-cycle trail dashes, dust, scratches, false
// marks, a terrain-like background with vignetting, blur, sensor and grain noise.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <algorithm>
#include <filesystem>
#include <future>
#include <string>
#include <vector>

#include "platemeter/core/image_writer.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/render_crb.h"

namespace {

using platemeter::sim::MarkKind;
using platemeter::sim::MarkShapeKind;
using platemeter::sim::Scene;
using platemeter::sim::SceneMark;

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

struct Lcg {  // a tiny deterministic generator for the scene layout
  uint64_t state;
  double Uniform() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return (state >> 11) * (1.0 / 9007199254740992.0);
  }
};

Scene MakeScene(long size_px) {
  Scene scene;
  scene.width_px = size_px;
  scene.height_px = size_px;
  scene.background.level_dn = 30000.0;
  scene.background.terrain_amplitude_dn = 1500.0;
  scene.background.terrain_scale_px = size_px / 8.0;
  scene.background.vignetting_fraction = 0.12;
  scene.background.optical_centre_px = {0.5 * size_px, 0.5 * size_px};
  scene.background.vignetting_radius_px = 0.5 * std::sqrt(2.0) * size_px;
  scene.noise.scanner_blur_sigma_px = 0.6;
  scene.noise.sensor_sigma_dn = 20.0;
  scene.noise.grain_sigma_dn = 30.0;
  scene.noise.seed = 2026;

  const double scale = 0.2, rotation = 0.0015;  // px/um (5 um/px), rad
  auto frame = [&](SceneMark* mark) {
    mark->px_from_um[0] = scale * std::cos(rotation), mark->px_from_um[1] = scale * std::sin(rotation);
    mark->px_from_um[2] = scale * std::sin(rotation), mark->px_from_um[3] = -scale * std::cos(rotation);
  };
  Lcg rng{12345};
  const double spacing = size_px / 11.0;
  for (int j = 0; j < 11; ++j)
    for (int i = 0; i < 11; ++i) {
      SceneMark cross;
      cross.id = "X" + std::to_string(i + 1) + "Y" + std::to_string(11 - j);
      cross.kind = MarkKind::kReseauCross;
      cross.shape = MarkShapeKind::kCross;
      cross.centre_px = {(i + 0.5) * spacing + rng.Uniform() - 0.5, (j + 0.5) * spacing + rng.Uniform() - 0.5};
      cross.size_um = std::min(600.0, 0.8 * spacing / scale);
      cross.line_width_um = 20.0;
      cross.amplitude_dn = -9000.0;
      if ((i * 7 + j * 3) % 17 == 0) cross.damage_fraction = 0.3, cross.seed = i * 11 + j;
      frame(&cross);
      scene.marks.push_back(cross);
    }
  for (int k = 0; k < 4; ++k) {
    const double sx = (k & 1) ? 1.0 : -1.0, sy = (k & 2) ? 1.0 : -1.0;
    SceneMark corner;
    corner.id = "corner" + std::to_string(k + 1);
    corner.kind = MarkKind::kFiducial;
    corner.shape = MarkShapeKind::kCorner;
    corner.centre_px = {0.5 * size_px + sx * 0.47 * size_px, 0.5 * size_px + sy * 0.47 * size_px};
    corner.size_um = 1000.0;
    corner.line_width_um = 40.0;
    corner.corner_angle_rad = std::atan2(sy, -sx);  // bisector toward the plate centre (v up)
    corner.amplitude_dn = -12000.0;
    frame(&corner);
    scene.marks.push_back(corner);
    SceneMark dot = corner;
    dot.id = "dot" + std::to_string(k + 1);
    dot.shape = k % 2 ? MarkShapeKind::kDot : MarkShapeKind::kRing;
    dot.centre_px = {0.5 * size_px + sx * 0.49 * size_px, 0.5 * size_px};
    if (k >= 2) dot.centre_px = {0.5 * size_px, 0.5 * size_px + sx * 0.49 * size_px};
    dot.size_um = 200.0;
    scene.marks.push_back(dot);
  }
  const long area_mpx = std::max(1L, size_px * size_px / 1000000);
  auto random_point = [&] { return platemeter::PixelPoint{rng.Uniform() * size_px, rng.Uniform() * size_px}; };
  for (long k = 0; k < 8 * area_mpx; ++k) {  // ~2000 stars on a 16k plate
    SceneMark star;
    star.id = "star" + std::to_string(k);
    star.kind = MarkKind::kStar;
    star.shape = MarkShapeKind::kPsf;
    star.centre_px = random_point();
    star.psf_fwhm_um = 15.0;
    star.amplitude_dn = 20000.0 * std::exp(3.0 * rng.Uniform());
    frame(&star);
    scene.marks.push_back(star);
  }
  for (long k = 0; k < area_mpx; ++k) {  // trail dashes
    SceneMark dash;
    dash.id = "dash" + std::to_string(k);
    dash.kind = MarkKind::kTrailDash;
    dash.shape = MarkShapeKind::kSegment;
    dash.centre_px = random_point();
    dash.psf_fwhm_um = 15.0;
    dash.segment_u_um = 300.0;
    dash.segment_v_um = 80.0;
    dash.amplitude_dn = 300000.0;
    frame(&dash);
    scene.marks.push_back(dash);
  }
  for (long k = 0; k < std::max(1L, area_mpx / 8); ++k) {
    SceneMark dust;
    dust.id = "dust" + std::to_string(k);
    dust.kind = MarkKind::kDust;
    dust.centre_px = random_point();
    dust.size_um = 50.0 + 200.0 * rng.Uniform();
    dust.amplitude_dn = rng.Uniform() < 0.5 ? -5000.0 : 4000.0;
    frame(&dust);
    scene.marks.push_back(dust);
    SceneMark false_mark = dust;
    false_mark.id = "false" + std::to_string(k);
    false_mark.kind = MarkKind::kFalseMark;
    false_mark.shape = MarkShapeKind::kCross;
    false_mark.centre_px = random_point();
    false_mark.size_um = 300.0;
    false_mark.line_width_um = 15.0;
    false_mark.amplitude_dn = -6000.0;
    scene.marks.push_back(false_mark);
  }
  for (long k = 0; k < std::max(1L, area_mpx / 50); ++k) {
    SceneMark scratch;
    scratch.id = "scratch" + std::to_string(k);
    scratch.kind = MarkKind::kScratch;
    scratch.centre_px = random_point();
    scratch.size_um = 0.3 * size_px / scale;
    scratch.line_width_um = 4.0;
    scratch.corner_angle_rad = M_PI * rng.Uniform();
    scratch.amplitude_dn = 3000.0;
    frame(&scratch);
    scene.marks.push_back(scratch);
  }
  return scene;
}

}  // namespace

int main(int argc, char** argv) {
  long size_px = 16000;
  std::string out_dir;
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--size" && i + 1 < argc) {
      size_px = std::atol(argv[++i]);
    } else if (arg == "--out" && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (arg == "--keep") {
      keep = true;
    } else {
      std::fprintf(stderr, "usage: bench_render [--size N] [--out DIR] [--keep]\n");
      return 2;
    }
  }
  if (size_px < 64) {
    std::fprintf(stderr, "bench_render: --size must be >= 64\n");
    return 2;
  }
  namespace fs = std::filesystem;
  const bool own_dir = out_dir.empty();
  if (own_dir) out_dir = (fs::temp_directory_path() / ("bench_render_" + std::to_string(::getpid()))).string();
  fs::create_directories(out_dir);
  const std::string path = (fs::path(out_dir) / "plate.tif").string();

  try {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    const Scene scene = MakeScene(size_px);
    const platemeter::sim::SceneRenderer renderer(scene);
    const auto t1 = Clock::now();

    platemeter::ImageWriterOptions options;
    options.width_px = size_px;
    options.height_px = size_px;
    options.sample_type = platemeter::SampleType::kUint16;
    options.tile_size_px = 256;
    options.compression = "zip";
    options.pixel_size_um = 5.0;
    platemeter::ImageWriter writer(path, options);
    const long band = writer.band_height_px();
    // Two buffers: band k is written (serial compression) while band k+1 renders (all cores).
    std::vector<float> buffers[2] = {std::vector<float>(band * size_px), std::vector<float>(band * size_px)};
    double render_s = 0.0;
    std::future<void> writing;
    int which = 0;
    for (long y0 = 0; y0 < size_px; y0 += band, which ^= 1) {
      const long rows = std::min(band, size_px - y0);
      const auto r0 = Clock::now();
      renderer.RenderBand(y0, rows, buffers[which].data());
      render_s += std::chrono::duration<double>(Clock::now() - r0).count();
      if (writing.valid()) writing.get();
      writing = std::async(std::launch::async,
                           [&writer, y0, rows, data = buffers[which].data()] { writer.WriteBand(y0, rows, data); });
    }
    if (writing.valid()) writing.get();
    writer.Finish();
    const auto t2 = Clock::now();

    // The bound of every mark (what detectors are scored against).
    const auto bounds = platemeter::sim::CramerRaoBounds(scene);
    const auto t3 = Clock::now();
    double median_cross_sigma = 0.0;
    {
      std::vector<double> sigmas;
      for (size_t i = 0; i < scene.marks.size(); ++i)
        if (scene.marks[i].kind == MarkKind::kReseauCross && bounds[i].valid) sigmas.push_back(bounds[i].sigma_x_px);
      std::nth_element(sigmas.begin(), sigmas.begin() + sigmas.size() / 2, sigmas.end());
      median_cross_sigma = sigmas.empty() ? 0.0 : sigmas[sigmas.size() / 2];
    }

    const double setup_s = std::chrono::duration<double>(t1 - t0).count();
    const double write_s = std::chrono::duration<double>(t2 - t1).count();
    const double crb_s = std::chrono::duration<double>(t3 - t2).count();
    const double mpx = static_cast<double>(size_px) * size_px / 1e6;
    std::printf("bench_render: %ld x %ld px, %zu marks, 16-bit tiled TIFF (256 px, zip): %s\n", size_px, size_px,
                scene.marks.size(), path.c_str());
    std::printf("  scene + mark models:       %8.2f s\n", setup_s);
    std::printf("  render + write (wall):     %8.2f s  = %.1f Mpixel/s (render alone %.2f s, %.1f Mpixel/s)\n",
                write_s, mpx / write_s, render_s, mpx / render_s);
    std::printf("  Cramer-Rao bounds (all):   %8.2f s  (median reseau cross sigma_x %.4f px)\n", crb_s,
                median_cross_sigma);
    std::printf("  file size:                 %8.1f MB\n", fs::file_size(path) / 1e6);
    std::printf("  peak RSS:                  %8.1f MB\n", PeakRssMb());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_render: %s\n", e.what());
    return 1;
  }
  if (!keep) {
    if (own_dir) fs::remove_all(out_dir);
    else fs::remove(path);
  }
  return 0;
}
