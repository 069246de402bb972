#pragma once
// What a test checks in a written HTML report: the links of a page, and
// whether a file is a whole PNG or SVG (header only: the test folder compiles *_test.cpp only).
#include <string>
#include <vector>

namespace platemeter::testing {

struct PngSize {
  bool valid = false;  // signature, IHDR and IEND present
  int width = 0, height = 0;
};

// The values of every src="..." and href="..." attribute (in-page anchors "#..." left out).
// AttributeOfImage: the value of `attribute` in the <img> of `target` ("" if none).
// IsSvg: an SVG document: <svg ...> near the start, </svg> after it.
inline std::vector<std::string> LinkedFiles(const std::string& html) {
  std::vector<std::string> links;
  for (const char* attribute : {"src=\"", "href=\""}) {
    const std::string key = attribute;
    for (size_t at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) {
      const size_t start = at + key.size(), end = html.find('"', start);
      const std::string value = html.substr(start, end - start);
      if (!value.empty() && value[0] != '#') links.push_back(value);
    }
  }
  return links;
}

inline std::string AttributeOfImage(const std::string& html, const std::string& target, const std::string& attribute) {
  const size_t at = html.find("<img src=\"" + target + "\"");
  if (at == std::string::npos) return "";
  const size_t tag_end = html.find('>', at);
  const size_t a = html.find(" " + attribute + "=\"", at);
  if (a == std::string::npos || a > tag_end) return "";
  const size_t start = a + attribute.size() + 3;
  return html.substr(start, html.find('"', start) - start);
}

inline PngSize ReadPngSize(const std::string& bytes) {
  PngSize size;
  if (bytes.size() < 33 || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 || bytes.compare(12, 4, "IHDR") != 0) {
    return size;
  }
  auto be32 = [&](size_t at) {
    return (static_cast<unsigned char>(bytes[at]) << 24) | (static_cast<unsigned char>(bytes[at + 1]) << 16) |
           (static_cast<unsigned char>(bytes[at + 2]) << 8) | static_cast<unsigned char>(bytes[at + 3]);
  };
  size.width = static_cast<int>(be32(16));
  size.height = static_cast<int>(be32(20));
  size.valid = bytes.find("IEND") != std::string::npos && bytes.size() >= 12;
  return size;
}

inline bool IsSvg(const std::string& bytes) {
  const size_t open = bytes.find("<svg");
  const size_t close = bytes.rfind("</svg>");
  return open != std::string::npos && open < 200 && close != std::string::npos && close > open;
}

}  // namespace platemeter::testing
