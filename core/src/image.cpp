#include "platemeter/core/image.h"

#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/imageio.h>

#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <set>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "image_jpeg_integrity.h"
#include "tiff_integrity.h"

namespace platemeter {
namespace {

namespace oiio = OIIO;

oiio::ImageCache* Cache() {
  // Created once with the default options; ConfigureImageCache may change them.
  static oiio::ImageCache* cache = [] {
    oiio::ImageCache* created = oiio::ImageCache::create(/*shared=*/true);
    ImageCacheOptions defaults;
    created->attribute("max_memory_MB", static_cast<float>(defaults.max_memory_mb));
    created->attribute("autotile", defaults.autotile_px);
    created->attribute("autoscanline", 0);
    created->attribute("max_open_files", defaults.max_open_files);
    // Keep tiles in the file's own type: a 16-bit scan costs 2 bytes a pixel in the cache.
    created->attribute("forcefloat", 0);
    // OpenImageIO refuses to open any image whose decoded size exceeds its
    // "limits:imagesize_MB" guard, meant for readers that hold the whole image.
    // platemeter reads TIFF, JPEG and FITS by tiles or rows (the memory used is
    // the cache's), so the guard is lifted here and applied by Image::Open only
    // to the formats OpenImageIO decodes whole (WholeDecodeLimitMb).
    oiio::attribute("limits:imagesize_MB", INT_MAX);
    return created;
  }();
  return cache;
}

std::string CacheError() {
  std::string message = OneLine(Cache()->geterror());
  return message.empty() ? "unknown OpenImageIO error" : message;
}

void WarnOnce(const std::string& path, const std::string& message) {
  static std::mutex mutex;
  static std::set<std::string> warned;
  std::lock_guard<std::mutex> lock(mutex);
  if (warned.insert(path + "\n" + message).second) Warn(path + ": " + message);
}

// Native samples (channels per pixel: 1 or 3) to grayscale DN.
template <typename Sample>
void ToGrayDn(const Sample* samples, int channels, size_t count, float* values_dn) {
  if (channels == 1) {
    std::copy(samples, samples + count, values_dn);
    return;
  }
  for (size_t i = 0; i < count; ++i) {
    values_dn[i] = 0.2126f * static_cast<float>(samples[3 * i]) + 0.7152f * static_cast<float>(samples[3 * i + 1]) +
                   0.0722f * static_cast<float>(samples[3 * i + 2]);
  }
}

// Float samples that are no intensity (NaN, infinite, beyond kMaxPixelMagnitudeDn)
// become NaN, the one marker of a masked pixel. The comparison is false for NaN.
void MaskInvalid(float* values_dn, size_t count) {
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  constexpr float kMax = static_cast<float>(kMaxPixelMagnitudeDn);
  for (size_t i = 0; i < count; ++i) {
    if (!(std::abs(values_dn[i]) <= kMax)) values_dn[i] = kNan;
  }
}

// Formats whose OpenImageIO reader decodes tiles, strips or rows on demand; any
// other (PNG among them) decodes the whole image on the first pixel read.
bool ReadsByParts(const std::string& format) { return format == "tiff" || format == "jpeg" || format == "fits"; }

oiio::TypeDesc NativeType(SampleType type) {
  switch (type) {
    case SampleType::kUint8: return oiio::TypeDesc::UINT8;
    case SampleType::kUint16: return oiio::TypeDesc::UINT16;
    case SampleType::kFloat32: return oiio::TypeDesc::FLOAT;
  }
  return oiio::TypeDesc::FLOAT;
}

// Reads into a buffer of the native type with `read(type, buffer)` and converts.
template <typename ReadFn>
void ReadNativeAsGray(SampleType type, int channels, size_t count, float* values_dn, const ReadFn& read) {
  const size_t samples = count * static_cast<size_t>(channels);
  if (type == SampleType::kUint8) {
    std::vector<uint8_t> raw(samples);
    read(oiio::TypeDesc::UINT8, raw.data());
    ToGrayDn(raw.data(), channels, count, values_dn);
  } else if (type == SampleType::kUint16) {
    std::vector<uint16_t> raw(samples);
    read(oiio::TypeDesc::UINT16, raw.data());
    ToGrayDn(raw.data(), channels, count, values_dn);
  } else {
    std::vector<float> raw(samples);
    read(oiio::TypeDesc::FLOAT, raw.data());
    ToGrayDn(raw.data(), channels, count, values_dn);
    MaskInvalid(values_dn, count);
  }
}

std::optional<double> ResolutionToUm(const oiio::ImageSpec& spec, const char* tag) {
  const float resolution = spec.get_float_attribute(tag, 0.0f);
  const std::string unit = spec.get_string_attribute("ResolutionUnit", "");
  if (!(resolution > 0.0f)) return std::nullopt;
  if (unit == "in" || unit == "inch") return 25400.0 / resolution;
  if (unit == "cm") return 10000.0 / resolution;
  return std::nullopt;  // "none" or unknown: the tags carry no physical size
}

// Before the first pixel read: a format decoded whole must fit the limit.
void CheckWholeDecodeSize(oiio::ustring name, const oiio::ImageSpec& spec, const std::string& path) {
  oiio::ustring format;
  Cache()->get_image_info(name, 0, 0, oiio::ustring("fileformat"), oiio::TypeString, &format);
  if (ReadsByParts(format.string())) return;
  const double decoded_mb = static_cast<double>(spec.image_bytes()) / (1024.0 * 1024.0);
  const double limit_mb = WholeDecodeLimitMb();
  if (decoded_mb <= limit_mb) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "%ld x %ld px: OpenImageIO decodes a %s file whole, %.0f MB, more than the %.0f MB platemeter allows "
                "(the smaller of 32 GB and the physical memory); convert it to a tiled TIFF, which is read tile by tile "
                "(e.g. oiiotool SCAN --tile 512 512 -o SCAN.tif)",
                static_cast<long>(spec.width), static_cast<long>(spec.height),
                format.empty() ? "this" : format.c_str(), decoded_mb, limit_mb);
  throw Error(path, text);
}

// A TIFF is read a strip or tile at a time. A strip (one holding the whole image included) must fit in
// memory; a tile must fit in the tile cache, which holds whole tiles (OpenImageIO aborts on a tile far beyond
// its memory limit).
void CheckTiffBlockSize(const internal::TiffBlock& block, const std::string& path) {
  float cache_mb = 0.0f;
  Cache()->getattribute("max_memory_MB", cache_mb);
  // A RowsPerStrip beyond the height is accepted while what the reader allocates for it is small (a small
  // image written with a writer's usual strip height); a large one is a corrupt tag.
  const double tag_mb = block.tag_rows * block.row_bytes / (1024.0 * 1024.0);
  if (tag_mb > cache_mb) {
    char text[300];
    std::snprintf(text, sizeof text,
                  "RowsPerStrip %.0f exceeds the image's height, and reading a strip would allocate %.0f MB for it "
                  "(more than the image cache's %.0f MB): a corrupt tag",
                  block.tag_rows, tag_mb, static_cast<double>(cache_mb));
    throw Error(path, text);
  }
  const double block_mb = block.bytes / (1024.0 * 1024.0);
  const double limit_mb = block.tiled ? static_cast<double>(cache_mb) : WholeDecodeLimitMb();
  if (block_mb <= limit_mb) return;
  char text[400];
  if (block.tiled) {
    std::snprintf(text, sizeof text,
                  "one tile holds %.0f MB decoded, more than the image cache's %.0f MB (--cache-mb): a corrupt "
                  "tile size, or rewrite it with smaller tiles (e.g. oiiotool SCAN --tile 512 512 -o SCAN.tif)",
                  block_mb, limit_mb);
  } else {
    std::snprintf(text, sizeof text,
                  "one strip holds %.0f MB decoded, more than the %.0f MB platemeter allows (the "
                  "smaller of 32 GB and the physical memory); rewrite it tiled (e.g. oiiotool SCAN --tile 512 512 "
                  "-o SCAN.tif)",
                  block_mb, limit_mb);
  }
  throw Error(path, text);
}

}  // namespace

bool ImageCacheOptions::Check(std::string* why) const {
  if (!(max_memory_mb >= 16.0)) {
    *why = "image cache memory must be at least 16 MB";
    return false;
  }
  if (autotile_px < 64 || (autotile_px & (autotile_px - 1)) != 0) {
    *why = "autotile size must be a power of two of at least 64 px";
    return false;
  }
  if (max_open_files < 1) {
    *why = "max_open_files must be positive";
    return false;
  }
  return true;
}

void ConfigureImageCache(const ImageCacheOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("image cache options", why);
  Cache()->attribute("max_memory_MB", static_cast<float>(options.max_memory_mb));
  Cache()->attribute("autotile", options.autotile_px);
  Cache()->attribute("max_open_files", options.max_open_files);
}

size_t CountMaskedPixels(const float* values_dn, size_t count) {
  size_t masked = 0;
  for (size_t i = 0; i < count; ++i) masked += std::isnan(values_dn[i]) ? 1 : 0;
  return masked;
}

double WholeDecodeLimitMb() {
  const double physical_mb = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE)) /
                             (1024.0 * 1024.0);
  return physical_mb > 0.0 ? std::min(32768.0, physical_mb) : 32768.0;
}

double ImageCacheMemoryUsedMb() {
  long long bytes = 0;
  Cache()->getattribute("stat:cache_memory_used", oiio::TypeDesc::INT64, &bytes);
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

const char* SampleTypeName(SampleType type) {
  switch (type) {
    case SampleType::kUint8: return "uint8";
    case SampleType::kUint16: return "uint16";
    case SampleType::kFloat32: return "float32";
  }
  return "?";
}

Image Image::Open(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw Error(path, "is a directory, not an image");

  if (internal::LooksLikeTiff(path)) {
    internal::TiffBlock block;
    const std::string problem = internal::TiffIntegrityProblem(path, &block);
    if (!problem.empty()) throw Error(path, problem);
    CheckTiffBlockSize(block, path);
  } else if (internal::LooksLikeJpeg(path)) {
    const std::string problem = internal::JpegIntegrityProblem(path);
    if (!problem.empty()) throw Error(path, problem);
  }

  const oiio::ustring name(path);
  // A file rewritten since it was last cached (e.g. by a rerun) must be read anew.
  Cache()->invalidate(name, /*force=*/false);
  oiio::ImageSpec spec;
  if (!Cache()->get_imagespec(name, spec, 0, 0, /*native=*/true)) {
    throw Error(path, "cannot read as an image (" + CacheError() + ")");
  }

  Image image;
  ImageInfo& info = image.info_;
  info.path = path;
  info.format_name = spec.get_string_attribute("oiio:FileFormat",
                                               spec.get_string_attribute("fitsinput:format", ""));
  if (info.format_name.empty()) {
    // The cache does not always record the format; ask the reader's extension map.
    info.format_name = std::filesystem::path(path).extension().string();
  }
  info.width_px = spec.width;
  info.height_px = spec.height;
  info.channels = spec.nchannels;
  info.tiled = spec.tile_width > 0;
  info.tile_width_px = spec.tile_width;
  info.tile_height_px = spec.tile_height;
  info.compression = spec.get_string_attribute("compression", "none");
  if (spec.depth > 1) throw Error(path, "volume images are not scans");
  if (info.width_px <= 0 || info.height_px <= 0) throw Error(path, "image has no pixels");

  const oiio::TypeDesc format = spec.format;
  if (format == oiio::TypeDesc::UINT8) {
    info.sample_type = SampleType::kUint8;
    info.full_scale_dn = 255.0;
  } else if (format == oiio::TypeDesc::UINT16) {
    info.sample_type = SampleType::kUint16;
    info.full_scale_dn = 65535.0;
  } else if (format == oiio::TypeDesc::FLOAT || format == oiio::TypeDesc::HALF ||
             format == oiio::TypeDesc::DOUBLE) {
    info.sample_type = SampleType::kFloat32;
    info.full_scale_dn = 1.0;
  } else {
    throw Error(path, std::string("unsupported sample type ") + format.c_str() +
                          " (scans must be 8-bit, 16-bit or float)");
  }
  const int bits = spec.get_int_attribute("oiio:BitsPerSample", 0);
  if (info.sample_type == SampleType::kUint8 && bits != 0 && bits < 8) {
    throw Error(path, "unsupported bit depth " + std::to_string(bits) + " (scans must be 8-bit, 16-bit or float)");
  }
  if (info.sample_type == SampleType::kUint16 && bits != 0 && bits < 16) {
    WarnOnce(path, std::to_string(bits) + "-bit samples read as 16-bit");
  }
  if (info.channels != 1 && info.channels != 2 && info.channels != 3 && info.channels != 4) {
    throw Error(path, "unsupported channel count " + std::to_string(info.channels));
  }
  info.pixel_size_x_um = ResolutionToUm(spec, "XResolution");
  info.pixel_size_y_um = ResolutionToUm(spec, "YResolution");
  CheckWholeDecodeSize(name, spec, path);

  // Probe the last pixel: it lies in the last tile or strip, which a truncated
  // file does not have.
  float probe[4];
  if (!Cache()->get_pixels(name, 0, 0, spec.x + spec.width - 1, spec.x + spec.width, spec.y + spec.height - 1,
                           spec.y + spec.height, 0, 1, 0, std::min(info.channels, 4),
                           oiio::TypeDesc::FLOAT, probe)) {
    throw Error(path, "cannot read pixel data, the file may be truncated (" + CacheError() + ")");
  }
  if (info.channels >= 3) WarnOnce(path, "colour image converted to luminance (Rec. 709 weights)");
  return image;
}

PixelRect Image::Clip(const PixelRect& rect) const {
  const long x0 = std::max(rect.x0_px, 0L);
  const long y0 = std::max(rect.y0_px, 0L);
  const long x1 = std::min(rect.x_end_px(), info_.width_px);
  const long y1 = std::min(rect.y_end_px(), info_.height_px);
  return {x0, y0, std::max(0L, x1 - x0), std::max(0L, y1 - y0)};
}

ImageWindow Image::ReadWindow(const PixelRect& rect) const {
  ImageWindow window;
  window.rect = rect;
  window.values_dn.resize(static_cast<size_t>(std::max(0L, rect.width_px)) *
                          static_cast<size_t>(std::max(0L, rect.height_px)));
  ReadWindowInto(rect, window.values_dn.data());
  return window;
}

void Image::ReadWindowInto(const PixelRect& rect, float* values_dn) const {
  if (rect.empty() || rect.x0_px < 0 || rect.y0_px < 0 || rect.x_end_px() > info_.width_px ||
      rect.y_end_px() > info_.height_px) {
    throw Error(info_.path, "window [" + std::to_string(rect.x0_px) + "," + std::to_string(rect.y0_px) + " " +
                                std::to_string(rect.width_px) + "x" + std::to_string(rect.height_px) +
                                "] lies outside the image");
  }
  const oiio::ustring name(info_.path);
  const size_t count = static_cast<size_t>(rect.width_px) * static_cast<size_t>(rect.height_px);
  const int x0 = static_cast<int>(rect.x0_px), x1 = static_cast<int>(rect.x_end_px());
  const int y0 = static_cast<int>(rect.y0_px), y1 = static_cast<int>(rect.y_end_px());
  // Gray (+ alpha): the first channel; colour: the first three. Integer scans
  // are read in their own type so DN come back exact (a detour through OIIO's
  // [0, 1] floats would give 99.99999 for 100).
  const int channels = info_.channels <= 2 ? 1 : 3;
  ReadNativeAsGray(info_.sample_type, channels, count, values_dn, [&](oiio::TypeDesc type, void* buffer) {
    if (!Cache()->get_pixels(name, 0, 0, x0, x1, y0, y1, 0, 1, 0, channels, type, buffer)) {
      throw Error(info_.path, "cannot read pixels (" + CacheError() + ")");
    }
  });
}

void Image::ReleaseCachedTiles() const { Cache()->invalidate(oiio::ustring(info_.path), /*force=*/true); }

void Image::ReadRowsDirect(long y0_px, long rows, float* values_dn) const {
  if (rows <= 0 || y0_px < 0 || y0_px + rows > info_.height_px) {
    throw Error(info_.path, "rows " + std::to_string(y0_px) + "+" + std::to_string(rows) + " lie outside the image");
  }
  auto input = oiio::ImageInput::open(info_.path);
  if (!input) throw Error(info_.path, "cannot open for reading (" + OneLine(oiio::geterror()) + ")");
  const int channels = info_.channels <= 2 ? 1 : 3;
  const long width = info_.width_px;
  // Tiled files are read by whole tile rows, then cropped to the rows asked for.
  const long tile_h = info_.tiled ? info_.tile_height_px : 1;
  const long read_y0 = y0_px / tile_h * tile_h;
  const long read_y1 = std::min(info_.height_px, (y0_px + rows + tile_h - 1) / tile_h * tile_h);
  const size_t read_count = static_cast<size_t>(width) * static_cast<size_t>(read_y1 - read_y0);
  std::vector<float> gray;
  float* target = values_dn;
  if (read_y0 != y0_px || read_y1 != y0_px + rows) {
    gray.resize(read_count);
    target = gray.data();
  }
  const oiio::ImageSpec& spec = input->spec();
  ReadNativeAsGray(info_.sample_type, channels, read_count, target, [&](oiio::TypeDesc type, void* buffer) {
    const bool ok = info_.tiled
                        ? input->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + static_cast<int>(read_y0),
                                            spec.y + static_cast<int>(read_y1), 0, 1, 0, channels, type, buffer)
                        : input->read_scanlines(0, 0, spec.y + static_cast<int>(read_y0),
                                                spec.y + static_cast<int>(read_y1), 0, 0, channels, type, buffer);
    if (!ok) throw Error(info_.path, "cannot read pixels (" + OneLine(input->geterror()) + ")");
  });
  if (target != values_dn) {
    std::copy(gray.begin() + (y0_px - read_y0) * width, gray.begin() + (y0_px - read_y0 + rows) * width, values_dn);
  }
}

double ResolvePixelSizeUm(const ImageInfo& info, std::optional<double> user_pixel_size_um) {
  if (user_pixel_size_um) {
    if (!(*user_pixel_size_um > 0.0) || !std::isfinite(*user_pixel_size_um)) {
      throw Error(info.path, "pixel size must be a positive number of micrometres");
    }
    return *user_pixel_size_um;
  }
  if (info.pixel_size_x_um && info.pixel_size_y_um) {
    const double x = *info.pixel_size_x_um, y = *info.pixel_size_y_um;
    if (std::abs(x - y) > 1e-6 * x) {
      throw Error(info.path, "resolution tags give non-square pixels (" + std::to_string(x) + " x " +
                                 std::to_string(y) + " um); give --pixel-size-um");
    }
    return x;
  }
  throw Error(info.path, "no pixel size in the file's resolution tags; give --pixel-size-um");
}

}  // namespace platemeter
