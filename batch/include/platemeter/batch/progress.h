#pragma once
// Progress of a batch: on a terminal one updating line (done/total, failed,
// skipped, scans per hour, ETA); otherwise one plain log line per scan.
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace platemeter {

class ProgressReporter {
 public:
  // `total`: the scans of this run; `terminal`: draw the updating line; `stream`: usually stderr.
  ProgressReporter(size_t total, bool terminal, std::FILE* stream);
  // A scan finished: status "ok", "failed", "skipped" (current outputs) or "skipped-failed".
  void ScanFinished(const std::string& stem, const std::string& status, double seconds, const std::string& reason);
  // Redraws the terminal line (the ETA moves between scans).
  void Tick();
  // Ends the terminal line.
  void Finish();
  // Scans per hour over the scans actually processed (skips excluded); 0 before the first.
  double ScansPerHour() const;

  static bool IsTerminal(std::FILE* stream);

 private:
  std::string StatusLineLocked() const;
  double ScansPerHourLocked() const;
  size_t total_;
  bool terminal_;
  std::FILE* stream_;
  mutable std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  size_t done_ = 0, failed_ = 0, skipped_ = 0, processed_ = 0;
  bool line_open_ = false;
};

// "3m05s", "1h02m", "45s".
std::string FormatDuration(double seconds);

}  // namespace platemeter
