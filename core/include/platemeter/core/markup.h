#pragma once
// Text into XML or HTML (MicMac exports, the batch's HTML index).
#include <string>

namespace platemeter {

// s with & < > " replaced by their entities (element text and attribute values).
inline std::string EscapeMarkup(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace platemeter
