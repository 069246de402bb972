#pragma once
// Error policy (DESIGN.md): bad input throws platemeter::Error naming the file
// (or other subject) and the reason; the CLI prints what() on one line and exits
// non-zero. Never a silent default.
#include <stdexcept>
#include <string>

namespace platemeter {

class Error : public std::runtime_error {
 public:
  // `subject` is usually a file path; `reason` says what is wrong with it.
  Error(const std::string& subject, const std::string& reason);
  const std::string& subject() const { return subject_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string subject_;
  std::string reason_;
};

// A failure of the machine rather than of the input: disk full, no permission, an
// I/O error, a folder that cannot be created. The same work may succeed when run
// again, so batch retries such a scan on a plain rerun (docs/batch.md), while an
// input defect (a bad scan, the wrong camera) is remembered.
class EnvironmentError : public Error {
 public:
  using Error::Error;
};

// Folds a multi-line library message (OpenImageIO, toml++) into one line.
std::string OneLine(const std::string& text);

}  // namespace platemeter
