// `platemeter batch` over an archive of scans each larger than the image cache:
// throughput (scans per hour) and the batch process's peak RSS, against one
// `platemeter measure` of a single scan.
//
//   bench_batch [--scans 20] [--pixel-um 20] [--cache-mb 32] [--jobs 2] [--keep DIR]
//
// The scans are simulated SN-004 terrain plates (Ikogon B, 121 crosses, eight
// fiducials, terrain background, 16-bit, zip-compressed tiles), each with its
// own seed. At 20 um a plate is about 6300 x 6300 px: 79 MB of 16-bit pixels,
// over twice the 32 MB cache. The batch runs as its own process, so the time
// and the peak RSS (wait4's ru_maxrss) are the tool's alone.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_process.h"
#include "platemeter/batch/scan_record.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace {

using platemeter::bench::RunProcess;
using platemeter::bench::ToolRun;

namespace fs = std::filesystem;
using namespace platemeter;

std::string SpecText(double pixel_um, int seed) {
  std::ostringstream s;
  s << "name = \"bench-batch\"\ncamera = \"sn004-terrain\"\nseed = " << seed << "\n"
    << "[output]\npixel_size_um = " << pixel_um << "\nmargin_mm = 2.0\nbits = 16\ntile_size_px = 256\n"
    << "compression = \"zip\"\n"
    << "[thermal]\ntemperature_degC = 22.0\ncalibration_temperature_degC = 20.0\n"
    << "[emulsion]\ndepth_um = 8.0\nrefractive_index = 1.65\n"
    << "[film]\naffine_ppm = [45.0, 6.0, -4.0, -30.0]\nshift_um = [1.5, -2.0]\n"
    << "[scanner]\nrotation_deg = 0.25\nnon_orthogonality_arcsec = 12.0\noffset_px = [3.3, -2.7]\n"
    << "[marks.reseau]\npolarity = \"dark\"\ncontrast_dn = 14000.0\n"
    << "[marks.fiducials]\npolarity = \"bright\"\ncontrast_dn = 16000.0\n"
    << "[background]\nlevel_dn = 26000.0\nterrain_amplitude_dn = 5000.0\nterrain_scale_mm = 15.0\n"
    << "vignetting_fraction = 0.08\nvignetting_radius_mm = 80.0\n"
    << "[noise]\nblur_sigma_um = 6.0\nsensor_sigma_dn = 150.0\ngrain_sigma_dn = 250.0\n"
    << "[defects]\ndust_count = 6\nscratch_count = 1\n";
  return s.str();
}


}  // namespace

int main(int argc, char** argv) {
  int scans = 20, jobs = 2;
  double pixel_um = 20.0, cache_mb = 32.0;
  std::string keep;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_batch: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--scans") scans = std::stoi(next());
    else if (a == "--pixel-um") pixel_um = std::stod(next());
    else if (a == "--cache-mb") cache_mb = std::stod(next());
    else if (a == "--jobs") jobs = std::stoi(next());
    else if (a == "--keep") keep = next();
    else {
      std::fprintf(stderr, "usage: bench_batch [--scans 20] [--pixel-um 20] [--cache-mb 32] [--jobs 2] [--keep DIR]\n");
      return 2;
    }
  }
  const fs::path root = keep.empty() ? fs::temp_directory_path() / ("bench_batch-" + std::to_string(::getpid())) : fs::path(keep);
  const fs::path in = root / "scans", out = root / "out", single = root / "single", gen = root / "gen";
  fs::create_directories(in);
  fs::remove_all(out);
  fs::remove_all(single);

  // The archive: one simulated plate per seed, rendered band by band (bounded memory).
  const DefinitionRegistry registry = DefinitionRegistry::Load({});
  long width = 0, height = 0;
  int rendered = 0;
  const auto render_start = std::chrono::steady_clock::now();
  for (int k = 1; k <= scans; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "plate-%03d.tif", k);
    const sim::SimulationSpec spec = sim::ParseSimulationSpec(SpecText(pixel_um, 1000 + k), "bench_batch");
    sim::SimulatedPlate plate = sim::BuildSimulatedPlate(spec, registry, {});
    width = plate.scene.width_px;
    height = plate.scene.height_px;
    if (fs::exists(in / name)) continue;
    fs::remove_all(gen);
    const sim::SimulateOutputs o = sim::WriteSimulatedPlate(std::move(plate), gen.string());
    fs::rename(o.image_path, in / name);
    ++rendered;
  }
  fs::remove_all(gen);
  const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - render_start).count();
  const double pixels_mb = 2.0 * width * height / 1048576.0;
  uintmax_t file_bytes = 0;
  for (const auto& e : fs::directory_iterator(in)) file_bytes += e.file_size();
  std::printf("archive: %d simulated SN-004 terrain scans, %ld x %ld px at %g um, 16-bit: %.0f MB of pixels each "
              "(%.0f MB zip-compressed on disk in all; %d rendered now in %.0f s); image cache %g MB\n",
              scans, width, height, pixel_um, pixels_mb, file_bytes / 1048576.0, rendered, render_s, cache_mb);

  const std::string bin = PLATEMETER_BIN, cache = std::to_string(cache_mb);
  const ToolRun one = RunProcess({bin, "--cache-mb", cache, "measure", (in / "plate-001.tif").string(), "--camera",
                                  "sn004-terrain", "-o", single.string()},
                                 (root / "single.log").string());
  std::printf("single scan (platemeter measure): %.2f s wall, %.2f s CPU, peak RSS %.0f MB, exit %d\n", one.seconds,
              one.cpu_seconds, one.peak_rss_mb, one.exit_code);

  const ToolRun batch = RunProcess({bin, "--cache-mb", cache, "batch", in.string(), "-o", out.string(), "--camera",
                                    "sn004-terrain", "--jobs", std::to_string(jobs)},
                                   (root / "batch.log").string());
  int ok = 0;
  for (const ScanRecord& r : ReadAllRecords(out.string())) ok += r.status == "ok";
  std::printf("batch --jobs %d: %d scans (%d ok) in %.1f s wall, %.1f s CPU: %.0f scans/hour, %.2f s per scan; "
              "peak RSS %.0f MB; exit %d\n",
              jobs, scans, ok, batch.seconds, batch.cpu_seconds, 3600.0 * scans / batch.seconds,
              batch.seconds / scans, batch.peak_rss_mb, batch.exit_code);
  std::printf("speed-up over single runs in a row: %.2f (on %u cores)\n", one.seconds * scans / batch.seconds,
              std::thread::hardware_concurrency());
  const ToolRun rerun = RunProcess({bin, "--cache-mb", cache, "batch", in.string(), "-o", out.string(), "--camera",
                                    "sn004-terrain", "--jobs", std::to_string(jobs)},
                                   (root / "rerun.log").string());
  std::printf("rerun (every scan current, skipped): %.2f s, exit %d\n", rerun.seconds, rerun.exit_code);
  if (keep.empty()) fs::remove_all(root);
  return ok == scans && batch.exit_code == 0 ? 0 : 1;
}
