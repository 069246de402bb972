#include "platemeter/core/atomic_file.h"

#include <filesystem>
#include <fstream>

#include "platemeter/core/error.h"

namespace platemeter {

void WriteFileAtomicallyThrough(const std::string& path, const std::string& temp_path, std::string_view contents) {
  namespace fs = std::filesystem;
  const fs::path target(path), temp(temp_path);
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path, "cannot create the temporary file " + temp.string());
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      fs::remove(temp, ignored);
      throw Error(path, "write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw Error(path, "cannot rename into place (" + ec.message() + ")");
  }
}

void WriteFileAtomically(const std::string& path, std::string_view contents) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  // Same folder as the target so the rename stays on one file system; the
  // ".partial." infix is ignored by git (.gitignore) and by the readers.
  const fs::path temp = target.parent_path() /
                        ("." + target.stem().string() + ".partial" + target.extension().string());
  WriteFileAtomicallyThrough(path, temp.string(), contents);
}

}  // namespace platemeter
