// The bundle's two CSV files (bundle_input_io.h, docs/bundle-job.md):
// observations and ground points, their readers and writers.
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/core/error.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/text_input.h"

namespace platemeter {
namespace {

// Accepted ranges (docs/bundle-job.md, "Accepted ranges").
constexpr NumberRange kImageMm{-1e4, 1e4, "mm"};        // camera-frame coordinates; formats are < 500 mm
constexpr NumberRange kImageSigmaMm{0.0, 1e3, "mm"};    // > 0 as well
// Object coordinates: geocentric ones are < 7e6 m, but the round-trip test
// writes 1e22 m, so the bound is numerical (squares of sums stay finite).
constexpr NumberRange kObjectM{-1e30, 1e30, "m"};
constexpr NumberRange kObjectSigmaM{0.0, 1e9, "m"};

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return std::string();
  const size_t end = s.find_last_not_of(" \t");
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

template <size_t N>
std::string JoinColumns(const std::array<const char*, N>& columns) {
  std::string out;
  for (size_t i = 0; i < N; ++i) out += std::string(i ? "," : "") + columns[i];
  return out;
}

// Reads a headed CSV file line by line; every error names the file, the line
// and, for a field, the column.
template <size_t N>
class CsvReader {
 public:
  CsvReader(const std::string& text, const std::string& origin, const std::array<const char*, N>& columns,
            const char* what)
      : in_(std::string(WithoutUtf8Bom(text))),  // a UTF-8 byte order mark (spreadsheets)
        origin_(origin),
        columns_(columns),
        what_(what) {}

  // The next data row's fields (N of them), or false at the end. Checks the
  // header line first.
  bool Next(std::vector<std::string>* fields) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::string trimmed = Trim(line);
      if (trimmed.empty() || trimmed[0] == '#') continue;
      std::vector<std::string> f = SplitFields(line);
      if (!have_header_) {
        CheckHeader(f);
        have_header_ = true;
        continue;
      }
      if (f.size() != N) {
        Fail("expected " + std::to_string(N) + " fields (" + JoinColumns(columns_) + "), found " +
             std::to_string(f.size()));
      }
      for (size_t i = 0; i < N; ++i) {
        if (f[i].find('"') != std::string::npos) {
          FailColumn(i, "'" + f[i] + "' contains a double quote (there is no CSV quoting)");
        }
      }
      *fields = std::move(f);
      return true;
    }
    if (!have_header_) {
      throw Error(origin_, std::string("no header line: ") + what_ + " start with the column names '" +
                               JoinColumns(columns_) + "'");
    }
    return false;
  }

  int line() const { return line_; }
  std::string Origin() const { return origin_ + ":" + std::to_string(line_); }

  [[noreturn]] void Fail(const std::string& reason) const {
    throw Error(origin_, "line " + std::to_string(line_) + ": " + reason);
  }
  [[noreturn]] void FailColumn(size_t column, const std::string& reason) const {
    throw Error(origin_, "line " + std::to_string(line_) + ", column " + std::to_string(column + 1) + " (" +
                             columns_[column] + "): " + reason);
  }

  std::string Id(const std::string& field, size_t column) const {
    if (field.empty()) FailColumn(column, "empty");
    if (const std::string why = TextFieldProblem(field); !why.empty()) FailColumn(column, why);
    return field;
  }
  double Number(const std::string& field, size_t column, const NumberRange& range) const {
    const double value = Number(field, column);
    if (!range.Contains(value)) FailColumn(column, OutsideRange(field, range));
    return value;
  }
  double Number(const std::string& field, size_t column) const {
    if (field.empty()) FailColumn(column, "empty (a number is required)");
    const char* begin = field.data();
    const char* end = field.data() + field.size();
    if (*begin == '+' && field.size() > 1 && field[1] != '-' && field[1] != '+') ++begin;
    double value = 0.0;
    const auto result = std::from_chars(begin, end, value);
    if (begin == end || result.ec == std::errc::invalid_argument || result.ptr != end) {
      FailColumn(column, "'" + field + "' is not a number");
    }
    if (result.ec == std::errc::result_out_of_range) FailColumn(column, "'" + field + "' is out of a double's range");
    if (!std::isfinite(value)) FailColumn(column, "'" + field + "' is not a finite number");
    return value;
  }

 private:
  void CheckHeader(const std::vector<std::string>& names) const {
    for (size_t i = 0; i < names.size() && i < N; ++i) {
      if (names[i] != columns_[i]) {
        Fail("column " + std::to_string(i + 1) + " of the header is '" + names[i] + "', expected '" + columns_[i] +
             "' (header: " + JoinColumns(columns_) + ")");
      }
    }
    if (names.size() != N) {
      Fail("the header has " + std::to_string(names.size()) + " columns, expected " + std::to_string(N) + " (" +
           JoinColumns(columns_) + ")");
    }
  }

  std::istringstream in_;
  const std::string& origin_;
  const std::array<const char*, N>& columns_;
  const char* what_;
  int line_ = 0;
  bool have_header_ = false;
};

std::string ReadText(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, std::string("cannot open the ") + what);
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path, "read error");
  return buffer.str();
}

// Writers: the same rules the readers enforce, so whatever is written reads back.
std::string FormatNumber(double value, const char* subject, const std::string& what) {
  if (!std::isfinite(value)) throw Error(subject, what + ": cannot write a non-finite number");
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);  // shortest round-trip form
  return std::string(buffer, result.ptr);
}

void CheckId(const std::string& id, const char* subject, const std::string& what, bool first_column) {
  if (id.empty()) throw Error(subject, what + " is empty");
  if (id.find_first_of(",\"\n\r") != std::string::npos) {
    throw Error(subject, what + " '" + id + "' contains a comma, double quote or newline");
  }
  if (id != Trim(id)) throw Error(subject, what + " '" + id + "' begins or ends with a space");
  if (first_column && id[0] == '#') throw Error(subject, what + " '" + id + "' begins with '#' (a comment line)");
}

}  // namespace

// ---------------------------------------------------------------------------
// Observations.

std::vector<ImageObservation> ParseObservationsCsv(const std::string& text, const std::string& origin) {
  CsvReader<6> reader(text, origin, kObservationColumns, "observation files");
  std::vector<ImageObservation> observations;
  std::map<std::pair<std::string, std::string>, int> seen;  // (frame, point) -> line
  std::vector<std::string> f;
  while (reader.Next(&f)) {
    ImageObservation o;
    o.frame = reader.Id(f[0], 0);
    o.point_id = reader.Id(f[1], 1);
    o.x_mm = reader.Number(f[2], 2, kImageMm);
    o.y_mm = reader.Number(f[3], 3, kImageMm);
    o.sigma_x_mm = reader.Number(f[4], 4);
    o.sigma_y_mm = reader.Number(f[5], 5);
    for (size_t column : {4u, 5u}) {
      const double sigma = column == 4 ? o.sigma_x_mm : o.sigma_y_mm;
      if (!(sigma > 0.0)) {
        reader.FailColumn(column, "a standard deviation of an image observation must be positive ('" + f[column] +
                                      "')");
      }
      if (!kImageSigmaMm.Contains(sigma)) reader.FailColumn(column, OutsideRange(f[column], kImageSigmaMm));
    }
    const auto [it, inserted] = seen.emplace(std::make_pair(o.frame, o.point_id), reader.line());
    if (!inserted) {
      reader.FailColumn(1, "point '" + o.point_id + "' is observed twice in frame '" + o.frame +
                               "' (first on line " + std::to_string(it->second) + ")");
    }
    o.origin = reader.Origin();
    observations.push_back(std::move(o));
  }
  return observations;
}

std::vector<ImageObservation> ReadObservationsCsv(const std::string& path) {
  return ParseObservationsCsv(ReadText(path, "observations file"), path);
}

std::string FormatObservationsCsv(const std::vector<ImageObservation>& observations) {
  const char* subject = "observations";
  std::ostringstream out;
  out << JoinColumns(kObservationColumns) << '\n';
  std::set<std::pair<std::string, std::string>> seen;
  for (const ImageObservation& o : observations) {
    const std::string what = "observation of '" + o.point_id + "' in frame '" + o.frame + "'";
    CheckId(o.frame, subject, "frame id", true);
    CheckId(o.point_id, subject, "point id", false);
    if (!(o.sigma_x_mm > 0.0) || !(o.sigma_y_mm > 0.0)) {
      throw Error(subject, what + ": the standard deviations must be positive");
    }
    if (!seen.emplace(o.frame, o.point_id).second) throw Error(subject, what + " is given twice");
    out << o.frame << ',' << o.point_id << ',' << FormatNumber(o.x_mm, subject, what) << ','
        << FormatNumber(o.y_mm, subject, what) << ',' << FormatNumber(o.sigma_x_mm, subject, what) << ','
        << FormatNumber(o.sigma_y_mm, subject, what) << '\n';
  }
  return out.str();
}

void WriteObservationsCsv(const std::string& path, const std::vector<ImageObservation>& observations) {
  std::string text;
  try {
    text = FormatObservationsCsv(observations);
  } catch (const Error& e) {
    throw Error(path, e.reason());
  }
  WriteFileAtomically(path, text);
}

// ---------------------------------------------------------------------------
// Ground points.

std::vector<GroundPoint> ParseGroundPointsCsv(const std::string& text, const std::string& origin) {
  CsvReader<7> reader(text, origin, kGroundPointColumns, "ground point files");
  std::vector<GroundPoint> points;
  std::map<std::string, int> seen;  // id -> line
  std::vector<std::string> f;
  while (reader.Next(&f)) {
    GroundPoint p;
    p.id = reader.Id(f[0], 0);
    for (int axis = 0; axis < 3; ++axis) p.position_m[axis] = reader.Number(f[1 + axis], 1 + axis, kObjectM);
    for (int axis = 0; axis < 3; ++axis) {
      const size_t column = 4 + axis;
      if (f[column].empty()) continue;  // free
      const double sigma = reader.Number(f[column], column);
      if (sigma < 0.0) {
        reader.FailColumn(column, "a standard deviation cannot be negative ('" + f[column] +
                                      "'; 0 = fixed, empty = free)");
      }
      if (!kObjectSigmaM.Contains(sigma)) reader.FailColumn(column, OutsideRange(f[column], kObjectSigmaM));
      p.sigma_m[axis] = sigma;
    }
    const auto [it, inserted] = seen.emplace(p.id, reader.line());
    if (!inserted) {
      reader.FailColumn(0, "ground point '" + p.id + "' is listed twice (first on line " + std::to_string(it->second) +
                               ")");
    }
    p.origin = reader.Origin();
    points.push_back(std::move(p));
  }
  return points;
}

std::vector<GroundPoint> ReadGroundPointsCsv(const std::string& path) {
  return ParseGroundPointsCsv(ReadText(path, "ground points file"), path);
}

std::string FormatGroundPointsCsv(const std::vector<GroundPoint>& points) {
  const char* subject = "ground points";
  std::ostringstream out;
  out << JoinColumns(kGroundPointColumns) << '\n';
  std::set<std::string> seen;
  for (const GroundPoint& p : points) {
    const std::string what = "ground point '" + p.id + "'";
    CheckId(p.id, subject, "ground point id", true);
    if (!seen.insert(p.id).second) throw Error(subject, what + " is given twice");
    out << p.id;
    for (int axis = 0; axis < 3; ++axis) out << ',' << FormatNumber(p.position_m[axis], subject, what);
    for (int axis = 0; axis < 3; ++axis) {
      out << ',';
      if (!p.sigma_m[axis]) continue;
      if (!(*p.sigma_m[axis] >= 0.0)) throw Error(subject, what + ": a standard deviation cannot be negative");
      out << FormatNumber(*p.sigma_m[axis], subject, what);
    }
    out << '\n';
  }
  return out.str();
}

void WriteGroundPointsCsv(const std::string& path, const std::vector<GroundPoint>& points) {
  std::string text;
  try {
    text = FormatGroundPointsCsv(points);
  } catch (const Error& e) {
    throw Error(path, e.reason());
  }
  WriteFileAtomically(path, text);
}

}  // namespace platemeter
