#pragma once
// A number as the shortest text that reads back to the same double (std::to_chars), for
// the files and messages that must round-trip what they print.
#include <charconv>
#include <string>

namespace platemeter {

inline std::string ShortestText(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

}  // namespace platemeter
