// The binary's own promises: --help, --version, and bad input answered with one
// line on stderr and a non-zero exit code, never a crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "platemeter/core/image_writer.h"
#include "platemeter/core/version.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::RunPlatemeter;

int CountLines(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

// One line on stderr naming `subject`, nothing on stdout, exit code 1.
void ExpectOneLineError(const testing::CommandResult& result, const std::string& subject, const std::string& reason) {
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(CountLines(result.err), 1) << result.err;
  EXPECT_EQ(result.err.rfind("platemeter: error: ", 0), 0u) << result.err;
  EXPECT_NE(result.err.find(subject), std::string::npos) << result.err;
  EXPECT_NE(result.err.find(reason), std::string::npos) << result.err;
}

TEST(Cli, HelpAndVersion) {
  const auto help = RunPlatemeter("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("info"), std::string::npos);
  const auto version = RunPlatemeter("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.out.find(kVersion), std::string::npos);
}

TEST(Cli, NoSubcommandIsAUsageError) {
  const auto result = RunPlatemeter("");
  EXPECT_NE(result.exit_code, 0);
}

TEST(Cli, InfoOnMissingFile) {
  testing::TempDir dir;
  ExpectOneLineError(RunPlatemeter("info '" + dir.file("absent.tif") + "'"), dir.file("absent.tif"), "no such file");
}

TEST(Cli, InfoOnTruncatedTiff) {
  testing::TempDir dir;
  const std::string path = dir.file("cut.tif");
  ImageWriterOptions options;
  options.width_px = options.height_px = 512;
  options.tile_size_px = 128;
  options.compression = "none";
  std::vector<float> values(512 * 512, 1000.0f);
  WriteImage(path, options, values.data());
  std::filesystem::resize_file(path, std::filesystem::file_size(path) * 3 / 4);
  ExpectOneLineError(RunPlatemeter("info '" + path + "'"), path, "truncated");
}

TEST(Cli, InfoOnTextFile) {
  testing::TempDir dir;
  const std::string path = dir.file("notes.png");
  std::ofstream(path) << "not a png\n";
  ExpectOneLineError(RunPlatemeter("info '" + path + "'"), path, "cannot read");
}

TEST(Cli, InfoReportsPixelSizeFromTags) {
  testing::TempDir dir;
  const std::string path = dir.file("tagged.tif");
  ImageWriterOptions options;
  options.width_px = 64;
  options.height_px = 32;
  options.pixel_size_um = 10.0;
  std::vector<float> values(64 * 32, 7.0f);
  WriteImage(path, options, values.data());
  const auto result = RunPlatemeter("info '" + path + "'");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("size_px: 64 x 32"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("pixel_size_um: 10"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("uint16"), std::string::npos) << result.out;
}

}  // namespace
}  // namespace platemeter
