#include "platemeter/grids/registry.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"

namespace platemeter {
namespace {

template <typename Entries>
auto* FindIn(Entries& entries, const std::string& name) {
  for (auto& entry : entries) {
    if (entry.first.name == name) return &entry;
  }
  return static_cast<decltype(&entries.front())>(nullptr);
}

template <typename Entries>
std::vector<std::string> NamesOf(const Entries& entries) {
  std::vector<std::string> names;
  for (const auto& entry : entries) names.push_back(entry.first.name);
  std::sort(names.begin(), names.end());
  return names;
}

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out.empty() ? "none" : out;
}

std::string Where(const std::string& file, int line) {
  return line > 0 ? file + " line " + std::to_string(line) : file;
}

std::vector<std::string> SplitPathList(const std::string& list) {
  std::vector<std::string> paths;
  std::stringstream stream(list);
  std::string path;
  while (std::getline(stream, path, ':')) {
    if (!path.empty()) paths.push_back(path);
  }
  return paths;
}

// The built-ins are parsed once per process.
const std::vector<DefinitionFile>& BuiltinDefinitionFiles() {
  static const std::vector<DefinitionFile> files = [] {
    std::vector<DefinitionFile> parsed;
    for (const auto& [origin, text] : BuiltinDefinitionTexts()) parsed.push_back(ReadDefinitions(text, origin));
    return parsed;
  }();
  return files;
}

}  // namespace

DefinitionRegistry::DefinitionRegistry() {
  for (const DefinitionFile& file : BuiltinDefinitionFiles()) Add(file, true);
  CheckReferences();
}

DefinitionRegistry DefinitionRegistry::Load(const std::vector<std::string>& user_files,
                                            const DefinitionLoadOptions& options) {
  DefinitionRegistry registry;
  std::vector<std::string> files;
  if (options.use_environment) {
    if (const char* list = std::getenv("PLATEMETER_DEFINITIONS")) {
      for (const std::string& path : SplitPathList(list)) {
        if (!std::filesystem::is_regular_file(path)) {
          throw Error(path, "no such definition file (named in PLATEMETER_DEFINITIONS)");
        }
        files.push_back(path);
      }
    }
  }
  files.insert(files.end(), user_files.begin(), user_files.end());
  for (const std::string& path : files) registry.Add(ReadDefinitionFile(path), false);
  registry.CheckReferences();
  return registry;
}

DefinitionRegistry DefinitionRegistry::FromTexts(const std::vector<std::pair<std::string, std::string>>& user_texts) {
  DefinitionRegistry registry;
  for (const auto& [origin, text] : user_texts) registry.Add(ReadDefinitions(text, origin), false);
  registry.CheckReferences();
  return registry;
}

void DefinitionRegistry::Add(const DefinitionFile& file, bool builtin) {
  // Grids and fiducial sets share a namespace; a built-in of either kind is replaced by a user's.
  auto claim = [&](const std::string& kind, const std::string& name, int line, bool camera) {
    const Origin* previous = nullptr;
    if (camera) {
      if (auto* entry = FindIn(cameras_, name)) previous = &entry->second;
    } else if (auto* entry = FindIn(grids_, name)) {
      previous = &entry->second;
    } else if (auto* entry = FindIn(fiducial_sets_, name)) {
      previous = &entry->second;
    }
    if (!previous) return;
    if (!previous->builtin || builtin) {
      throw Error(file.origin, (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) + kind + " '" +
                                   name + "' is already defined in " + Where(previous->file, previous->line));
    }
    Warn(Where(file.origin, line) + ": " + kind + " '" + name + "' replaces the built-in definition from " +
         previous->file);
    auto drop = [&](auto& entries) {
      entries.erase(std::remove_if(entries.begin(), entries.end(), [&](const auto& e) { return e.first.name == name; }),
                    entries.end());
    };
    if (camera) {
      drop(cameras_);
    } else {
      drop(grids_);
      drop(fiducial_sets_);
    }
  };
  for (size_t k = 0; k < file.grids.size(); ++k) {
    const int line = k < file.grid_lines.size() ? file.grid_lines[k] : 0;
    claim("grid", file.grids[k].name, line, false);
    grids_.push_back({file.grids[k], Origin{file.origin, line, builtin}});
  }
  for (size_t k = 0; k < file.fiducial_sets.size(); ++k) {
    const int line = k < file.fiducial_set_lines.size() ? file.fiducial_set_lines[k] : 0;
    claim("fiducial_set", file.fiducial_sets[k].name, line, false);
    fiducial_sets_.push_back({file.fiducial_sets[k], Origin{file.origin, line, builtin}});
  }
  for (size_t k = 0; k < file.cameras.size(); ++k) {
    const int line = k < file.camera_lines.size() ? file.camera_lines[k] : 0;
    claim("camera", file.cameras[k].name, line, true);
    cameras_.push_back({file.cameras[k], Origin{file.origin, line, builtin}});
  }
}

void DefinitionRegistry::CheckReferences() const {
  for (const auto& [camera, origin] : cameras_) {
    auto fail = [&](const std::string& problem) {
      throw Error(origin.file,
                  (origin.line > 0 ? "line " + std::to_string(origin.line) + ": " : std::string()) + "camera '" +
                      camera.name + "': " + problem);
    };
    if (!camera.grid.empty() && !FindGrid(camera.grid)) {
      fail("unknown grid '" + camera.grid + "' (known grids: " + Join(GridNames()) + ")");
    }
    if (!camera.fiducial_set.empty() && !FindFiducials(camera.fiducial_set)) {
      fail("unknown fiducial_set '" + camera.fiducial_set + "' (known fiducial sets: " + Join(FiducialSetNames()) +
           ")");
    }
  }
}

const MasterGrid* DefinitionRegistry::FindGrid(const std::string& name) const {
  auto* entry = FindIn(grids_, name);
  return entry ? &entry->first : nullptr;
}
const FiducialSet* DefinitionRegistry::FindFiducials(const std::string& name) const {
  auto* entry = FindIn(fiducial_sets_, name);
  return entry ? &entry->first : nullptr;
}
const CameraDefinition* DefinitionRegistry::FindCamera(const std::string& name) const {
  auto* entry = FindIn(cameras_, name);
  return entry ? &entry->first : nullptr;
}

const MasterGrid& DefinitionRegistry::Grid(const std::string& name) const {
  if (const MasterGrid* grid = FindGrid(name)) return *grid;
  throw Error(name, "unknown grid (known grids: " + Join(GridNames()) + ")");
}
const FiducialSet& DefinitionRegistry::Fiducials(const std::string& name) const {
  if (const FiducialSet* set = FindFiducials(name)) return *set;
  throw Error(name, "unknown fiducial set (known fiducial sets: " + Join(FiducialSetNames()) + ")");
}
const CameraDefinition& DefinitionRegistry::Camera(const std::string& name) const {
  if (const CameraDefinition* camera = FindCamera(name)) return *camera;
  throw Error(name, "unknown camera (known cameras: " + Join(CameraNames()) + ")");
}

std::vector<std::string> DefinitionRegistry::GridNames() const { return NamesOf(grids_); }
std::vector<std::string> DefinitionRegistry::FiducialSetNames() const { return NamesOf(fiducial_sets_); }
std::vector<std::string> DefinitionRegistry::CameraNames() const { return NamesOf(cameras_); }

std::string DefinitionRegistry::OriginOf(const std::string& name) const {
  if (auto* entry = FindIn(grids_, name)) return entry->second.file;
  if (auto* entry = FindIn(fiducial_sets_, name)) return entry->second.file;
  return {};
}
std::string DefinitionRegistry::CameraOriginOf(const std::string& name) const {
  auto* entry = FindIn(cameras_, name);
  return entry ? entry->second.file : std::string();
}

}  // namespace platemeter
