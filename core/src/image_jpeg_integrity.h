#pragma once
// libjpeg reads a JPEG that ends early with only a warning ("Premature end of
// JPEG file") and fills the rest with grey, which OpenImageIO's image cache does
// not pass on: a truncated JPEG scan would be measured as if its lower part were
// blank. A JPEG must end with the end-of-image marker FF D9, and the entropy-coded
// data cannot contain that byte pair (a coded FF is always followed by 00 or a
// restart marker D0..D7), so its absence at the end means the file was cut.
// Reads only the file's last bytes.
#include <string>

namespace platemeter::internal {

// True if the file starts with the JPEG start-of-image marker FF D8 FF.
bool LooksLikeJpeg(const std::string& path);

// Empty if the file ends with the end-of-image marker (after any zero padding);
// otherwise the reason, on one line.
std::string JpegIntegrityProblem(const std::string& path);

}  // namespace platemeter::internal
