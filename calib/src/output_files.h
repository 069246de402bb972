#pragma once
// Writing an adjustment's set of output files (calibration.json, report.md, ...):
// the folder is created, every text was formatted before (a failure leaves no
// partial set), and each file is written atomically (temporary name + rename).
#include <string>
#include <utility>
#include <vector>

namespace platemeter {

// Writes each (name, text) into `dir`; returns the paths written. Throws
// platemeter::Error naming the folder or file.
std::vector<std::string> WriteOutputFiles(const std::string& dir,
                                          const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace platemeter
