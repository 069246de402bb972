#pragma once
// Scan access through one shared OpenImageIO ImageCache: windows are read tile
// by tile under a memory limit, so a scan larger than RAM can be measured.
// Values come back as grayscale float in the file's own digital numbers (DN):
// 0..255 for 8-bit, 0..65535 for 16-bit, as stored for float. RGB is converted
// to luminance (Rec. 709 weights) with a warning.
#include <optional>
#include <string>
#include <vector>

#include "platemeter/core/pixel.h"

namespace platemeter {

struct ImageCacheOptions {
  double max_memory_mb = 256.0;  // MB; the cache's tile memory, shared by all open scans
  int autotile_px = 512;         // px; tile size used to cache untiled (striped) files
  int max_open_files = 100;      // files kept open at once by the cache
  bool Check(std::string* why) const;
};

// Applies to the shared cache from now on (throws Error if the options are invalid).
void ConfigureImageCache(const ImageCacheOptions& options);
// Tile memory the cache holds now, in MB (for benchmarks and reports).
double ImageCacheMemoryUsedMb();

enum class SampleType { kUint8, kUint16, kFloat32 };
const char* SampleTypeName(SampleType type);

struct ImageInfo {
  std::string path;
  std::string format_name;  // OpenImageIO's name: "tiff", "png", "jpeg", "fits", ...
  long width_px = 0;
  long height_px = 0;
  int channels = 1;            // in the file; windows are always one channel
  SampleType sample_type = SampleType::kUint8;
  double full_scale_dn = 255;  // 255, 65535, or 1 for float
  bool tiled = false;
  int tile_width_px = 0;
  int tile_height_px = 0;
  std::string compression;     // as OpenImageIO names it ("none", "lzw", "zip", ...)
  // From the TIFF resolution tags (inch or centimetre units only); empty otherwise.
  std::optional<double> pixel_size_x_um;
  std::optional<double> pixel_size_y_um;
};

// A grayscale window in DN, row-major, addressed with absolute pixel indices.
struct ImageWindow {
  PixelRect rect;
  std::vector<float> values_dn;
  float at(long col, long row) const {
    return values_dn[static_cast<size_t>((row - rect.y0_px) * rect.width_px + (col - rect.x0_px))];
  }
};

class Image {
 public:
  // Opens a scan and probes its last tile, so that a truncated file fails here
  // rather than half-way through a measurement. Throws Error on bad input.
  static Image Open(const std::string& path);

  const ImageInfo& info() const { return info_; }
  PixelRect Bounds() const { return {0, 0, info_.width_px, info_.height_px}; }
  // Clips a rectangle to the image (may return an empty rectangle).
  PixelRect Clip(const PixelRect& rect) const;

  // Reads a window lying inside the image; throws Error otherwise or on a read failure.
  ImageWindow ReadWindow(const PixelRect& rect) const;
  void ReadWindowInto(const PixelRect& rect, float* values_dn) const;

  // Reads whole rows [y0_px, y0_px + rows) through a private reader, bypassing
  // the cache: for streaming passes that touch every pixel once. OpenImageIO's
  // cache decodes one file's tiles one at a time; private readers on separate
  // threads decode in parallel. Rows are best aligned to rows_alignment_px()
  // (each call decodes the tile rows it touches).
  void ReadRowsDirect(long y0_px, long rows, float* values_dn) const;
  // The tile height of a tiled file, else 1.
  long rows_alignment_px() const { return info_.tiled ? info_.tile_height_px : 1; }

 private:
  ImageInfo info_;
};

// The pixel size to use: the user's value if given, else the file's resolution
// tags; throws Error naming the file when neither is there.
double ResolvePixelSizeUm(const ImageInfo& info, std::optional<double> user_pixel_size_um);

}  // namespace platemeter
