#pragma once
// Shared helpers for the test suites: temporary folders, running the CLI.
#include <filesystem>
#include <string>

namespace platemeter::testing {

// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs the platemeter binary with a shell-quoted argument string.
CommandResult RunPlatemeter(const std::string& arguments);

// Runs the shell script (PLATEMETER is set to the binary's path); with private_mounts, in a private
// mount namespace as root of a user namespace (`unshare -rm`), where it may mount a tmpfs.
CommandResult RunShell(const std::string& script, bool private_mounts = false);

// Whether `unshare -rm` can give a test a private mount namespace (a tmpfs of a set size
// for a full disk, a read-only folder that root cannot write either).
bool PrivateMountsAvailable();

// The whole content of a text file ("" if it cannot be read).
std::string ReadTextFile(const std::string& path);

// Peak resident set size of this process so far, in MB.
double PeakRssMb();

}  // namespace platemeter::testing
