#pragma once
// Scan access through one shared OpenImageIO ImageCache: windows are read tile
// by tile under a memory limit, so a scan larger than RAM can be measured.
// Values come back as grayscale float in the file's own digital numbers (DN):
// 0..255 for 8-bit, 0..65535 for 16-bit, as stored for float. RGB is converted
// to luminance (Rec. 709 weights) with a warning.
//
// Masked pixels: a float scan's sample that is NaN, infinite, or larger in
// magnitude than kMaxPixelMagnitudeDn is missing data, not a value; every read
// returns it as NaN (the one marker the detectors skip), so no estimate or fit
// ever uses it. Integer scans have no masked pixels (and pay nothing for the rule).
#include <cmath>
#include <cstddef>
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

// DN; a float sample beyond this magnitude is a fill or no-data marker, never an
// intensity: masked. Above any count a scanner writes (even 32-bit counts stay
// below 4.3e9), below the fill values in use (1e20, the CF/CMIP missing_value;
// 9.97e36, netCDF's default fill; -3.4e38, float's lowest, as GDAL writes it).
// Finite values below it are values (a hot pixel is an outlier for the fits).
inline constexpr double kMaxPixelMagnitudeDn = 1e10;

// True for a masked pixel as reads return it.
inline bool IsMaskedPixel(float value_dn) { return std::isnan(value_dn); }
// Masked pixels among `count` values.
size_t CountMaskedPixels(const float* values_dn, size_t count);

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
  // Only float scans can hold masked pixels (see kMaxPixelMagnitudeDn).
  bool may_have_masked_pixels() const { return sample_type == SampleType::kFloat32; }
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
  // rather than half-way through a measurement (TIFF: every strip or tile must lie
  // inside the file; JPEG: the file must end with its end-of-image marker).
  // Throws Error on bad input, and for a format OpenImageIO decodes whole (PNG and
  // any but TIFF, JPEG, FITS) when the decoded image would exceed
  // WholeDecodeLimitMb().
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
  // Drops this file's decoded tiles from the shared cache (a stage done with its windows gives the memory
  // back; a later read decodes them anew).
  void ReleaseCachedTiles() const;

 private:
  ImageInfo info_;
};

// MB; the largest decoded image platemeter accepts in a format that OpenImageIO
// decodes whole on the first pixel read: OpenImageIO's own default guard, the
// smaller of 32 GB and the physical memory. TIFF, JPEG and FITS are read tile by
// tile or row by row, so their size is not limited (the memory used is --cache-mb).
double WholeDecodeLimitMb();

// The pixel size to use: the user's value if given, else the file's resolution
// tags; throws Error naming the file when neither is there.
double ResolvePixelSizeUm(const ImageInfo& info, std::optional<double> user_pixel_size_um);

}  // namespace platemeter
