// The readers under the fuzz harness (fuzz_targets.h).
#include "fuzz/fuzz_targets.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include "platemeter/batch/scan_list.h"
#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/calib/stellar_job.h"
#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/detect/passpoint_detector.h"
#include "platemeter/grids/definition_io.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/pipeline/job_file.h"

#ifndef PLATEMETER_SOURCE_DIR
#error "PLATEMETER_SOURCE_DIR must name the source tree (the corpus is read from it)"
#endif

namespace platemeter::fuzz {
namespace fs = std::filesystem;
namespace {

fs::path CorpusDir(const std::string& name) { return fs::path(PLATEMETER_SOURCE_DIR) / "tests/fuzz/corpus" / name; }

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
  if (!out) throw std::runtime_error("fuzz: cannot write " + path.string());
}

// Memory-backed when the system has /dev/shm: a file write per input on a
// slow disk would cost more than the reader itself.
fs::path TempRoot() {
  std::error_code ec;
  if (fs::is_directory("/dev/shm", ec)) return "/dev/shm";
  return fs::temp_directory_path();
}

fs::path WorkDirPath() { return TempRoot() / ("platemeter-fuzz-" + std::to_string(::getpid())); }

// A folder of this process for the files a reader needs on disk: the job
// readers' referenced files are copied from corpus/<name>/files/.
const fs::path& WorkDir() {
  static const fs::path dir = [] {
    const fs::path d = WorkDirPath();
    fs::create_directories(d);
    for (const char* name : {"stellar_job", "bundle_job"}) {
      const fs::path files = CorpusDir(name) / "files";
      if (fs::exists(files)) fs::copy(files, d, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    }
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(WorkDirPath(), ec);
    });
    return d;
  }();
  return dir;
}

// A reader-accepted value the writer refuses or reads back differently.
[[noreturn]] void ReadBackFailed(const std::string& what) { throw std::logic_error("read back: " + what); }

template <typename Write, typename Read>
void ExpectReadsBack(const char* format, const Write& write, const Read& read) {
  std::string text;
  try {
    text = write();
  } catch (const Error& e) {
    ReadBackFailed(std::string(format) + ": the writer refuses what the reader accepted: " + e.what());
  }
  try {
    read(text);
  } catch (const Error& e) {
    ReadBackFailed(std::string(format) + ": the written text does not read back: " + e.what());
  }
}

}  // namespace

void FuzzMeasurementFile(const std::string& bytes) {
  const MeasurementFile file = ParseMeasurementFile(bytes, "fuzz.csv");
  ExpectReadsBack("measurement file", [&] { return FormatMeasurementFile(file); }, [&](const std::string& text) {
    const MeasurementFile again = ParseMeasurementFile(text, "written.csv");
    if (again.points.size() != file.points.size()) ReadBackFailed("measurement file: the point count changed");
  });
}

void FuzzDefinitions(const std::string& bytes) {
  const DefinitionFile file = ReadDefinitions(bytes, "fuzz.toml");
  for (const MasterGrid& grid : file.grids) {
    ExpectReadsBack("grid", [&] { return ToToml(grid); }, [](const std::string& text) { ReadDefinitions(text, "grid.toml"); });
  }
  for (const FiducialSet& set : file.fiducial_sets) {
    ExpectReadsBack("fiducial set", [&] { return ToToml(set); }, [](const std::string& text) { ReadDefinitions(text, "set.toml"); });
  }
  for (const CameraDefinition& camera : file.cameras) {
    ExpectReadsBack("camera", [&] { return ToToml(camera); }, [](const std::string& text) { ReadDefinitions(text, "camera.toml"); });
  }
}

void FuzzJobFile(const std::string& bytes) { pipeline::ParseJobFile(bytes, (WorkDir() / "job.toml").string()); }

void FuzzPasspointList(const std::string& bytes) { ParsePasspointList(bytes, "fuzz.csv"); }

void FuzzObservationsCsv(const std::string& bytes) {
  const std::vector<ImageObservation> observations = ParseObservationsCsv(bytes, "fuzz.csv");
  ExpectReadsBack("observations", [&] { return FormatObservationsCsv(observations); },
                  [](const std::string& text) { ParseObservationsCsv(text, "written.csv"); });
}

void FuzzGroundPointsCsv(const std::string& bytes) {
  const std::vector<GroundPoint> points = ParseGroundPointsCsv(bytes, "fuzz.csv");
  ExpectReadsBack("ground points", [&] { return FormatGroundPointsCsv(points); },
                  [](const std::string& text) { ParseGroundPointsCsv(text, "written.csv"); });
}

void FuzzScanManifest(const std::string& bytes) {
  const fs::path path = WorkDir() / "manifest.csv";
  WriteBytes(path, bytes);
  for (const ScanInput& scan : ReadScanManifest(path.string(), pipeline::JobOverrideKeys())) {
    pipeline::JobDefinition job;
    for (const auto& [key, value] : scan.overrides) pipeline::ApplyJobOverride(job, key, value);
  }
}

void FuzzStellarJob(const std::string& bytes) {
  static const DefinitionRegistry registry;
  const fs::path path = WorkDir() / "stellar.toml";
  WriteBytes(path, bytes);
  ReadStellarJob(path.string(), registry);
}

void FuzzBundleJob(const std::string& bytes) {
  const fs::path path = WorkDir() / "bundle.toml";
  WriteBytes(path, bytes);
  const BundleJob job = ReadBundleJob(path.string());
  CheckBundleInput(job.input, job.check_options);
}

void FuzzTiffHeader(const std::string& bytes) {
  // A new name per input: the image cache keys its entries by file name.
  static std::atomic<long> counter{0};
  const fs::path path = WorkDir() / ("scan-" + std::to_string(counter++) + ".tif");
  WriteBytes(path, bytes);
  struct Remove {
    fs::path path;
    ~Remove() {
      std::error_code ec;
      fs::remove(path, ec);
    }
  } remove{path};
  const Image image = Image::Open(path.string());
  const PixelRect bounds = image.Bounds();
  // The four corners and the middle, 16 x 16 px each where the image has them.
  for (const auto& [fx, fy] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}}) {
    const long x0 = static_cast<long>(fx * std::max(0L, bounds.width_px - 16));
    const long y0 = static_cast<long>(fy * std::max(0L, bounds.height_px - 16));
    const PixelRect window = image.Clip({x0, y0, 16, 16});
    if (window.width_px > 0 && window.height_px > 0) image.ReadWindow(window);
  }
  if (bounds.width_px > 0 && bounds.width_px <= 4096 && bounds.height_px > 0) {
    std::vector<float> row(static_cast<size_t>(bounds.width_px) * std::min(bounds.height_px, 2L));
    image.ReadRowsDirect(0, std::min(bounds.height_px, 2L), row.data());
  }
}

const std::vector<FuzzTarget>& AllTargets() {
  static const std::vector<FuzzTarget> targets = {
      {"measurement_file", FuzzMeasurementFile},   {"definitions", FuzzDefinitions},
      {"job_file", FuzzJobFile},                   {"passpoint_list", FuzzPasspointList},
      {"observations_csv", FuzzObservationsCsv},   {"ground_points_csv", FuzzGroundPointsCsv},
      {"scan_manifest", FuzzScanManifest},         {"stellar_job", FuzzStellarJob},
      {"bundle_job", FuzzBundleJob},               {"tiff_header", FuzzTiffHeader, true, true}};
  return targets;
}

const FuzzTarget& TargetNamed(const std::string& name) {
  for (const FuzzTarget& t : AllTargets()) {
    if (t.name == name) return t;
  }
  throw std::invalid_argument("no fuzz target '" + name + "'");
}

namespace {

// Small scans of every kind the writer makes: 8/16-bit and float, tiled and
// striped, compressed or not, with and without resolution tags.
std::vector<std::string> TiffSeeds() {
  std::vector<std::string> seeds;
  const SampleType types[] = {SampleType::kUint8, SampleType::kUint16, SampleType::kFloat32};
  int n = 0;
  for (SampleType type : types) {
    for (int tile : {0, 16}) {
      for (const char* compression : {"none", "zip"}) {
        ImageWriterOptions options;
        options.width_px = 40;
        options.height_px = 24;
        options.sample_type = type;
        options.tile_size_px = tile;
        options.compression = compression;
        if (n % 2) options.pixel_size_um = 12.5;
        std::vector<float> values(40 * 24);
        for (size_t i = 0; i < values.size(); ++i) values[i] = static_cast<float>((i * 37) % 251);
        const fs::path path = WorkDir() / ("seed-" + std::to_string(n++) + ".tif");
        WriteImage(path.string(), options, values.data());
        seeds.push_back(ReadBytes(path));
        fs::remove(path);
      }
    }
  }
  return seeds;
}

}  // namespace

std::vector<std::string> SeedsOf(const FuzzTarget& target) {
  if (target.name == "tiff_header") return TiffSeeds();
  std::vector<std::string> seeds;
  std::vector<fs::path> files;
  if (fs::exists(CorpusDir(target.name))) {
    for (const auto& entry : fs::directory_iterator(CorpusDir(target.name))) {
      if (entry.is_regular_file() && entry.path().filename().string().rfind("seed", 0) == 0) files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());  // the same order everywhere: runs repeat
  for (const fs::path& file : files) seeds.push_back(ReadBytes(file));
  if (target.name == "definitions") {
    for (const auto& [origin, text] : BuiltinDefinitionTexts()) seeds.push_back(text);
  }
  return seeds;
}

}  // namespace platemeter::fuzz
