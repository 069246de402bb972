// RemoveStalePlots and PrintWritten (written_outputs.h).
#include "written_outputs.h"

#include <filesystem>
#include <iostream>
#include <set>

namespace platemeter::cli {

void RemoveStalePlots(const std::string& dir, const std::vector<std::string>& written) {
  std::set<std::string> kept;
  for (const std::string& path : written) kept.insert(std::filesystem::path(path).filename().string());
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(dir) / "plots", error)) {
    const std::string extension = entry.path().extension().string();
    if ((extension == ".png" || extension == ".svg") && !kept.count(entry.path().filename().string())) {
      std::filesystem::remove(entry.path(), error);
    }
  }
}

void PrintWritten(const std::string& dir, const std::vector<std::string>& written) {
  int plots = 0;
  for (const std::string& path : written) {
    if (path.find("/plots/") != std::string::npos) {
      ++plots;
    } else {
      std::cout << "wrote " << path << '\n';
    }
  }
  if (plots > 0) std::cout << "wrote " << plots << " plot files (PNG and SVG) into " << dir << "/plots\n";
}

}  // namespace platemeter::cli
