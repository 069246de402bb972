#pragma once
// libtiff reads a strip that runs past the end of a truncated file as partial
// data without an error, so a truncated scan would be measured as if its lower
// part were blank. This check compares every strip/tile extent with the file
// size before any pixel is used (it reads only the directory).
#include <cstdint>
#include <string>

namespace platemeter::internal {

// True if the file starts with a TIFF or BigTIFF signature.
bool LooksLikeTiff(const std::string& path);

// What a reader must hold at once: one decoded tile (tiled files) or strip.
struct TiffBlock {
  bool tiled = false;
  double bytes = 0.0;  // bytes of one tile, or of one strip of min(RowsPerStrip, height) rows
  // Strips: RowsPerStrip beyond the image's height (other than the TIFF default 2^32 - 1, "one strip")
  // is what OpenImageIO allocates rows for: `tag_rows` rows of `row_bytes` (0 when the tag is in range).
  double tag_rows = 0.0, row_bytes = 0.0;
};

// Empty if every strip or tile of the first directory lies inside the file;
// otherwise the reason, on one line. `block` (if given) gets the block size.
std::string TiffIntegrityProblem(const std::string& path, TiffBlock* block = nullptr);

}  // namespace platemeter::internal
