#include "platemeter/core/image_writer.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

namespace oiio = OIIO;

oiio::TypeDesc TypeOf(SampleType type) {
  switch (type) {
    case SampleType::kUint8: return oiio::TypeDesc::UINT8;
    case SampleType::kUint16: return oiio::TypeDesc::UINT16;
    case SampleType::kFloat32: return oiio::TypeDesc::FLOAT;
  }
  return oiio::TypeDesc::UINT16;
}

}  // namespace

bool ImageWriterOptions::Check(std::string* why) const {
  if (width_px <= 0 || height_px <= 0) {
    *why = "image size must be positive";
    return false;
  }
  if (width_px > 2147483647L || height_px > 2147483647L) {
    *why = "image size exceeds 2^31 px";
    return false;
  }
  if (tile_size_px < 0 || (tile_size_px > 0 && tile_size_px % 16 != 0)) {
    *why = "tile size must be 0 (strips) or a multiple of 16 px";
    return false;
  }
  if (compression != "none" && compression != "lzw" && compression != "zip") {
    *why = "compression must be none, lzw or zip";
    return false;
  }
  if (pixel_size_um && !(*pixel_size_um > 0.0)) {
    *why = "pixel size must be positive";
    return false;
  }
  return true;
}

struct ImageWriter::Impl {
  std::string path;
  std::string temp_path;
  ImageWriterOptions options;
  std::unique_ptr<oiio::ImageOutput> output;
  long next_row = 0;
  bool finished = false;
  std::vector<unsigned char> buffer;
};

ImageWriter::ImageWriter(const std::string& path, const ImageWriterOptions& options)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.Check(&why)) throw Error(path, why);
  impl_->path = path;
  impl_->options = options;
  const std::filesystem::path target(path);
  // Same folder, so the final rename stays on one file system; the extension is
  // kept so OpenImageIO picks the format from it.
  impl_->temp_path = (target.parent_path() / ("." + target.stem().string() + ".partial" +
                                              target.extension().string())).string();

  impl_->output = oiio::ImageOutput::create(path);
  if (!impl_->output) throw Error(path, "no writer for this file type (" + OneLine(oiio::geterror()) + ")");
  const bool is_tiff = std::string(impl_->output->format_name()) == "tiff";

  oiio::ImageSpec spec(static_cast<int>(options.width_px), static_cast<int>(options.height_px), 1,
                       TypeOf(options.sample_type));
  const bool tiled = options.tile_size_px > 0 && impl_->output->supports("tiles");
  if (tiled) {
    spec.tile_width = spec.tile_height = options.tile_size_px;
  }
  if (is_tiff) {
    spec.attribute("compression", options.compression);
    const double raw_bytes = static_cast<double>(options.width_px) * static_cast<double>(options.height_px) *
                             static_cast<double>(spec.format.size());
    if (options.bigtiff || raw_bytes > 3.5e9) spec.attribute("tiff:bigtiff", 1);
  }
  if (options.pixel_size_um) {
    const float dpi = static_cast<float>(25400.0 / *options.pixel_size_um);
    spec.attribute("XResolution", dpi);
    spec.attribute("YResolution", dpi);
    spec.attribute("ResolutionUnit", "inch");
  }
  if (!impl_->output->open(impl_->temp_path, spec)) {
    throw Error(path, "cannot create (" + OneLine(impl_->output->geterror()) + ")");
  }
  impl_->options.tile_size_px = tiled ? options.tile_size_px : 0;
}

ImageWriter::~ImageWriter() {
  if (!impl_->finished) {
    if (impl_->output) impl_->output->close();
    std::remove(impl_->temp_path.c_str());
  }
}

int ImageWriter::band_height_px() const {
  return impl_->options.tile_size_px > 0 ? impl_->options.tile_size_px : 64;
}

void ImageWriter::WriteBand(long y0_px, long rows, const float* values_dn) {
  const ImageWriterOptions& o = impl_->options;
  if (y0_px != impl_->next_row || rows <= 0 || y0_px + rows > o.height_px) {
    throw Error(impl_->path, "bands must be written in order from the top");
  }
  if (o.tile_size_px > 0 && rows != o.tile_size_px && y0_px + rows != o.height_px) {
    throw Error(impl_->path, "a band must be one tile high except the last");
  }
  // Round and clamp here so every caller quantizes the same way.
  const size_t count = static_cast<size_t>(rows) * static_cast<size_t>(o.width_px);
  const oiio::TypeDesc type = TypeOf(o.sample_type);
  impl_->buffer.resize(count * type.size());
  if (o.sample_type == SampleType::kFloat32) {
    std::copy(values_dn, values_dn + count, reinterpret_cast<float*>(impl_->buffer.data()));
  } else if (o.sample_type == SampleType::kUint16) {
    auto* out = reinterpret_cast<uint16_t*>(impl_->buffer.data());
    for (size_t i = 0; i < count; ++i) out[i] = static_cast<uint16_t>(std::clamp(std::lround(values_dn[i]), 0L, 65535L));
  } else {
    auto* out = impl_->buffer.data();
    for (size_t i = 0; i < count; ++i) out[i] = static_cast<uint8_t>(std::clamp(std::lround(values_dn[i]), 0L, 255L));
  }
  bool ok;
  const int x_end = static_cast<int>(o.width_px);
  const int y0 = static_cast<int>(y0_px), y1 = static_cast<int>(y0_px + rows);
  if (o.tile_size_px > 0) {
    ok = impl_->output->write_tiles(0, x_end, y0, y1, 0, 1, type, impl_->buffer.data());
  } else {
    ok = impl_->output->write_scanlines(y0, y1, 0, type, impl_->buffer.data());
  }
  if (!ok) throw Error(impl_->path, "cannot write pixels (" + OneLine(impl_->output->geterror()) + ")");
  impl_->next_row = y0_px + rows;
}

void ImageWriter::Finish() {
  if (impl_->next_row != impl_->options.height_px) {
    throw Error(impl_->path, "only " + std::to_string(impl_->next_row) + " of " +
                                 std::to_string(impl_->options.height_px) + " rows were written");
  }
  if (!impl_->output->close()) {
    throw Error(impl_->path, "cannot finish writing (" + OneLine(impl_->output->geterror()) + ")");
  }
  std::error_code ec;
  std::filesystem::rename(impl_->temp_path, impl_->path, ec);
  if (ec) throw Error(impl_->path, "cannot rename into place (" + ec.message() + ")");
  impl_->finished = true;
}

void WriteImage(const std::string& path, const ImageWriterOptions& options, const float* values_dn) {
  ImageWriter writer(path, options);
  const long band = writer.band_height_px();
  for (long y = 0; y < options.height_px; y += band) {
    const long rows = std::min(band, options.height_px - y);
    writer.WriteBand(y, rows, values_dn + static_cast<size_t>(y) * static_cast<size_t>(options.width_px));
  }
  writer.Finish();
}

}  // namespace platemeter
