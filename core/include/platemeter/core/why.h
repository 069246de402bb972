#pragma once
// The reason-out-parameter idiom of the checks (`bool Check(..., std::string* why)`).
#include <string>

namespace platemeter {

// Stores the reason (when asked for) and returns false, so a check can `return Fail(why, ...)`.
inline bool Fail(std::string* why, const std::string& reason) {
  if (why) *why = reason;
  return false;
}

}  // namespace platemeter
