// Scan input checks (issue #28): a truncated JPEG is refused at open like a
// truncated TIFF; a float scan's NaN, infinite and |value| > 1e10 samples come
// back masked (NaN) from every read while large physical values stay values; a
// 200000 x 200000 tiled TIFF opens and reads (platemeter reads it tile by tile),
// and a PNG too large to decode whole, or a TIFF stored as one such strip, is
// refused with a message that says what the limit is and what to do.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

std::string OpenError(const std::string& path) {
  try {
    Image::Open(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

void ExpectOneLineErrorNaming(const std::string& what, const std::string& path, const std::string& fragment) {
  ASSERT_FALSE(what.empty()) << path << " opened without an error";
  EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
  EXPECT_NE(what.find(fragment), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

std::string WriteJpeg(const testing::TempDir& dir, const std::string& name) {
  std::vector<float> values(320 * 240);
  for (long row = 0; row < 240; ++row)
    for (long col = 0; col < 320; ++col)
      values[static_cast<size_t>(row * 320 + col)] = static_cast<float>((col * 7 + row * 3) % 200 + 20);
  ImageWriterOptions options;
  options.width_px = 320;
  options.height_px = 240;
  options.sample_type = SampleType::kUint8;
  options.tile_size_px = 0;
  WriteImage(dir.file(name), options, values.data());
  return dir.file(name);
}

TEST(ImageInputChecks, TruncatedJpegIsRefusedAtOpen) {
  testing::TempDir dir;
  const std::string whole = WriteJpeg(dir, "whole.jpg");
  const uintmax_t bytes = std::filesystem::file_size(whole);
  // Cut anywhere in the coded data, or just the last byte of the end-of-image marker.
  for (uintmax_t keep : {bytes * 6 / 10, bytes * 95 / 100, bytes - 1}) {
    const std::string cut = dir.file("cut-" + std::to_string(keep) + ".jpg");
    std::filesystem::copy_file(whole, cut);
    std::filesystem::resize_file(cut, keep);
    const std::string what = OpenError(cut);
    ExpectOneLineErrorNaming(what, cut, "the file is truncated");
    EXPECT_NE(what.find("end-of-image marker"), std::string::npos) << what;
  }
  // The whole file, and the whole file padded with zero bytes after the marker, open and read.
  EXPECT_EQ(OpenError(whole), "");
  const std::string padded = dir.file("padded.jpg");
  std::filesystem::copy_file(whole, padded);
  std::ofstream(padded, std::ios::binary | std::ios::app) << std::string(100, '\0');
  const Image image = Image::Open(padded);
  EXPECT_NEAR(image.ReadWindow({100, 100, 1, 1}).values_dn[0], (100 * 7 + 100 * 3) % 200 + 20, 4.0);
}

TEST(ImageInputChecks, FloatNonFiniteAndFillValuesAreMasked) {
  testing::TempDir dir;
  const float inf = std::numeric_limits<float>::infinity();
  // The first six are no intensity; the rest are values, however large or negative.
  // Fill values: 3e38, float's lowest (GDAL), 1e20 (CF/CMIP missing_value); 4.2e9 a 32-bit count.
  const std::vector<float> written = {std::numeric_limits<float>::quiet_NaN(), inf, -inf, 3e38f, -3.4e38f, 1e20f,
                                      4.2e9f, -1e9f, -5.0f, 0.5f, 65535.0f, 0.0f};
  ImageWriterOptions options;
  options.width_px = 6;
  options.height_px = 2;
  options.sample_type = SampleType::kFloat32;
  options.tile_size_px = 0;
  WriteImage(dir.file("float.tif"), options, written.data());
  const Image image = Image::Open(dir.file("float.tif"));
  EXPECT_TRUE(image.info().may_have_masked_pixels());
  const ImageWindow window = image.ReadWindow(image.Bounds());
  std::vector<float> rows(written.size());
  image.ReadRowsDirect(0, 2, rows.data());
  for (size_t i = 0; i < written.size(); ++i) {
    if (i < 6) {
      EXPECT_TRUE(IsMaskedPixel(window.values_dn[i])) << i;
      EXPECT_TRUE(IsMaskedPixel(rows[i])) << i;
    } else {
      EXPECT_EQ(window.values_dn[i], written[i]) << i;
      EXPECT_EQ(rows[i], written[i]) << i;
    }
  }
  EXPECT_EQ(CountMaskedPixels(window.values_dn.data(), window.values_dn.size()), 6u);

  // Integer scans hold no masked pixel.
  options.sample_type = SampleType::kUint16;
  const std::vector<float> dn = {0, 1, 65535, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  WriteImage(dir.file("int.tif"), options, dn.data());
  EXPECT_FALSE(Image::Open(dir.file("int.tif")).info().may_have_masked_pixels());
}

void PutLe(std::vector<uint8_t>* out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<uint8_t>(value >> (8 * i)));
}

// A tiled 8-bit TIFF of width x height px, uncompressed, whose tiles all share one
// 1024 x 1024 block of data (legal TIFF, and a file of 1.3 MB for 40 GB of pixels).
void WriteSharedTileTiff(const std::string& path, uint32_t width, uint32_t height) {
  constexpr uint32_t kTile = 1024;
  const uint32_t tiles = ((width + kTile - 1) / kTile) * ((height + kTile - 1) / kTile);
  const uint32_t entries = 11, ifd_bytes = 2 + entries * 12 + 4;
  const uint32_t offsets_at = 8 + ifd_bytes, counts_at = offsets_at + 4 * tiles, data_at = counts_at + 4 * tiles;
  std::vector<uint8_t> f = {'I', 'I'};
  PutLe(&f, 42, 2);
  PutLe(&f, 8, 4);
  PutLe(&f, entries, 2);
  auto entry = [&](uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
    PutLe(&f, tag, 2), PutLe(&f, type, 2), PutLe(&f, count, 4), PutLe(&f, value, 4);
  };
  constexpr uint16_t kShort = 3, kLong = 4;
  entry(256, kLong, 1, width);
  entry(257, kLong, 1, height);
  entry(258, kShort, 1, 8);       // bits per sample
  entry(259, kShort, 1, 1);       // no compression
  entry(262, kShort, 1, 1);       // min-is-black
  entry(277, kShort, 1, 1);       // samples per pixel
  entry(284, kShort, 1, 1);       // contiguous
  entry(322, kLong, 1, kTile);    // tile width
  entry(323, kLong, 1, kTile);    // tile length
  entry(324, kLong, tiles, offsets_at);
  entry(325, kLong, tiles, counts_at);
  PutLe(&f, 0, 4);  // no next directory
  for (uint32_t t = 0; t < tiles; ++t) PutLe(&f, data_at, 4);
  for (uint32_t t = 0; t < tiles; ++t) PutLe(&f, kTile * kTile, 4);
  for (uint32_t y = 0; y < kTile; ++y)
    for (uint32_t x = 0; x < kTile; ++x) f.push_back(static_cast<uint8_t>((x * 7 + y * 3) % 251));
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(f.data()), static_cast<std::streamsize>(f.size()));
}

TEST(ImageInputChecks, A200000PxSquareTiledTiffOpensAndReads) {
  testing::TempDir dir;
  const std::string path = dir.file("huge.tif");
  WriteSharedTileTiff(path, 200000, 200000);
  const Image image = Image::Open(path);  // 38147 MB of pixels: read by tiles, never whole
  EXPECT_EQ(image.info().width_px, 200000);
  EXPECT_EQ(image.info().height_px, 200000);
  const ImageWindow far = image.ReadWindow({199990, 150005, 10, 3});
  for (long row = 150005; row < 150008; ++row)
    for (long col = 199990; col < 200000; ++col)
      EXPECT_EQ(far.at(col, row), static_cast<float>(((col % 1024) * 7 + (row % 1024) * 3) % 251)) << col << "," << row;
}

// A 200000 x 200000 8-bit TIFF stored as one deflate strip (RowsPerStrip = height): a reader must
// inflate 38147 MB at once. The strip's bytes are never read.
void WriteOneStripTiff(const std::string& path) {
  std::vector<uint8_t> f = {'I', 'I'};
  PutLe(&f, 42, 2);
  PutLe(&f, 8, 4);
  const uint32_t entries = 9, data_at = 8 + 2 + entries * 12 + 4;
  PutLe(&f, entries, 2);
  auto entry = [&](uint16_t tag, uint16_t type, uint32_t value) {
    PutLe(&f, tag, 2), PutLe(&f, type, 2), PutLe(&f, 1, 4), PutLe(&f, value, 4);
  };
  entry(256, 4, 200000);
  entry(257, 4, 200000);
  entry(258, 3, 8);
  entry(259, 3, 8);  // deflate
  entry(262, 3, 1);
  entry(273, 4, data_at);  // strip offset
  entry(277, 3, 1);
  entry(278, 4, 200000);   // rows per strip: all
  entry(279, 4, 16);       // strip byte count
  PutLe(&f, 0, 4);
  f.insert(f.end(), 16, 0);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(f.data()), static_cast<std::streamsize>(f.size()));
}

TEST(ImageInputChecks, ATiffWhoseOneStripIsTooLargeToDecodeIsRefused) {
  testing::TempDir dir;
  const std::string path = dir.file("one-strip.tif");
  WriteOneStripTiff(path);
  const std::string what = OpenError(path);
  ExpectOneLineErrorNaming(what, path, "one strip holds 38147 MB decoded");
  EXPECT_NE(what.find("rewrite it tiled"), std::string::npos) << what;
}

uint32_t Crc32(const uint8_t* data, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void PutChunk(std::vector<uint8_t>* png, const std::string& type, const std::vector<uint8_t>& data) {
  for (int i = 3; i >= 0; --i) png->push_back(static_cast<uint8_t>(data.size() >> (8 * i)));
  std::vector<uint8_t> body(type.begin(), type.end());
  body.insert(body.end(), data.begin(), data.end());
  png->insert(png->end(), body.begin(), body.end());
  const uint32_t crc = Crc32(body.data(), body.size());
  for (int i = 3; i >= 0; --i) png->push_back(static_cast<uint8_t>(crc >> (8 * i)));
}

TEST(ImageInputChecks, APngTooLargeToDecodeWholeIsRefusedSayingWhatToDo) {
  testing::TempDir dir;
  const std::string path = dir.file("huge.png");
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  const uint32_t side = 200000;
  std::vector<uint8_t> header;
  for (int k = 0; k < 2; ++k)
    for (int i = 3; i >= 0; --i) header.push_back(static_cast<uint8_t>(side >> (8 * i)));
  header.insert(header.end(), {8, 0, 0, 0, 0});  // 8-bit grey, no interlace
  PutChunk(&png, "IHDR", header);
  PutChunk(&png, "IDAT", {0x78, 0x9C, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01});  // never decoded
  PutChunk(&png, "IEND", {});
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  const std::string what = OpenError(path);
  ExpectOneLineErrorNaming(what, path, "decodes a png file whole, 38147 MB");
  EXPECT_NE(what.find("convert it to a tiled TIFF"), std::string::npos) << what;
  EXPECT_EQ(what.find("OIIO global attribute"), std::string::npos) << what;  // no advice the user cannot follow
  EXPECT_LE(WholeDecodeLimitMb(), 32768.0);
}

}  // namespace
}  // namespace platemeter
