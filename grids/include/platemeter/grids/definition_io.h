#pragma once
// Reading and writing the TOML definition format (docs/definitions.md) and
// writing grids and fiducial sets as CSV. toml++ stays inside grids/src.
#include <string>
#include <vector>

#include "platemeter/grids/definitions.h"

namespace platemeter {

// The definitions of one file (or built-in text), checked on their own:
// syntax, keys, types, finite numbers, ids. References from cameras to grids
// and fiducial sets are checked by DefinitionRegistry, which sees all files.
struct DefinitionFile {
  std::string origin;  // the file path (or "builtin/<name>.toml")
  std::vector<MasterGrid> grids;
  std::vector<FiducialSet> fiducial_sets;
  std::vector<CameraDefinition> cameras;
  // 1-based source line of each definition's table, in the same order (0 if unknown).
  std::vector<int> grid_lines, fiducial_set_lines, camera_lines;
};

// Parses `text`; `origin` names it in errors. Throws platemeter::Error
// ("<origin>: line N: <what is wrong>") on any problem.
DefinitionFile ReadDefinitions(const std::string& text, const std::string& origin);
// Reads and parses a file; an unreadable file is an Error naming it.
DefinitionFile ReadDefinitionFile(const std::string& path);

// TOML text of one definition, in the format ReadDefinitions reads (a
// [[grid]], [[fiducial_set]] or [[camera]] table). Coordinates are written
// with as many decimals as the set needs (4 for the seed tables), other
// numbers in their shortest exact form, so reading the text back gives the
// same values.
std::string ToToml(const MasterGrid& grid);
std::string ToToml(const FiducialSet& fiducials);
std::string ToToml(const CameraDefinition& camera);

// CSV with the header "id,x_mm,y_mm", one row per point, coordinates as in ToToml.
std::string ToCsv(const MasterGrid& grid);
std::string ToCsv(const FiducialSet& fiducials);

}  // namespace platemeter
