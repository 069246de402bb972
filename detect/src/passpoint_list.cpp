// The approximate passpoint list (passpoint_detector.h, docs/passpoints.md):
// CSV `id,x_px,y_px`, '#' comments and blank lines skipped.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/text_input.h"
#include "platemeter/detect/passpoint_detector.h"

namespace platemeter {
namespace {

// Scan positions as the measurement file accepts them (docs/passpoints.md).
constexpr NumberRange kScanPx{-1e7, 1e7, "px"};

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  for (std::string f; std::getline(in, f, ',');) fields.push_back(Trim(f));
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(text.c_str(), &end);
  return errno == 0 && end == text.c_str() + text.size() && std::isfinite(*value);
}

}  // namespace

std::vector<ApproximatePasspoint> ParsePasspointList(const std::string& text, const std::string& origin) {
  std::vector<ApproximatePasspoint> list;
  std::set<std::string> ids;
  bool header = false;
  std::stringstream in{std::string(WithoutUtf8Bom(text))};
  int number = 0;
  for (std::string raw; std::getline(in, raw);) {
    ++number;
    const std::string line = Trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = "line " + std::to_string(number) + ": ";
    const std::vector<std::string> fields = SplitFields(line);
    if (!header) {
      if (fields != std::vector<std::string>{"id", "x_px", "y_px"})
        throw Error(origin, where + "expected the header 'id,x_px,y_px', found '" + line + "'");
      header = true;
      continue;
    }
    if (fields.size() != 3)
      throw Error(origin, where + "expected 3 fields (id,x_px,y_px), found " + std::to_string(fields.size()));
    ApproximatePasspoint p;
    p.id = fields[0];
    if (p.id.empty()) throw Error(origin, where + "empty id");
    // The id goes into the measurement file and micmac.xml.
    if (const std::string why = TextFieldProblem(p.id); !why.empty()) throw Error(origin, where + "the id " + why);
    if (!ParseNumber(fields[1], &p.position_px.x_px))
      throw Error(origin, where + "x_px '" + fields[1] + "' is not a number");
    if (!ParseNumber(fields[2], &p.position_px.y_px))
      throw Error(origin, where + "y_px '" + fields[2] + "' is not a number");
    if (!kScanPx.Contains(p.position_px.x_px)) throw Error(origin, where + "x_px " + OutsideRange(fields[1], kScanPx));
    if (!kScanPx.Contains(p.position_px.y_px)) throw Error(origin, where + "y_px " + OutsideRange(fields[2], kScanPx));
    if (!ids.insert(p.id).second) throw Error(origin, where + "duplicate id '" + p.id + "'");
    list.push_back(p);
  }
  if (!header) throw Error(origin, "no header 'id,x_px,y_px' (empty list)");
  if (list.empty()) throw Error(origin, "the list has no passpoints");
  return list;
}

std::vector<ApproximatePasspoint> ReadPasspointList(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path, "cannot read the passpoint list");
  std::stringstream text;
  text << file.rdbuf();
  if (file.bad()) throw Error(path, "cannot read the passpoint list");
  return ParsePasspointList(text.str(), path);
}

}  // namespace platemeter
