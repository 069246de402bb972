#pragma once
// Writes a grayscale scan band by band, so a plate of any size is written with
// memory for one band of rows. The file appears under its final name only when
// Finish() succeeds (temporary name + rename): never a half-written scan.
#include <memory>
#include <optional>
#include <string>

#include "platemeter/core/image.h"

namespace platemeter {

struct ImageWriterOptions {
  long width_px = 0;
  long height_px = 0;
  SampleType sample_type = SampleType::kUint16;
  int tile_size_px = 256;           // px; 0 writes strips (scanlines) instead of tiles
  std::string compression = "zip";  // "none", "lzw" or "zip" (deflate); TIFF only
  bool bigtiff = false;             // forced on when the raw size passes 3.5 GB
  std::optional<double> pixel_size_um;  // um; written as TIFF resolution tags (dpi)
  bool Check(std::string* why) const;
};

class ImageWriter {
 public:
  // The format follows the file name's extension (.tif/.tiff, .png, .jpg, .fits).
  ImageWriter(const std::string& path, const ImageWriterOptions& options);
  ~ImageWriter();  // removes the temporary file unless Finish() succeeded
  ImageWriter(const ImageWriter&) = delete;
  ImageWriter& operator=(const ImageWriter&) = delete;

  // Rows a band must have (the tile height, or any number for strips); the last
  // band may be shorter.
  int band_height_px() const;
  // Writes rows [y0_px, y0_px + rows) in DN (clamped and rounded to the sample
  // type). Bands must come in order from the top.
  void WriteBand(long y0_px, long rows, const float* values_dn);
  // Closes the file and renames it into place; throws Error on failure.
  void Finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes a small in-memory image in one go (tests, plots, sample data).
void WriteImage(const std::string& path, const ImageWriterOptions& options, const float* values_dn);

}  // namespace platemeter
