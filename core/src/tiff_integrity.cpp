#include "tiff_integrity.h"

#include <tiffio.h>

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

namespace platemeter::internal {
namespace {

// Keeps libtiff's first message instead of letting it print to stderr.
int KeepFirstMessage(TIFF*, void* user_data, const char*, const char* format, va_list args) {
  auto* message = static_cast<std::string*>(user_data);
  if (message->empty()) {
    char buffer[512];
    std::vsnprintf(buffer, sizeof buffer, format, args);
    *message = buffer;
  }
  return 1;  // handled: do not call the global handler
}

int IgnoreWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

}  // namespace

bool LooksLikeTiff(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[4] = {};
  if (!in.read(reinterpret_cast<char*>(magic), 4)) return false;
  const bool little = magic[0] == 'I' && magic[1] == 'I' && (magic[2] == 42 || magic[2] == 43) && magic[3] == 0;
  const bool big = magic[0] == 'M' && magic[1] == 'M' && magic[2] == 0 && (magic[3] == 42 || magic[3] == 43);
  return little || big;
}

std::string TiffIntegrityProblem(const std::string& path, TiffBlock* block) {
  std::string message;
  std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(),
                                                                        TIFFOpenOptionsFree);
  TIFFOpenOptionsSetErrorHandlerExtR(options.get(), KeepFirstMessage, &message);
  TIFFOpenOptionsSetWarningHandlerExtR(options.get(), IgnoreWarning, nullptr);
  // "rm": read-only, no memory mapping (the file may be far larger than RAM).
  TIFF* tiff = TIFFOpenExt(path.c_str(), "rm", options.get());
  if (!tiff) return "not a readable TIFF (" + (message.empty() ? std::string("unknown error") : message) + ")";
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  const uint32_t count = TIFFIsTiled(tiff) ? TIFFNumberOfTiles(tiff) : TIFFNumberOfStrips(tiff);
  std::string problem;
  for (uint32_t strile = 0; strile < count && problem.empty(); ++strile) {
    int error = 0;
    const uint64_t offset = TIFFGetStrileOffsetWithErr(tiff, strile, &error);
    const uint64_t bytes = error ? 0 : TIFFGetStrileByteCountWithErr(tiff, strile, &error);
    if (error) {
      problem = "its strip/tile table cannot be read, the file may be truncated";
    } else if (offset + bytes > file_bytes) {
      problem = std::string(TIFFIsTiled(tiff) ? "tile " : "strip ") + std::to_string(strile) + " of " +
                std::to_string(count) + " ends at byte " + std::to_string(offset + bytes) + " but the file has " +
                std::to_string(file_bytes) + " bytes: the file is truncated";
    }
  }
  if (block) {
    block->tiled = TIFFIsTiled(tiff);
    uint32_t rows_per_strip = 0;
    if (block->tiled) {
      block->bytes = static_cast<double>(TIFFTileSize64(tiff));
    } else {
      block->bytes = static_cast<double>(TIFFStripSize64(tiff));
      uint32_t height = 0;
      TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &height);
      if (TIFFGetFieldDefaulted(tiff, TIFFTAG_ROWSPERSTRIP, &rows_per_strip) == 1 && rows_per_strip > height &&
          rows_per_strip != UINT32_MAX) {
        block->tag_rows = rows_per_strip;
        block->row_bytes = static_cast<double>(TIFFScanlineSize64(tiff));
      }
    }
  }
  TIFFClose(tiff);
  return problem;
}

}  // namespace platemeter::internal
