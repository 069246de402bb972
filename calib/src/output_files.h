#pragma once
// Writing an adjustment's set of output files (calibration.json, report.md, ...):
// every text was formatted before, and the files land as one set (core/output_set.h:
// a staging folder renamed into place at the end), so a failure, a full disk or an
// interrupt leaves the earlier run's files, never a mix.
#include <string>
#include <utility>
#include <vector>

namespace platemeter {

// Writes each (name, text) into `dir`; returns the paths written. Throws
// platemeter::Error naming the folder or file.
std::vector<std::string> WriteOutputFiles(const std::string& dir,
                                          const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace platemeter
