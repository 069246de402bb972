// WriteOutputFiles (output_files.h).
#include "output_files.h"

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"

namespace platemeter {

std::vector<std::string> WriteOutputFiles(const std::string& dir,
                                          const std::vector<std::pair<std::string, std::string>>& files) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw Error(dir, "cannot create the output folder: " + error.message());
  std::vector<std::string> written;
  for (const auto& [name, text] : files) {
    const std::filesystem::path full = std::filesystem::path(dir) / name;
    // A name with a folder (plots/x.png): the folder too.
    if (full.parent_path() != std::filesystem::path(dir)) {
      std::filesystem::create_directories(full.parent_path(), error);
      if (error) throw Error(full.parent_path().string(), "cannot create the output folder: " + error.message());
    }
    const std::string path = full.string();
    WriteFileAtomically(path, text);
    written.push_back(path);
  }
  return written;
}

}  // namespace platemeter
