#include "image_jpeg_integrity.h"

#include <algorithm>
#include <fstream>
#include <vector>

namespace platemeter::internal {

bool LooksLikeJpeg(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[3] = {};
  if (!in.read(reinterpret_cast<char*>(magic), 3)) return false;
  return magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF;
}

std::string JpegIntegrityProblem(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return "cannot be opened for reading";
  const std::streamoff file_bytes = in.tellg();
  // Some writers pad the file with zero bytes after the marker; 4 KiB of tail covers that.
  constexpr std::streamoff kTailBytes = 4096;
  const std::streamoff tail = std::min(file_bytes, kTailBytes);
  std::vector<unsigned char> bytes(static_cast<size_t>(tail));
  in.seekg(file_bytes - tail);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), tail)) return "cannot read the end of the file";
  size_t end = bytes.size();
  while (end > 0 && bytes[end - 1] == 0x00) --end;
  if (end >= 2 && bytes[end - 2] == 0xFF && bytes[end - 1] == 0xD9) return "";
  return "the JPEG data has no end-of-image marker (FF D9) after " + std::to_string(file_bytes) +
         " bytes: the file is truncated";
}

}  // namespace platemeter::internal
