#pragma once
// Warnings and progress go to stderr through one replaceable sink, so the CLI
// can keep stdout for results and tests can capture what was said.
#include <functional>
#include <string>

namespace platemeter {

using LogSink = std::function<void(const std::string& line)>;

// Installs a sink (nullptr restores the default: "warning: ..." on stderr).
void SetWarningSink(LogSink sink);
void Warn(const std::string& message);

}  // namespace platemeter
