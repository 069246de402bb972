// platemeter grids list|show, platemeter cameras list|show: the master grids,
// fiducial sets and cameras known to platemeter (built-ins plus --definitions
// files and PLATEMETER_DEFINITIONS), as a listing, CSV or TOML.
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"

namespace platemeter::cli {
namespace {

DefinitionRegistry LoadRegistry(const GlobalOptions& global) {
  return DefinitionRegistry::Load(global.definition_files);
}

void PrintRow(const std::string& kind, const std::string& name, const std::string& points,
              const std::string& description) {
  std::cout << std::left << std::setw(14) << kind << std::setw(28) << name << std::setw(8) << points << description
            << '\n';
}

void ListAll(const DefinitionRegistry& registry, bool cameras_only) {
  PrintRow("kind", "name", "points", "description");
  if (!cameras_only) {
    for (const std::string& name : registry.GridNames()) {
      const MasterGrid& grid = registry.Grid(name);
      PrintRow("grid", name, std::to_string(grid.points.size()), grid.description);
    }
    for (const std::string& name : registry.FiducialSetNames()) {
      const FiducialSet& set = registry.Fiducials(name);
      PrintRow("fiducial_set", name, std::to_string(set.marks.size()), set.description);
    }
  }
  for (const std::string& name : registry.CameraNames()) {
    const CameraDefinition& camera = registry.Camera(name);
    // A camera's points: its reseau crosses plus its fiducials.
    size_t points = 0;
    if (!camera.grid.empty()) points += registry.Grid(camera.grid).points.size();
    if (!camera.fiducial_set.empty()) points += registry.Fiducials(camera.fiducial_set).marks.size();
    if (camera.format_corners_as_fiducials) points += 4;
    PrintRow("camera", name, std::to_string(points), camera.description);
  }
}

void RegisterGrids(CLI::App& app, GlobalOptions& global) {
  auto* grids = app.add_subcommand("grids", "master grids (reseau plates) and fiducial sets");
  grids->require_subcommand(1);

  auto* list = grids->add_subcommand("list", "list grids, fiducial sets and cameras with their point counts");
  list->callback([&global] { ListAll(LoadRegistry(global), false); });

  auto* show = grids->add_subcommand("show", "print a grid or fiducial set (CSV: id,x_mm,y_mm; or TOML)");
  auto name = std::make_shared<std::string>();
  auto format = std::make_shared<std::string>("csv");
  show->add_option("NAME", *name, "grid or fiducial set name (see `platemeter grids list`)")->required();
  show->add_option("--format", *format, "csv (default) or toml")->check(CLI::IsMember({"csv", "toml"}));
  show->callback([&global, name, format] {
    const DefinitionRegistry registry = LoadRegistry(global);
    if (const MasterGrid* grid = registry.FindGrid(*name)) {
      std::cout << (*format == "toml" ? ToToml(*grid) : ToCsv(*grid));
    } else if (const FiducialSet* set = registry.FindFiducials(*name)) {
      std::cout << (*format == "toml" ? ToToml(*set) : ToCsv(*set));
    } else {
      std::string known;
      for (const auto& names : {registry.GridNames(), registry.FiducialSetNames()}) {
        for (const std::string& known_name : names) known += (known.empty() ? "" : ", ") + known_name;
      }
      throw Error(*name, "unknown grid or fiducial set (known: " + known + ")");
    }
  });
}

void RegisterCameras(CLI::App& app, GlobalOptions& global) {
  auto* cameras = app.add_subcommand("cameras", "camera definitions (format, grid, fiducials, lens calibration)");
  cameras->require_subcommand(1);

  auto* list = cameras->add_subcommand("list", "list the cameras");
  list->callback([&global] { ListAll(LoadRegistry(global), true); });

  auto* show = cameras->add_subcommand("show", "print a camera definition as TOML");
  auto name = std::make_shared<std::string>();
  show->add_option("NAME", *name, "camera name (see `platemeter cameras list`)")->required();
  show->callback([&global, name] { std::cout << ToToml(LoadRegistry(global).Camera(*name)); });
}

}  // namespace

void RegisterGridsCommand(CLI::App& app, GlobalOptions& global) {
  RegisterGrids(app, global);
  RegisterCameras(app, global);
}

}  // namespace platemeter::cli
