// TIFF headers the fuzz harness (tests/fuzz, tiff_header) found to crash
// `platemeter info` / Image::Open: std::bad_alloc escaping as a non-Error, then an
// OpenImageIO assertion aborting the process (or a 4 GB tile read for 11 s before an
// abort). Image::Open now checks a tile against the image cache's memory, a strip
// against the memory limit and a RowsPerStrip beyond the height (core/src/image.cpp)
// before any pixel is read. They run the CLI, so an abort cannot take the test down.
#include <gtest/gtest.h>

#include <string>

#include "support/test_support.h"

namespace platemeter {
namespace {

std::string Regression(const std::string& name) {
  return std::string(PLATEMETER_SOURCE_DIR) + "/tests/fuzz/regressions/" + name;
}

void ExpectOneLineError(const std::string& name) {
  const testing::CommandResult r = testing::RunPlatemeter("info " + Regression(name));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("platemeter: error: " + Regression(name) + ": ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;  // one line
}

TEST(FuzzTiffRegression, WidthOf2To31PixelsIsAnError) { ExpectOneLineError("tiff-width-2e31.tif"); }
TEST(FuzzTiffRegression, HugeRowsPerStripIsAnError) { ExpectOneLineError("tiff-rows-per-strip-huge.tif"); }
TEST(FuzzTiffRegression, HugeTileWidthIsAnError) { ExpectOneLineError("tiff-tile-width-huge.tif"); }
TEST(FuzzTiffRegression, AFourGigabyteTileIsAnErrorNotAnAbort) { ExpectOneLineError("tiff-tile-4gb.tif"); }

}  // namespace
}  // namespace platemeter
