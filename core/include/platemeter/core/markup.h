#pragma once
// Text into XML or HTML (MicMac exports, the batch's HTML index, the reports).
#include <string>

namespace platemeter {

// s with & < > " replaced by their entities (element text and attribute values), and
// every byte sequence XML 1.0 cannot hold -- invalid UTF-8 (a file name in another
// encoding), control characters other than tab and newline -- replaced by U+FFFD,
// so the document stays well-formed whatever the text.
std::string EscapeMarkup(const std::string& s);

}  // namespace platemeter
