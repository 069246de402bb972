#pragma once
// Running a tool as its own process from a benchmark, so that its wall time,
// CPU time and peak RSS are its own (wait4's rusage). The child's peak RSS
// counts the pages the parent has resident at fork: free big structures first.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace platemeter::bench {

struct ToolRun {
  bool ok = false;           // exited with 0
  int exit_code = -1;        // exit status, or 128 + signal
  double seconds = 0.0;      // wall
  double cpu_seconds = 0.0;  // user + system
  double peak_rss_mb = 0.0;
};

// Runs args[0] with args; its stdout and stderr go to `log`.
inline ToolRun RunProcess(const std::vector<std::string>& args, const std::string& log) {
  ToolRun run;
  std::fflush(stdout);  // or the child would write our buffered lines again
  std::fflush(stderr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t child = fork();
  if (child == 0) {
    if (!std::freopen(log.c_str(), "w", stdout) || !std::freopen(log.c_str(), "a", stderr)) _exit(126);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(child, &status, 0, &usage);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.peak_rss_mb = usage.ru_maxrss / 1024.0;
  run.cpu_seconds = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.ok = run.exit_code == 0;
  return run;
}

}  // namespace platemeter::bench
