#pragma once
// libtiff reads a strip that runs past the end of a truncated file as partial
// data without an error, so a truncated scan would be measured as if its lower
// part were blank. This check compares every strip/tile extent with the file
// size before any pixel is used (it reads only the directory).
#include <string>

namespace platemeter::internal {

// True if the file starts with a TIFF or BigTIFF signature.
bool LooksLikeTiff(const std::string& path);

// Empty if every strip or tile of the first directory lies inside the file;
// otherwise the reason, on one line.
std::string TiffIntegrityProblem(const std::string& path);

}  // namespace platemeter::internal
