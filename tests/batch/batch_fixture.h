#pragma once
// The archive the batch CLI tests run on: 40 small simulated reseau scans (a 5 x 5 test
// camera, 80 um pixels, each its own seed), three of them bad (a truncated TIFF, bytes that
// are no image, a scan of another camera). Rendered once and kept in the build tree
// (<build>/batch-test-fixture/<key>/), so the test processes ctest starts share it; the key
// changes with this test binary, so a rebuilt simulator renders it anew.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace platemeter::batch_test {

namespace fs = std::filesystem;

inline constexpr const char* kDefinitions = R"toml(
[[grid]]
name = "batchtest-grid"
description = "5 x 5 nominal reseau, 10 mm (batch tests)"
source = "nominal, made up for the batch tests"
columns = 5
rows = 5
spacing_mm = 10.0
mark = { type = "cross", line_width_um = 60.0, arm_length_um = 1500.0 }

[[grid]]
name = "batchtest-wide-grid"
description = "5 x 5 nominal reseau, 13 mm (batch tests: the wrong camera)"
source = "nominal, made up for the batch tests"
columns = 5
rows = 5
spacing_mm = 13.0
mark = { type = "cross", line_width_um = 60.0, arm_length_um = 1500.0 }

[[camera]]
name = "batchtest"
description = "a small reseau camera for the batch tests"
source = "made up for the batch tests"
format_width_mm = 50.0
format_height_mm = 50.0
nominal_principal_distance_mm = 100.0
grid = "batchtest-grid"

[[camera]]
name = "batchtest-wide"
description = "another small reseau camera (the wrong one for the batch tests)"
source = "made up for the batch tests"
format_width_mm = 64.0
format_height_mm = 64.0
nominal_principal_distance_mm = 100.0
grid = "batchtest-wide-grid"
)toml";

inline std::string SpecText(const std::string& camera, int seed) {
  return "name = \"plate\"\ncamera = \"" + camera + "\"\nseed = " + std::to_string(seed) +
         "\n[output]\npixel_size_um = 80.0\nmargin_mm = 2.0\nbits = 16\ntile_size_px = 256\ncompression = \"zip\"\n"
         "[thermal]\ntemperature_degC = 22.0\ncalibration_temperature_degC = 20.0\n"
         "[film]\naffine_ppm = [45.0, 6.0, -4.0, -30.0]\n"
         "[scanner]\nrotation_deg = 0.25\noffset_px = [3.3, -2.7]\n"
         "[marks.reseau]\npolarity = \"dark\"\ncontrast_dn = 14000.0\n"
         "[background]\nlevel_dn = 26000.0\n"
         "[noise]\nblur_sigma_um = 20.0\nsensor_sigma_dn = 150.0\ngrain_sigma_dn = 250.0\n";
}

inline constexpr int kScans = 40;
inline constexpr int kTruncated = 7, kNotAnImage = 19, kWrongCamera = 31;

struct Fixture {
  fs::path root;         // the fixture's folder
  std::string defs;      // the definition file (cameras batchtest, batchtest-wide)
  std::string scans;     // the folder of the 40 scans plate-00.tif .. plate-39.tif
  std::vector<std::string> names;  // plate-00 .. plate-39 (stems), sorted
  bool IsBad(int i) const { return i == kTruncated || i == kNotAnImage || i == kWrongCamera; }
  std::string Scan(int i) const { return (fs::path(scans) / (names[i] + ".tif")).string(); }
};

inline std::string Name(int i) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "plate-%02d", i);
  return buffer;
}

inline void Render(const std::string& camera, int seed, const DefinitionRegistry& registry, const fs::path& work,
                   const fs::path& target) {
  const sim::SimulationSpec spec = sim::ParseSimulationSpec(SpecText(camera, seed), "batch fixture");
  const sim::SimulateOutputs out =
      sim::WriteSimulatedPlate(sim::BuildSimulatedPlate(spec, registry, {}), work.string());
  fs::rename(out.image_path, target);
  fs::remove_all(work);
}

inline const Fixture& GetFixture() {
  static const Fixture fixture = [] {
    Fixture f;
    struct stat self {};
    ::stat("/proc/self/exe", &self);
    const std::string key = "v1-" + std::to_string(self.st_size) + "-" + std::to_string(self.st_mtim.tv_sec) + "-" +
                            std::to_string(self.st_mtim.tv_nsec);
    const fs::path base = fs::path(PLATEMETER_BIN).parent_path().parent_path() / "batch-test-fixture";
    f.root = base / key;
    f.defs = (f.root / "batchtest.toml").string();
    f.scans = (f.root / "scans").string();
    for (int i = 0; i < kScans; ++i) f.names.push_back(Name(i));
    if (fs::exists(f.root / "complete")) return f;

    // Render into a private folder, then rename it into place: a concurrent test process
    // either wins the rename or throws its copy away.
    fs::create_directories(base);
    const fs::path work = base / (".render-" + std::to_string(::getpid()));
    fs::remove_all(work);
    fs::create_directories(work / "scans");
    std::ofstream(work / "batchtest.toml") << kDefinitions;
    const DefinitionRegistry registry = DefinitionRegistry::Load({(work / "batchtest.toml").string()});
    auto render_range = [&](int first) {
      for (int i = first; i < kScans; i += 2) {
        const fs::path target = work / "scans" / (Name(i) + ".tif");
        const fs::path tmp = work / ("sim-" + std::to_string(i));
        if (i == kNotAnImage) {
          std::ofstream out(target, std::ios::binary);
          for (int k = 0; k < 200; ++k) out << "this is a scanner's log, not an image\n";
        } else if (i == kWrongCamera) {
          Render("batchtest-wide", 1000 + i, registry, tmp, target);
        } else {
          Render("batchtest", 1000 + i, registry, tmp, target);
          if (i == kTruncated) fs::resize_file(target, fs::file_size(target) * 6 / 10);
        }
      }
    };
    std::thread other(render_range, 1);
    render_range(0);
    other.join();
    std::ofstream(work / "complete") << "rendered\n";
    std::error_code ec;
    fs::rename(work, f.root, ec);
    if (ec) fs::remove_all(work);  // another process was first
    // Fixtures of earlier builds.
    for (const auto& e : fs::directory_iterator(base)) {
      const std::string n = e.path().filename().string();
      if (n != key && n.rfind(".render-", 0) != 0) fs::remove_all(e.path(), ec);
    }
    if (!fs::exists(f.root / "complete")) throw Error(f.root.string(), "the batch test fixture was not rendered");
    return f;
  }();
  return fixture;
}

}  // namespace platemeter::batch_test
