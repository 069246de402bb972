// Image access: every supported layout and format reads back the values that
// were written, windows agree with the whole image, and bad input fails with
// a one-line error naming the file.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/core/log.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

// A pattern with distinct values everywhere, so a shifted or flipped read fails.
float Pattern(long col, long row, double full_scale) {
  return static_cast<float>(std::fmod(37.0 * col + 101.0 * row + 0.25 * col * row, full_scale));
}

std::vector<float> MakePattern(long width, long height, double full_scale) {
  std::vector<float> values(static_cast<size_t>(width * height));
  for (long row = 0; row < height; ++row)
    for (long col = 0; col < width; ++col)
      values[static_cast<size_t>(row * width + col)] = std::round(Pattern(col, row, full_scale));
  return values;
}

struct Layout {
  std::string name;
  std::string extension;
  SampleType type;
  int tile_px;
  std::string compression;
  bool bigtiff;
};

// Short parameter text (test names in ctest carry it).
void PrintTo(const Layout& layout, std::ostream* os) { *os << layout.name; }

class ImageLayouts : public ::testing::TestWithParam<Layout> {};

TEST_P(ImageLayouts, ReadsBackWhatWasWritten) {
  const Layout& layout = GetParam();
  testing::TempDir dir;
  const long width = 300, height = 170;  // not a multiple of any tile size
  const double full_scale = layout.type == SampleType::kUint8 ? 255 : layout.type == SampleType::kUint16 ? 65535 : 1000;
  const std::vector<float> values = MakePattern(width, height, full_scale);
  ImageWriterOptions options;
  options.width_px = width;
  options.height_px = height;
  options.sample_type = layout.type;
  options.tile_size_px = layout.tile_px;
  options.compression = layout.compression;
  options.bigtiff = layout.bigtiff;
  const std::string path = dir.file("scan" + layout.extension);
  WriteImage(path, options, values.data());

  const Image image = Image::Open(path);
  EXPECT_EQ(image.info().width_px, width);
  EXPECT_EQ(image.info().height_px, height);
  EXPECT_EQ(image.info().sample_type, layout.type);
  EXPECT_EQ(image.info().tiled, layout.tile_px > 0 && layout.extension == ".tif");
  const ImageWindow all = image.ReadWindow(image.Bounds());
  for (long row = 0; row < height; ++row)
    for (long col = 0; col < width; ++col)
      ASSERT_FLOAT_EQ(all.at(col, row), values[static_cast<size_t>(row * width + col)]) << col << "," << row;
  // A window across tile boundaries equals the same pixels of the whole image.
  const ImageWindow part = image.ReadWindow({61, 47, 130, 90});
  for (long row = 47; row < 137; ++row)
    for (long col = 61; col < 191; ++col) ASSERT_EQ(part.at(col, row), all.at(col, row));
  // Direct row reads (no cache), not aligned to tiles, and up to the last row.
  for (const auto& [y0, rows] : {std::pair<long, long>{37, 61}, {0, height}, {height - 5, 5}}) {
    std::vector<float> direct(static_cast<size_t>(width * rows));
    image.ReadRowsDirect(y0, rows, direct.data());
    for (long row = y0; row < y0 + rows; ++row)
      for (long col = 0; col < width; ++col)
        ASSERT_EQ(direct[static_cast<size_t>((row - y0) * width + col)], all.at(col, row)) << col << "," << row;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Formats, ImageLayouts,
    ::testing::Values(Layout{"tiff_strips_none_u16", ".tif", SampleType::kUint16, 0, "none", false},
                      Layout{"tiff_strips_lzw_u8", ".tif", SampleType::kUint8, 0, "lzw", false},
                      Layout{"tiff_tiled_lzw_u16", ".tif", SampleType::kUint16, 64, "lzw", false},
                      Layout{"tiff_tiled_zip_u8", ".tif", SampleType::kUint8, 128, "zip", false},
                      Layout{"tiff_tiled_zip_float", ".tif", SampleType::kFloat32, 64, "zip", false},
                      Layout{"bigtiff_tiled_u16", ".tif", SampleType::kUint16, 64, "zip", true},
                      Layout{"png_u8", ".png", SampleType::kUint8, 0, "none", false},
                      Layout{"png_u16", ".png", SampleType::kUint16, 0, "none", false},
                      Layout{"fits_float", ".fits", SampleType::kFloat32, 0, "none", false}),
    [](const ::testing::TestParamInfo<Layout>& info) { return info.param.name; });

TEST(ImageAccess, BigTiffIsReallyBigTiff) {
  testing::TempDir dir;
  const std::vector<float> values = MakePattern(64, 64, 65535);
  ImageWriterOptions options;
  options.width_px = options.height_px = 64;
  options.tile_size_px = 32;
  options.bigtiff = true;
  WriteImage(dir.file("big.tif"), options, values.data());
  std::ifstream in(dir.file("big.tif"), std::ios::binary);
  unsigned char header[4] = {};
  in.read(reinterpret_cast<char*>(header), 4);
  EXPECT_EQ(header[2] | (header[3] << 8), 43);  // TIFF magic 42, BigTIFF 43 (little-endian)
}

TEST(ImageAccess, JpegIsReadWithinCompressionError) {
  testing::TempDir dir;
  std::vector<float> values(200 * 100);
  for (long row = 0; row < 100; ++row)
    for (long col = 0; col < 200; ++col) values[static_cast<size_t>(row * 200 + col)] = 60.0f + 0.5f * col;
  ImageWriterOptions options;
  options.width_px = 200;
  options.height_px = 100;
  options.sample_type = SampleType::kUint8;
  options.tile_size_px = 0;
  WriteImage(dir.file("scan.jpg"), options, values.data());
  const Image image = Image::Open(dir.file("scan.jpg"));
  const ImageWindow all = image.ReadWindow(image.Bounds());
  for (long col = 10; col < 190; col += 20) EXPECT_NEAR(all.at(col, 50), 60.0f + 0.5f * col, 3.0f);
}

TEST(ImageAccess, RgbIsReadAsLuminanceWithAWarning) {
  testing::TempDir dir;
  const std::string path = dir.file("colour.png");
  const int width = 8, height = 4;
  std::vector<unsigned char> rgb(width * height * 3);
  for (int i = 0; i < width * height; ++i) {
    rgb[3 * i] = 200;
    rgb[3 * i + 1] = 100;
    rgb[3 * i + 2] = 50;
  }
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(path, OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
  out->close();

  std::vector<std::string> warnings;
  SetWarningSink([&](const std::string& line) { warnings.push_back(line); });
  const Image image = Image::Open(path);
  SetWarningSink(nullptr);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("luminance"), std::string::npos);
  EXPECT_NE(warnings[0].find(path), std::string::npos);
  // Rec. 709: 0.2126 * 200 + 0.7152 * 100 + 0.0722 * 50 = 42.52 + 71.52 + 3.61 = 117.65
  EXPECT_NEAR(image.ReadWindow({0, 0, 1, 1}).values_dn[0], 117.65f, 1e-3f);
}

TEST(ImageAccess, PixelSizeFromResolutionTags) {
  testing::TempDir dir;
  const std::vector<float> values = MakePattern(32, 32, 255);
  ImageWriterOptions options;
  options.width_px = options.height_px = 32;
  options.sample_type = SampleType::kUint8;
  options.pixel_size_um = 12.5;  // 2032 dpi
  WriteImage(dir.file("tagged.tif"), options, values.data());
  options.pixel_size_um.reset();
  WriteImage(dir.file("untagged.tif"), options, values.data());

  const Image tagged = Image::Open(dir.file("tagged.tif"));
  ASSERT_TRUE(tagged.info().pixel_size_x_um.has_value());
  EXPECT_NEAR(*tagged.info().pixel_size_x_um, 12.5, 1e-4);
  EXPECT_NEAR(ResolvePixelSizeUm(tagged.info(), std::nullopt), 12.5, 1e-4);
  EXPECT_DOUBLE_EQ(ResolvePixelSizeUm(tagged.info(), 7.0), 7.0);  // the user's value wins

  const Image untagged = Image::Open(dir.file("untagged.tif"));
  try {
    ResolvePixelSizeUm(untagged.info(), std::nullopt);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("untagged.tif"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("--pixel-size-um"), std::string::npos);
  }
  EXPECT_THROW(ResolvePixelSizeUm(untagged.info(), -3.0), Error);
}

// Bad input: each error is a platemeter::Error whose one-line message names the file.
void ExpectOpenError(const std::string& path, const std::string& fragment) {
  try {
    Image::Open(path);
    FAIL() << "expected an error for " << path;
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(ImageAccess, MissingFile) {
  testing::TempDir dir;
  ExpectOpenError(dir.file("nothing-here.tif"), "no such file");
}

TEST(ImageAccess, NotAnImage) {
  testing::TempDir dir;
  std::ofstream(dir.file("notes.tif")) << "this is not a TIFF\n";
  ExpectOpenError(dir.file("notes.tif"), "cannot read");
}

TEST(ImageAccess, TruncatedTiffFailsAtOpen) {
  for (int tile_px : {0, 64}) {
    testing::TempDir dir;
    const std::vector<float> values = MakePattern(256, 256, 65535);
    ImageWriterOptions options;
    options.width_px = options.height_px = 256;
    options.tile_size_px = tile_px;
    options.compression = "none";
    const std::string path = dir.file("truncated.tif");
    WriteImage(path, options, values.data());
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
    ExpectOpenError(path, "truncated");
  }
}

TEST(ImageAccess, WindowOutsideTheImage) {
  testing::TempDir dir;
  const std::vector<float> values = MakePattern(32, 32, 255);
  ImageWriterOptions options;
  options.width_px = options.height_px = 32;
  options.sample_type = SampleType::kUint8;
  WriteImage(dir.file("small.tif"), options, values.data());
  const Image image = Image::Open(dir.file("small.tif"));
  EXPECT_THROW(image.ReadWindow({30, 0, 4, 4}), Error);
  EXPECT_THROW(image.ReadWindow({-1, 0, 4, 4}), Error);
  const PixelRect clipped = image.Clip({30, -2, 4, 4});
  EXPECT_EQ(clipped.x0_px, 30);
  EXPECT_EQ(clipped.width_px, 2);
  EXPECT_EQ(clipped.y0_px, 0);
  EXPECT_EQ(clipped.height_px, 2);
}

TEST(ImageWriter, UnfinishedWriteLeavesNoFile) {
  testing::TempDir dir;
  const std::string path = dir.file("unfinished.tif");
  {
    ImageWriterOptions options;
    options.width_px = options.height_px = 64;
    options.tile_size_px = 32;
    ImageWriter writer(path, options);
    std::vector<float> band(64 * 32, 5.0f);
    writer.WriteBand(0, 32, band.data());
    // destroyed without Finish(): as if the process failed half-way
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(ImageWriter, QuantizesByRoundingAndClamping) {
  testing::TempDir dir;
  std::vector<float> values = {-5.0f, 0.49f, 0.5f, 1.5f, 254.6f, 300.0f, 17.2f, 99.5f};
  ImageWriterOptions options;
  options.width_px = 8;
  options.height_px = 1;
  options.sample_type = SampleType::kUint8;
  options.tile_size_px = 0;
  WriteImage(dir.file("q.tif"), options, values.data());
  const ImageWindow read = Image::Open(dir.file("q.tif")).ReadWindow({0, 0, 8, 1});
  const std::vector<float> expected = {0, 0, 1, 2, 255, 255, 17, 100};  // half away from zero
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(read.values_dn[i], expected[i]) << i;
}

TEST(ImageCacheOptions, RejectsNonsense) {
  ImageCacheOptions options;
  std::string why;
  EXPECT_TRUE(options.Check(&why));
  options.max_memory_mb = 1;
  EXPECT_FALSE(options.Check(&why));
  options = {};
  options.autotile_px = 100;
  EXPECT_FALSE(options.Check(&why));
  EXPECT_THROW(ConfigureImageCache(options), Error);
}

}  // namespace
}  // namespace platemeter
