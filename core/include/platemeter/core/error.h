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

// Folds a multi-line library message (OpenImageIO, toml++) into one line.
std::string OneLine(const std::string& text);

}  // namespace platemeter
