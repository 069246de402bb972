#pragma once
// SHA-256 of files and byte strings (OpenSSL's implementation), so a
// measurement file can name the exact scan it was measured on. Files are
// hashed in chunks: scans can be tens of GB.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace platemeter {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void Update(const void* data, size_t size);
  void Update(std::string_view bytes) { Update(bytes.data(), bytes.size()); }
  // The 32-byte digest; the object must not be updated afterwards.
  std::array<uint8_t, 32> Finish();
  // Lower-case hex of Finish().
  std::string FinishHex();

 private:
  struct Context;
  std::unique_ptr<Context> context_;
  bool finished_ = false;
};

// Lower-case hex digest of a byte string.
std::string Sha256Hex(std::string_view bytes);
// Lower-case hex digest of a file's contents; throws Error naming the file if it cannot be read.
std::string Sha256HexOfFile(const std::string& path);

}  // namespace platemeter
