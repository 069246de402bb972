#include "platemeter/batch/temporaries.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"

namespace platemeter {
namespace fs = std::filesystem;

bool IsTemporaryName(const std::string& file_name) {
  return file_name.size() > 1 && file_name[0] == '.' && file_name.find(".partial") != std::string::npos;
}

int RemoveTemporaries(const std::string& folder) {
  int removed = 0;
  std::error_code ec;
  std::vector<fs::path> doomed;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (IsTemporaryName(it->path().filename().string())) doomed.push_back(it->path());
  }
  for (const fs::path& p : doomed) {
    std::error_code e;
    if (fs::remove_all(p, e) > 0) ++removed;  // a file, or an output set's staging folder (core/output_set.h)
  }
  return removed;
}

void WriteSharedFileAtomically(const std::string& path, const std::string& contents) {
  const fs::path target(path);
  // core/atomic_file.h's temporary name is fixed per target: two shards finishing at the
  // same moment would write into the same temporary. The pid makes it unique per process.
  std::string temp_name = ".";
  temp_name += target.filename().string();
  temp_name += ".partial." + std::to_string(::getpid());
  const fs::path temp = target.parent_path() / temp_name;
  WriteFileAtomicallyThrough(path, temp.string(), contents);
}

}  // namespace platemeter
