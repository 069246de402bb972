#include "platemeter/batch/progress.h"

#include <unistd.h>

#include <cmath>

namespace platemeter {

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char buffer[32];
  if (s >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%ldh%02ldm", s / 3600, (s % 3600) / 60);
  } else if (s >= 60) {
    std::snprintf(buffer, sizeof buffer, "%ldm%02lds", s / 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%lds", s);
  }
  return buffer;
}

ProgressReporter::ProgressReporter(size_t total, bool terminal, std::FILE* stream)
    : total_(total), terminal_(terminal), stream_(stream), start_(std::chrono::steady_clock::now()) {}

bool ProgressReporter::IsTerminal(std::FILE* stream) { return ::isatty(::fileno(stream)) == 1; }

double ProgressReporter::ScansPerHourLocked() const {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return processed_ == 0 || elapsed <= 0 ? 0.0 : 3600.0 * static_cast<double>(processed_) / elapsed;
}

double ProgressReporter::ScansPerHour() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return ScansPerHourLocked();
}

std::string ProgressReporter::StatusLineLocked() const {
  char buffer[256];
  const double rate = ScansPerHourLocked();
  // Skipped scans take no time: the ETA counts the scans still to process at the processing rate.
  const double eta = rate > 0 ? 3600.0 * static_cast<double>(total_ - done_) / rate : NAN;
  std::snprintf(buffer, sizeof buffer, "batch: %zu/%zu done (%zu failed, %zu skipped), %.0f scans/h, ETA %s", done_,
                total_, failed_, skipped_, rate, rate > 0 ? FormatDuration(eta).c_str() : "?");
  return buffer;
}

void ProgressReporter::ScanFinished(const std::string& stem, const std::string& status, double seconds,
                                    const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++done_;
  const bool skipped = status.rfind("skipped", 0) == 0 || status == "busy";  // took no time here
  if (skipped) {
    ++skipped_;
  } else {
    ++processed_;
  }
  if (status == "failed" || status == "skipped-failed") ++failed_;
  if (terminal_) {
    // Failures stay on screen above the updating line; everything else only moves the line.
    if (status == "failed") std::fprintf(stream_, "\r\033[Kbatch: %s failed: %s\n", stem.c_str(), reason.c_str());
    std::fprintf(stream_, "\r\033[K%s", StatusLineLocked().c_str());
    line_open_ = true;
  } else {
    std::fprintf(stream_, "batch: [%zu/%zu] %s %s", done_, total_, stem.c_str(), status.c_str());
    if (!skipped) std::fprintf(stream_, " (%.1f s)", seconds);
    if (!reason.empty()) std::fprintf(stream_, ": %s", reason.c_str());
    std::fprintf(stream_, "\n");
  }
  std::fflush(stream_);
}

void ProgressReporter::Tick() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!terminal_) return;
  std::fprintf(stream_, "\r\033[K%s", StatusLineLocked().c_str());
  line_open_ = true;
  std::fflush(stream_);
}

void ProgressReporter::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (terminal_ && line_open_) std::fprintf(stream_, "\n");
  line_open_ = false;
  std::fflush(stream_);
}

}  // namespace platemeter
