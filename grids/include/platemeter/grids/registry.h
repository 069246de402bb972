#pragma once
// All known definitions: the built-ins (grids/builtin/*.toml, compiled in),
// then the files named in PLATEMETER_DEFINITIONS (colon-separated), then the
// files given by the caller (the CLI's --definitions). A user definition with
// a built-in's name replaces it with a warning; two user definitions with one
// name are an error. Grids and fiducial sets share one namespace (a name
// shown by `platemeter grids show` must be unambiguous); cameras have their own.
#include <string>
#include <utility>
#include <vector>

#include "platemeter/grids/definition_io.h"
#include "platemeter/grids/definitions.h"
#include "platemeter/grids/lens_models.h"

namespace platemeter {

// The built-in definition texts as {"builtin/<file>.toml", text}; generated
// from grids/builtin/*.toml by grids/embed_builtins.cmake.
const std::vector<std::pair<std::string, std::string>>& BuiltinDefinitionTexts();

struct DefinitionLoadOptions {
  bool use_environment = true;  // also read the files named in PLATEMETER_DEFINITIONS
};

class DefinitionRegistry {
 public:
  // The built-ins only.
  DefinitionRegistry();

  // Built-ins, then PLATEMETER_DEFINITIONS (unless switched off), then `user_files`.
  // Throws platemeter::Error naming the file and the problem.
  static DefinitionRegistry Load(const std::vector<std::string>& user_files,
                                 const DefinitionLoadOptions& options = {});
  // Built-ins plus user definitions given as {origin, text} (tests, embedding).
  static DefinitionRegistry FromTexts(const std::vector<std::pair<std::string, std::string>>& user_texts);

  // Lookups: throw platemeter::Error naming the unknown name and listing the known ones.
  const MasterGrid& Grid(const std::string& name) const;
  const FiducialSet& Fiducials(const std::string& name) const;
  const CameraDefinition& Camera(const std::string& name) const;
  // nullptr if there is none of that name.
  const MasterGrid* FindGrid(const std::string& name) const;
  const FiducialSet* FindFiducials(const std::string& name) const;
  const CameraDefinition* FindCamera(const std::string& name) const;

  // Sorted names.
  std::vector<std::string> GridNames() const;
  std::vector<std::string> FiducialSetNames() const;
  std::vector<std::string> CameraNames() const;
  // The file (or "builtin/<file>.toml") a definition came from; empty if unknown name.
  std::string OriginOf(const std::string& name) const;  // grid or fiducial set
  std::string CameraOriginOf(const std::string& name) const;

 private:
  struct Origin {
    std::string file;
    int line = 0;
    bool builtin = false;
  };
  void Add(const DefinitionFile& file, bool builtin);
  void CheckReferences() const;

  std::vector<std::pair<MasterGrid, Origin>> grids_;
  std::vector<std::pair<FiducialSet, Origin>> fiducial_sets_;
  std::vector<std::pair<CameraDefinition, Origin>> cameras_;
};

}  // namespace platemeter
