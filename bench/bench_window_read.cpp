// Reads random windows from a large 16-bit tiled TIFF through platemeter's
// shared image cache and prints time and peak memory, then does the same job
// the way a whole-image tool does (OpenCV imread) in a child process, so the
// two peak RSS figures do not mix.
//
//   bench_window_read [--size PX] [--windows N] [--window PX] [--cache-mb MB] [--dir DIR] [--no-peer]
//
// The scan is written once to DIR (default: the system temp folder) and reused.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"

namespace {

double PeakRssMb(int who) {
  rusage usage{};
  getrusage(who, &usage);
  return usage.ru_maxrss / 1024.0;
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void WriteTestScan(const std::string& path, long size_px) {
  platemeter::ImageWriterOptions options;
  options.width_px = options.height_px = size_px;
  options.sample_type = platemeter::SampleType::kUint16;
  options.tile_size_px = 256;
  options.compression = "zip";
  options.pixel_size_um = 5.0;
  platemeter::ImageWriter writer(path, options);
  std::vector<float> band(static_cast<size_t>(size_px) * writer.band_height_px());
  std::mt19937 random(7);
  std::uniform_real_distribution<float> noise(-200.0f, 200.0f);
  for (long y = 0; y < size_px; y += writer.band_height_px()) {
    const long rows = std::min<long>(writer.band_height_px(), size_px - y);
    for (long r = 0; r < rows; ++r)
      for (long x = 0; x < size_px; ++x)
        band[static_cast<size_t>(r * size_px + x)] = 30000.0f + 0.5f * ((x + y + r) % 4000) + noise(random);
    writer.WriteBand(y, rows, band.data());
  }
  writer.Finish();
}

std::vector<platemeter::PixelRect> RandomWindows(long size_px, long window_px, int count) {
  std::mt19937 random(42);
  std::uniform_int_distribution<long> corner(0, size_px - window_px);
  std::vector<platemeter::PixelRect> windows;
  for (int i = 0; i < count; ++i) windows.push_back({corner(random), corner(random), window_px, window_px});
  return windows;
}

}  // namespace

int main(int argc, char** argv) {
  long size_px = 20000, window_px = 256;
  int count = 500;
  double cache_mb = 256.0;
  bool peer = true;
  std::string dir = std::filesystem::temp_directory_path().string();
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (arg == "--size") size_px = std::stol(next());
    else if (arg == "--windows") count = std::stoi(next());
    else if (arg == "--window") window_px = std::stol(next());
    else if (arg == "--cache-mb") cache_mb = std::stod(next());
    else if (arg == "--dir") dir = next();
    else if (arg == "--no-peer") peer = false;
    else {
      std::fprintf(stderr, "usage: %s [--size PX] [--windows N] [--window PX] [--cache-mb MB] [--dir DIR] [--no-peer]\n", argv[0]);
      return 2;
    }
  }
  const std::string path = dir + "/bench_window_read_" + std::to_string(size_px) + ".tif";
  if (!std::filesystem::exists(path)) {
    const auto start = std::chrono::steady_clock::now();
    WriteTestScan(path, size_px);
    std::printf("wrote %s (%ld x %ld, 16-bit, tiled 256, zip, %.0f MB on disk) in %.1f s\n", path.c_str(), size_px,
                size_px, std::filesystem::file_size(path) / 1048576.0, Seconds(start));
  }
  const auto windows = RandomWindows(size_px, window_px, count);
  const double raw_mb = size_px * static_cast<double>(size_px) * 2 / 1048576.0;

  // Peer first, in a child, so its memory never counts against ours.
  if (peer) {
    std::fflush(stdout);
    const pid_t child = fork();
    if (child == 0) {
      const auto start = std::chrono::steady_clock::now();
      cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
      if (image.empty()) _exit(3);
      double sum = 0;
      for (const auto& w : windows) sum += cv::sum(image(cv::Rect(w.x0_px, w.y0_px, w.width_px, w.height_px)))[0];
      std::printf("peer (OpenCV imread whole image, then windows): %.2f s, checksum %.0f\n", Seconds(start), sum);
      std::fflush(stdout);
      _exit(0);
    }
    int status = 0;
    rusage usage{};
    wait4(child, &status, 0, &usage);
    std::printf("peer peak RSS: %.0f MB%s\n", usage.ru_maxrss / 1024.0,
                WIFEXITED(status) && WEXITSTATUS(status) == 0 ? "" : " (peer failed)");
  }

  platemeter::ImageCacheOptions cache;
  cache.max_memory_mb = cache_mb;
  platemeter::ConfigureImageCache(cache);
  const auto start = std::chrono::steady_clock::now();
  const platemeter::Image image = platemeter::Image::Open(path);
  std::vector<float> values(static_cast<size_t>(window_px * window_px));
  double sum = 0;
  for (const auto& w : windows) {
    image.ReadWindowInto(w, values.data());
    for (float v : values) sum += v;
  }
  const double seconds = Seconds(start);
  std::printf("platemeter: %d windows of %ld x %ld from %ld x %ld 16-bit (%.0f MB raw) in %.2f s (%.1f windows/s), "
              "checksum %.0f\n", count, window_px, window_px, size_px, size_px, raw_mb, seconds, count / seconds, sum);
  std::printf("platemeter peak RSS: %.0f MB (cache limit %.0f MB, cache now %.0f MB)\n", PeakRssMb(RUSAGE_SELF),
              cache_mb, platemeter::ImageCacheMemoryUsedMb());
  return 0;
}
