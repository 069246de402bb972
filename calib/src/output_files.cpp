// WriteOutputFiles (output_files.h).
#include "output_files.h"

#include <filesystem>

#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/output_set.h"

namespace platemeter {

std::vector<std::string> WriteOutputFiles(const std::string& dir,
                                          const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::string> names;
  for (const auto& file : files) names.push_back(file.first);
  OutputSet outputs(dir, names);
  std::vector<std::string> written;
  for (const auto& [name, text] : files) {
    outputs.Write(name, [&text = text](const std::string& path) { WriteFileAtomically(path, text); });
    written.push_back(outputs.FinalPath(name));
  }
  outputs.Commit();
  return written;
}

}  // namespace platemeter
