// WriteOutputFiles (output_files.h).
#include "output_files.h"

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/measure/atomic_file.h"

namespace platemeter {

std::vector<std::string> WriteOutputFiles(const std::string& dir,
                                          const std::vector<std::pair<std::string, std::string>>& files) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw Error(dir, "cannot create the output folder: " + error.message());
  std::vector<std::string> written;
  for (const auto& [name, text] : files) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    WriteFileAtomically(path, text);
    written.push_back(path);
  }
  return written;
}

}  // namespace platemeter
