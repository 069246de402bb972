// Placeholder until the grids library lands: replaced by the grids work.
#include "commands.h"
namespace platemeter::cli {
void RegisterGridsCommand(CLI::App&, GlobalOptions&) {}
}  // namespace platemeter::cli
