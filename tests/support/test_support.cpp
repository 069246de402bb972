#include "support/test_support.h"

#include <sys/resource.h>
#include <sys/wait.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <unistd.h>

namespace platemeter::testing {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device random;
  path_ = std::filesystem::temp_directory_path() /
          ("platemeter-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
           std::to_string(random()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

namespace {
std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// Runs `command` through the shell with stdout and stderr captured.
CommandResult RunCaptured(const std::string& command, const TempDir& dir) {
  const std::string out_path = dir.file("stdout"), err_path = dir.file("stderr");
  const int status = std::system((command + " >'" + out_path + "' 2>'" + err_path + "'").c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = ReadAll(out_path);
  result.err = ReadAll(err_path);
  return result;
}
}  // namespace

CommandResult RunPlatemeter(const std::string& arguments) {
  TempDir dir;
  return RunCaptured(std::string("'") + PLATEMETER_BIN + "' " + arguments, dir);
}

CommandResult RunShell(const std::string& script, bool private_mounts) {
  TempDir dir;
  std::ofstream(dir.file("script.sh")) << "PLATEMETER='" << PLATEMETER_BIN << "'\n" << script << "\n";
  return RunCaptured(std::string(private_mounts ? "unshare -rm " : "") + "sh '" + dir.file("script.sh") + "'", dir);
}

bool PrivateMountsAvailable() {
  static const bool available =
      std::system("unshare -rm sh -c 'd=$(mktemp -d) && mount -t tmpfs -o size=64k tmpfs \"$d\" && umount \"$d\" "
                  "&& rmdir \"$d\"' >/dev/null 2>&1") == 0;
  return available;
}

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KB on Linux
}

std::string ReadTextFile(const std::string& path) { return ReadAll(path); }

}  // namespace platemeter::testing
