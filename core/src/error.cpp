#include "platemeter/core/error.h"

namespace platemeter {

std::string OneLine(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  bool pending_space = false;
  for (char c : text) {
    if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
      pending_space = !out.empty();
      continue;
    }
    if (pending_space) out.push_back(' ');
    pending_space = false;
    out.push_back(c);
  }
  return out;
}

Error::Error(const std::string& subject, const std::string& reason)
    : std::runtime_error(OneLine(subject.empty() ? reason : subject + ": " + reason)),
      subject_(subject),
      reason_(OneLine(reason)) {}

}  // namespace platemeter
