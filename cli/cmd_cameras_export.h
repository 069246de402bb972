#pragma once
// platemeter cameras export (cmd_cameras_export.cpp).
#include "commands.h"

namespace platemeter::cli {

void RegisterCamerasExport(CLI::App* cameras, GlobalOptions& global);

}  // namespace platemeter::cli
