// Measurement file text format (docs/measurement-file.md).
#include "platemeter/measure/measurement_file.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/text_input.h"

namespace platemeter {
namespace {

constexpr const char* kTitle = "# platemeter measurement file";
constexpr const char* kWriterSubject = "measurement file";


// Accepted ranges (docs/measurement-file.md, "Accepted ranges"): generous for
// any real plate, small enough that squares and sums of them stay finite.
constexpr NumberRange kScanPx{-1e7, 1e7, "px"};       // scans are < 500000 px wide
constexpr NumberRange kScanSigmaPx{0.0, 1e4, "px"};   // a larger sigma is no measurement
// A Cramer-Rao bound is no measurement: an image too faint to measure has a
// huge one (the simulator writes 1e11 px); bounded so its square stays finite.
constexpr NumberRange kCrbPx{0.0, 1e100, "px"};
constexpr NumberRange kPlateMm{-1e4, 1e4, "mm"};      // plates are < 500 mm wide
constexpr NumberRange kPlateSigmaMm{0.0, 1e3, "mm"};
constexpr NumberRange kPixelSizeUm{0.01, 1e4, "um"};  // as the job file's pixel_size_um
constexpr NumberRange kAnyFinite{-1.7976931348623157e308, 1.7976931348623157e308, ""};  // checked after
constexpr long kMaxDot = 1000000;                     // images in one trail
constexpr size_t kMaxTimeLength = 64;                 // an ISO 8601 time is ~24 characters

// Column indices (0-based) in file order.
enum Column {
  kId, kKind, kStatus, kXPx, kYPx, kSigmaXPx, kSigmaYPx, kXMm, kYMm, kSigmaXMm, kSigmaYMm, kFlags,
  kStarId, kTrail, kDot, kMidTime, kCrbX, kCrbY, kCrbCorr, kNumColumns
};

std::string FormatDouble(double value) {
  if (!std::isfinite(value)) throw Error(kWriterSubject, "cannot write a non-finite number");
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);  // shortest round-trip form
  return std::string(buffer, result.ptr);
}

std::string FormatOptional(const std::optional<double>& value) {
  return value ? FormatDouble(*value) : std::string();
}

// A CSV field as written: no quoting, so no separators inside.
void CheckField(const std::string& value, const std::string& column, const std::string& id) {
  if (value.find_first_of(",\n\r\"") != std::string::npos) {
    throw Error(kWriterSubject, "point '" + id + "': " + column + " '" + value +
                                    "' contains a comma, quote or newline");
  }
}

void CheckHeaderValue(const std::string& value, const std::string& key) {
  if (value.find_first_of("\n\r") != std::string::npos) {
    throw Error(kWriterSubject, "header " + key + " contains a newline");
  }
  if (const std::string why = TextFieldProblem(value); !why.empty()) {
    throw Error(kWriterSubject, "header " + key + " " + why);
  }
}

// The reader's accepted ranges, for the writer (so whatever is written reads back).
template <typename Fail>
void CheckPointRanges(const MeasuredPoint& p, const Fail& fail) {
  const std::pair<const std::optional<double>*, std::pair<const char*, const NumberRange*>> checks[] = {
      {&p.x_px, {"x_px", &kScanPx}},          {&p.y_px, {"y_px", &kScanPx}},
      {&p.sigma_x_px, {"sigma_x_px", &kScanSigmaPx}}, {&p.sigma_y_px, {"sigma_y_px", &kScanSigmaPx}},
      {&p.x_mm, {"x_mm", &kPlateMm}},         {&p.y_mm, {"y_mm", &kPlateMm}},
      {&p.sigma_x_mm, {"sigma_x_mm", &kPlateSigmaMm}}, {&p.sigma_y_mm, {"sigma_y_mm", &kPlateSigmaMm}},
      {&p.crb_x_px, {"crb_x_px", &kCrbPx}},           {&p.crb_y_px, {"crb_y_px", &kCrbPx}}};
  for (const auto& [value, what] : checks) {
    if (*value && std::isfinite(**value) && !what.second->Contains(**value)) {
      fail(std::string(what.first) + " " + OutsideRange(FormatDouble(**value), *what.second));
    }
  }
  if (p.dot && (*p.dot < 0 || *p.dot > kMaxDot)) {
    fail("dot " + OutsideRange(std::to_string(*p.dot), {0.0, double(kMaxDot), ""}));
  }
  for (const std::string* text : {&p.id, &p.star_id, &p.trail, &p.mid_time_utc}) {
    if (const std::string why = TextFieldProblem(*text); !why.empty()) fail("a text field " + why);
  }
  for (const std::string& flag : p.flags) {
    if (const std::string why = TextFieldProblem(flag); !why.empty()) fail("a flag " + why);
  }
}

bool IsBlank(const std::string& s) { return s.find_first_not_of(" \t") == std::string::npos; }

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return parts;
}

// Reader context: names the file, line and column in every error.
struct Reader {
  const std::string& origin;
  int line = 0;

  [[noreturn]] void Fail(const std::string& reason) const {
    throw Error(origin, "line " + std::to_string(line) + ": " + reason);
  }
  [[noreturn]] void FailColumn(int column, const std::string& reason) const {
    throw Error(origin, "line " + std::to_string(line) + ", column " + std::to_string(column + 1) + " (" +
                            MeasurementColumns(true)[column] + "): " + reason);
  }

  std::optional<double> Number(const std::string& field, int column, const NumberRange& range) const {
    if (field.empty()) return std::nullopt;
    double value = 0;
    const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
    if (result.ec != std::errc() || result.ptr != field.data() + field.size()) {
      FailColumn(column, "'" + field + "' is not a number");
    }
    if (!std::isfinite(value)) FailColumn(column, "'" + field + "' is not a finite number");
    if (!range.Contains(value)) FailColumn(column, OutsideRange(field, range));
    return value;
  }
  std::optional<double> Sigma(const std::string& field, int column, const NumberRange& range) const {
    auto value = Number(field, column, kAnyFinite);
    if (value && *value < 0) FailColumn(column, "a standard deviation cannot be negative ('" + field + "')");
    if (value && !range.Contains(*value)) FailColumn(column, OutsideRange(field, range));
    return value;
  }
  // Ids, flags and names end up in XML, CSV and HTML: valid UTF-8, no control characters.
  void Text(const std::string& field, int column) const {
    if (const std::string why = TextFieldProblem(field); !why.empty()) FailColumn(column, why);
  }
};

}  // namespace


const std::vector<std::string>& MeasurementColumns(bool truth_columns) {
  static const std::vector<std::string> kAll = {
      "id",      "kind",       "status",     "x_px",    "y_px",         "sigma_x_px", "sigma_y_px",
      "x_mm",    "y_mm",       "sigma_x_mm", "sigma_y_mm", "flags",    "star_id",    "trail",
      "dot",     "mid_time_utc", "crb_x_px", "crb_y_px", "crb_xy_corr"};
  static const std::vector<std::string> kPlain(kAll.begin(), kAll.begin() + kCrbX);
  return truth_columns ? kAll : kPlain;
}

namespace {

// The file's text, streamed to `out` (FormatMeasurementFile's rules).
void PutMeasurementFile(const MeasurementFile& file, std::ostream& out) {
  const MeasurementHeader& h = file.header;
  bool truth = file.truth_columns;
  for (const MeasuredPoint& p : file.points) {
    if (p.status == PointStatus::kTruth || p.crb_x_px || p.crb_y_px || p.crb_xy_corr) truth = true;
  }

  out << kTitle << '\n';
  auto header_line = [&out](const std::string& key, const std::string& value) {
    CheckHeaderValue(value, key);
    out << "# " << key << ": " << value << '\n';
  };
  header_line("format_version", std::to_string(h.format_version));
  header_line("plate_id", h.plate_id);
  header_line("scan_file", h.scan_file);
  header_line("scan_sha256", h.scan_sha256);
  header_line("camera", h.camera);
  if (h.pixel_size_um && std::isfinite(*h.pixel_size_um) && !kPixelSizeUm.Contains(*h.pixel_size_um)) {
    throw Error(kWriterSubject, "pixel_size_um " + OutsideRange(FormatDouble(*h.pixel_size_um), kPixelSizeUm));
  }
  header_line("pixel_size_um", FormatOptional(h.pixel_size_um));
  header_line("software_version", h.software_version);
  for (const AppliedCorrection& correction : h.corrections) {
    if (correction.name.empty() || correction.name.find_first_of(" \t=") != std::string::npos) {
      throw Error(kWriterSubject, "correction name '" + correction.name + "' is empty or contains a space or '='");
    }
    std::string line = correction.name;
    for (const auto& [key, value] : correction.parameters) {
      if (key.empty() || key.find_first_of(" \t=") != std::string::npos ||
          value.find_first_of(" \t") != std::string::npos) {
        throw Error(kWriterSubject, "correction " + correction.name + ": parameter '" + key + "=" + value +
                                        "' has an empty name or contains a space");
      }
      line += " " + key + "=" + value;
    }
    header_line("correction", line);
  }
  static const std::set<std::string> kReserved = {"format_version", "plate_id", "scan_file", "scan_sha256",
                                                  "camera", "pixel_size_um", "software_version", "correction"};
  for (const auto& [key, value] : h.extra) {
    if (key.empty() || kReserved.count(key) || key.find_first_of(": \t\n\r") != std::string::npos) {
      throw Error(kWriterSubject, "header key '" + key + "' is empty, reserved or contains ':' or a space");
    }
    header_line(key, value);
  }

  const auto& columns = MeasurementColumns(truth);
  for (size_t i = 0; i < columns.size(); ++i) out << (i ? "," : "") << columns[i];
  out << '\n';

  std::set<std::pair<int, std::string>> seen;
  for (const MeasuredPoint& p : file.points) {
    if (p.id.empty()) throw Error(kWriterSubject, "a point has an empty id");
    if (!seen.insert({static_cast<int>(p.kind), p.id}).second) {
      throw Error(kWriterSubject, std::string("duplicate point ") + PointKindName(p.kind) + " '" + p.id + "'");
    }
    // The same rules the reader enforces, so whatever is written reads back.
    auto fail = [&p](const std::string& reason) { throw Error(kWriterSubject, "point '" + p.id + "': " + reason); };
    if (p.x_px.has_value() != p.y_px.has_value()) fail("x_px and y_px must both be given or both be empty");
    if (p.x_mm.has_value() != p.y_mm.has_value()) fail("x_mm and y_mm must both be given or both be empty");
    for (const auto* sigma : {&p.sigma_x_px, &p.sigma_y_px, &p.sigma_x_mm, &p.sigma_y_mm, &p.crb_x_px, &p.crb_y_px}) {
      if (*sigma && !(**sigma >= 0)) fail("a standard deviation cannot be negative");
    }
    CheckPointRanges(p, fail);
    if (p.crb_xy_corr && !(std::abs(*p.crb_xy_corr) <= 1)) fail("crb_xy_corr must lie in -1..1");
    if ((p.status == PointStatus::kMeasured || p.status == PointStatus::kPredicted ||
         p.status == PointStatus::kTruth) && !p.x_px && !p.x_mm) {
      fail(std::string("a ") + PointStatusName(p.status) + " point needs a position");
    }
    std::string flags;
    for (const std::string& flag : p.flags) {
      if (flag.empty() || flag.find('|') != std::string::npos) {
        throw Error(kWriterSubject, "point '" + p.id + "': flag '" + flag + "' is empty or contains '|'");
      }
      flags += (flags.empty() ? "" : "|") + flag;
    }
    std::vector<std::string> fields = {
        p.id, PointKindName(p.kind), PointStatusName(p.status), FormatOptional(p.x_px), FormatOptional(p.y_px),
        FormatOptional(p.sigma_x_px), FormatOptional(p.sigma_y_px), FormatOptional(p.x_mm),
        FormatOptional(p.y_mm), FormatOptional(p.sigma_x_mm), FormatOptional(p.sigma_y_mm), flags, p.star_id,
        p.trail, p.dot ? std::to_string(*p.dot) : std::string(), p.mid_time_utc};
    if (truth) {
      fields.push_back(FormatOptional(p.crb_x_px));
      fields.push_back(FormatOptional(p.crb_y_px));
      fields.push_back(FormatOptional(p.crb_xy_corr));
    }
    for (size_t i = 0; i < fields.size(); ++i) {
      CheckField(fields[i], columns[i], p.id);
      out << (i ? "," : "") << fields[i];
    }
    out << '\n';
  }
}

}  // namespace

std::string FormatMeasurementFile(const MeasurementFile& file) {
  std::ostringstream out;
  PutMeasurementFile(file, out);
  return out.str();
}

void WriteMeasurementFile(const std::string& path, const MeasurementFile& file) {
  // Streamed: a plate's file runs to tens of MB, which need not be held in memory twice.
  try {
    WriteFileAtomicallyStreamed(path, [&file](std::ostream& out) { PutMeasurementFile(file, out); });
  } catch (const EnvironmentError&) {
    throw;
  } catch (const Error& e) {
    throw Error(path, e.reason());
  }
}

namespace {

// One "# key: value" line of the header (docs/measurement-file.md, "Header keys").
void ReadHeaderLine(const Reader& reader, const std::string& line, MeasurementHeader* header, bool* have_version) {
  MeasurementHeader& h = *header;
  const std::string body = line.substr(1);
  if (IsBlank(body)) return;
  if (body[0] != ' ') reader.Fail("a header line must read '# key: value'");
  const size_t colon = body.find(':');
  if (colon == std::string::npos) reader.Fail("a header line must read '# key: value'");
  const std::string key = body.substr(1, colon - 1);
  std::string value = body.substr(colon + 1);
  if (!value.empty() && value[0] == ' ') value.erase(0, 1);
  if (key.empty() || key.find_first_of(" \t") != std::string::npos) reader.Fail("bad header key '" + key + "'");
  if (key == "format_version") {
    int version = 0;
    const auto r = std::from_chars(value.data(), value.data() + value.size(), version);
    if (r.ec != std::errc() || r.ptr != value.data() + value.size() || version < 1) {
      reader.Fail("format_version '" + value + "' is not a positive integer");
    }
    if (version > kMeasurementFormatVersion) {
      reader.Fail("format_version " + value + " is newer than this platemeter reads (" +
                  std::to_string(kMeasurementFormatVersion) + ")");
    }
    h.format_version = version;
    *have_version = true;
  } else if (key == "plate_id") {
    h.plate_id = value;
  } else if (key == "scan_file") {
    h.scan_file = value;
  } else if (key == "scan_sha256") {
    if (!value.empty() &&
        (value.size() != 64 || value.find_first_not_of("0123456789abcdef") != std::string::npos)) {
      reader.Fail("scan_sha256 must be 64 lower-case hex digits");
    }
    h.scan_sha256 = value;
  } else if (key == "camera") {
    h.camera = value;
  } else if (key == "pixel_size_um") {
    if (!value.empty()) {
      double size = 0;
      const auto r = std::from_chars(value.data(), value.data() + value.size(), size);
      if (r.ec != std::errc() || r.ptr != value.data() + value.size() || !(size > 0) || !std::isfinite(size)) {
        reader.Fail("pixel_size_um '" + value + "' is not a positive number");
      }
      if (!kPixelSizeUm.Contains(size)) reader.Fail("pixel_size_um " + OutsideRange(value, kPixelSizeUm));
      h.pixel_size_um = size;
    }
  } else if (key == "software_version") {
    h.software_version = value;
  } else if (key == "correction") {
    const std::vector<std::string> words = Split(value, ' ');
    AppliedCorrection correction;
    correction.name = words[0];
    if (correction.name.empty()) reader.Fail("correction without a name");
    if (correction.name.find('=') != std::string::npos) {
      reader.Fail("correction name '" + correction.name + "' contains '=' (write NAME param=value ...)");
    }
    for (size_t i = 1; i < words.size(); ++i) {
      const size_t eq = words[i].find('=');
      if (eq == std::string::npos || eq == 0) {
        reader.Fail("correction " + correction.name + ": parameter '" + words[i] + "' is not name=value");
      }
      correction.parameters.emplace_back(words[i].substr(0, eq), words[i].substr(eq + 1));
    }
    h.corrections.push_back(std::move(correction));
  } else {
    h.extra.emplace_back(key, value);
  }
}

// One data row: `seen` holds the (kind, id) pairs of the rows before.
MeasuredPoint ReadRow(const Reader& reader, const std::string& line, bool truth_columns,
                      std::set<std::pair<int, std::string>>* seen) {
  const size_t columns_expected = MeasurementColumns(truth_columns).size();
  const std::vector<std::string> f = Split(line, ',');
  if (f.size() != columns_expected) {
    reader.Fail("expected " + std::to_string(columns_expected) + " fields, found " + std::to_string(f.size()));
  }
  for (size_t column = 0; column < f.size(); ++column) {
    if (f[column].find('"') != std::string::npos) {
      reader.FailColumn(static_cast<int>(column), "contains a double quote (there is no CSV quoting)");
    }
  }
  for (int column : {kId, kFlags, kStarId, kTrail, kMidTime}) reader.Text(f[column], column);
  if (f[kMidTime].size() > kMaxTimeLength) {
    reader.FailColumn(kMidTime, "longer than " + std::to_string(kMaxTimeLength) + " characters (not an ISO 8601 time)");
  }
  MeasuredPoint p;
  p.id = f[kId];
  if (p.id.empty()) reader.FailColumn(kId, "empty id");
  if (!ParsePointKind(f[kKind], &p.kind)) {
    reader.FailColumn(kKind,
                      "unknown kind '" + f[kKind] + "' (reseau, fiducial, star, trail_dot, trail_dash, passpoint)");
  }
  if (!ParsePointStatus(f[kStatus], &p.status)) {
    reader.FailColumn(kStatus, "unknown status '" + f[kStatus] + "' (measured, rejected, missing, predicted, truth)");
  }
  if (!seen->insert({static_cast<int>(p.kind), p.id}).second) {
    reader.FailColumn(kId, std::string("duplicate ") + PointKindName(p.kind) + " '" + p.id + "'");
  }
  p.x_px = reader.Number(f[kXPx], kXPx, kScanPx);
  p.y_px = reader.Number(f[kYPx], kYPx, kScanPx);
  p.sigma_x_px = reader.Sigma(f[kSigmaXPx], kSigmaXPx, kScanSigmaPx);
  p.sigma_y_px = reader.Sigma(f[kSigmaYPx], kSigmaYPx, kScanSigmaPx);
  p.x_mm = reader.Number(f[kXMm], kXMm, kPlateMm);
  p.y_mm = reader.Number(f[kYMm], kYMm, kPlateMm);
  p.sigma_x_mm = reader.Sigma(f[kSigmaXMm], kSigmaXMm, kPlateSigmaMm);
  p.sigma_y_mm = reader.Sigma(f[kSigmaYMm], kSigmaYMm, kPlateSigmaMm);
  if (p.x_px.has_value() != p.y_px.has_value())
    reader.FailColumn(kXPx, "x_px and y_px must both be given or both be empty");
  if (p.x_mm.has_value() != p.y_mm.has_value())
    reader.FailColumn(kXMm, "x_mm and y_mm must both be given or both be empty");
  if (!f[kFlags].empty()) {
    p.flags = Split(f[kFlags], '|');
    for (const std::string& flag : p.flags) {
      if (flag.empty()) reader.FailColumn(kFlags, "empty flag in '" + f[kFlags] + "'");
    }
  }
  p.star_id = f[kStarId];
  p.trail = f[kTrail];
  if (!f[kDot].empty()) {
    long dot = 0;
    const auto r = std::from_chars(f[kDot].data(), f[kDot].data() + f[kDot].size(), dot);
    if (r.ec != std::errc() || r.ptr != f[kDot].data() + f[kDot].size()) {
      reader.FailColumn(kDot, "'" + f[kDot] + "' is not an integer");
    }
    if (dot < 0 || dot > kMaxDot) reader.FailColumn(kDot, OutsideRange(f[kDot], {0.0, double(kMaxDot), ""}));
    p.dot = dot;
  }
  p.mid_time_utc = f[kMidTime];
  if (truth_columns) {
    p.crb_x_px = reader.Sigma(f[kCrbX], kCrbX, kCrbPx);
    p.crb_y_px = reader.Sigma(f[kCrbY], kCrbY, kCrbPx);
    p.crb_xy_corr = reader.Number(f[kCrbCorr], kCrbCorr, kAnyFinite);
    if (p.crb_xy_corr && std::abs(*p.crb_xy_corr) > 1) reader.FailColumn(kCrbCorr, "a correlation must lie in -1..1");
  }
  if ((p.status == PointStatus::kMeasured || p.status == PointStatus::kPredicted || p.status == PointStatus::kTruth) &&
      !p.x_px && !p.x_mm) {
    reader.FailColumn(
        kXPx, std::string("a ") + PointStatusName(p.status) + " point needs a position (x_px,y_px or x_mm,y_mm)");
  }
  return p;
}

}  // namespace

MeasurementFile ParseMeasurementFile(const std::string& text, const std::string& origin) {
  MeasurementFile file;
  MeasurementHeader& h = file.header;
  Reader reader{origin};
  bool have_title = false, have_version = false, have_columns = false;
  std::set<std::pair<int, std::string>> seen;

  std::istringstream in(std::string(WithoutUtf8Bom(text)));
  std::string line;
  while (std::getline(in, line)) {
    ++reader.line;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (have_title && !line.empty() && line[0] == '#') {
      if (const std::string why = TextFieldProblem(line); !why.empty()) reader.Fail("the header line " + why);
    }
    if (!have_title) {
      if (line != kTitle) reader.Fail(std::string("not a measurement file (expected '") + kTitle + "')");
      have_title = true;
      continue;
    }
    if (IsBlank(line)) continue;
    if (line[0] == '#') {
      if (have_columns) reader.Fail("comment lines belong in the header, before the column names");
      ReadHeaderLine(reader, line, &h, &have_version);
      continue;
    }
    if (!have_columns) {
      if (!have_version) reader.Fail("the header has no format_version line");
      const std::vector<std::string> names = Split(line, ',');
      for (bool truth : {false, true}) {
        if (names == MeasurementColumns(truth)) {
          file.truth_columns = truth;
          have_columns = true;
        }
      }
      if (!have_columns) {
        const auto& expected = MeasurementColumns(false);
        for (size_t i = 0; i < names.size(); ++i) {
          if (i >= MeasurementColumns(true).size() || names[i] != MeasurementColumns(true)[i]) {
            reader.Fail("column " + std::to_string(i + 1) + " is '" + names[i] + "', expected '" +
                        (i < MeasurementColumns(true).size() ? MeasurementColumns(true)[i] : std::string("(none)")) +
                        "'");
          }
        }
        reader.Fail("the column line has " + std::to_string(names.size()) + " columns, expected " +
                    std::to_string(expected.size()) + " or " + std::to_string(MeasurementColumns(true).size()));
      }
      continue;
    }
    file.points.push_back(ReadRow(reader, line, file.truth_columns, &seen));
  }
  if (!have_title) throw Error(origin, "empty file (not a measurement file)");
  if (!have_columns) throw Error(origin, "line " + std::to_string(reader.line) + ": no column line after the header");
  return file;
}

MeasurementFile ReadMeasurementFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the measurement file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path, "read error");
  return ParseMeasurementFile(buffer.str(), path);
}

}  // namespace platemeter
