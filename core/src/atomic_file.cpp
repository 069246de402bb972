#include "platemeter/core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// The OS's reason for the last failed call, e.g. "No space left on device".
std::string OsReason(int error_number) { return std::strerror(error_number); }

// Writes all of `contents` to a new file `path`; returns 0 or the errno of the failure.
int WriteWhole(const std::string& path, std::string_view contents) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return errno;
  size_t done = 0;
  int error_number = 0;
  while (done < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + done, contents.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error_number = n < 0 ? errno : EIO;
      break;
    }
    done += static_cast<size_t>(n);
  }
  // close() can report a delayed write error (NFS, quotas).
  if (::close(fd) != 0 && error_number == 0) error_number = errno;
  return error_number;
}

// Same folder as the target so the rename stays on one file system; the
// ".partial." infix is ignored by git (.gitignore) and by the readers.
std::string TempPathFor(const std::string& path) {
  const std::filesystem::path target(path);
  return (target.parent_path() / ("." + target.stem().string() + ".partial" + target.extension().string())).string();
}

// Renames the finished temporary file over `path`; removes it if that fails.
void RenameIntoPlace(const std::string& path, const std::string& temp_path) {
  std::error_code ec;
  std::filesystem::rename(temp_path, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temp_path, ignored);
    throw EnvironmentError(path, "cannot rename into place (" + ec.message() + ")");
  }
}

}  // namespace

void WriteFileAtomicallyThrough(const std::string& path, const std::string& temp_path, std::string_view contents) {
  namespace fs = std::filesystem;
  const int error_number = WriteWhole(temp_path, contents);
  if (error_number != 0) {
    std::error_code ignored;
    fs::remove(temp_path, ignored);
    throw EnvironmentError(path, "write failed (" + OsReason(error_number) + ")");
  }
  RenameIntoPlace(path, temp_path);
}

void WriteFileAtomically(const std::string& path, std::string_view contents) {
  WriteFileAtomicallyThrough(path, TempPathFor(path), contents);
}

void WriteFileAtomicallyStreamed(const std::string& path, const std::function<void(std::ostream&)>& put) {
  const std::string temp_path = TempPathFor(path);
  try {
    std::ofstream out(temp_path, std::ios::binary | std::ios::trunc);
    if (!out) throw EnvironmentError(path, "write failed (" + OsReason(errno) + ")");
    put(out);
    out.close();  // flushes; a full disk shows here at the latest
    if (!out) throw EnvironmentError(path, "write failed (" + OsReason(errno != 0 ? errno : EIO) + ")");
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temp_path, ignored);
    throw;
  }
  RenameIntoPlace(path, temp_path);
}

}  // namespace platemeter
