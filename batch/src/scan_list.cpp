#include "platemeter/batch/scan_list.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/text_input.h"

namespace platemeter {
namespace fs = std::filesystem;

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

// One CSV record (RFC 4180: quoted fields may hold commas, "" and newlines). Reads further
// lines while a quote is open; `line_number` advances with every line read.
bool ReadCsvRecord(std::istream& in, int* line_number, std::vector<std::string>* fields, bool* open_quote) {
  std::string line;
  if (!std::getline(in, line)) return false;
  ++*line_number;
  fields->clear();
  std::string field;
  bool quoted = false;
  for (size_t i = 0;; ++i) {
    if (i == line.size()) {
      if (!quoted) break;
      std::string next;
      if (!std::getline(in, next)) {
        *open_quote = true;
        break;
      }
      ++*line_number;
      field += '\n';
      line = next;
      i = static_cast<size_t>(-1);
      continue;
    }
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields->push_back(field);
      field.clear();
    } else if (c != '\r') {
      field += c;
    }
  }
  fields->push_back(field);
  return true;
}

ScanInput MakeInput(const fs::path& path) {
  ScanInput s;
  s.path = path.string();
  s.stem = path.stem().string();
  return s;
}

}  // namespace

bool IsScanFileName(const std::string& file_name) {
  static const char* const kExtensions[] = {".tif", ".tiff", ".png", ".jpg", ".jpeg", ".fits", ".fit"};
  const std::string ext = Lower(fs::path(file_name).extension().string());
  return std::find(std::begin(kExtensions), std::end(kExtensions), ext) != std::end(kExtensions);
}

std::vector<ScanInput> ListScanFolder(const std::string& folder, bool recursive) {
  std::vector<fs::path> relative;
  std::error_code ec;
  auto consider = [&](const fs::directory_entry& entry) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.') return;
    std::error_code e;
    if (!entry.is_regular_file(e) || !IsScanFileName(name)) return;
    relative.push_back(entry.path().lexically_relative(folder));  // not fs::relative: it resolves symlinks
  };
  if (recursive) {
    fs::recursive_directory_iterator it(folder, fs::directory_options::skip_permission_denied, ec), end;
    if (ec) throw Error(folder, "cannot list the folder (" + ec.message() + ")");
    for (; it != end; it.increment(ec)) {
      if (ec) throw Error(folder, "cannot list the folder (" + ec.message() + ")");
      const std::string name = it->path().filename().string();
      if (!name.empty() && name[0] == '.' && it->is_directory()) {
        it.disable_recursion_pending();  // hidden folders (e.g. .git) are not scans
        continue;
      }
      consider(*it);
    }
  } else {
    fs::directory_iterator it(folder, ec), end;
    if (ec) throw Error(folder, "cannot list the folder (" + ec.message() + ")");
    for (; it != end; it.increment(ec)) {
      if (ec) throw Error(folder, "cannot list the folder (" + ec.message() + ")");
      consider(*it);
    }
  }
  // Byte order of the relative path: the same on every machine (no locale), so shards agree.
  std::sort(relative.begin(), relative.end(),
            [](const fs::path& a, const fs::path& b) { return a.generic_string() < b.generic_string(); });
  std::vector<ScanInput> scans;
  for (const fs::path& r : relative) scans.push_back(MakeInput(fs::path(folder) / r));
  return scans;
}

std::vector<ScanInput> ReadScanManifest(const std::string& path, const std::vector<std::string>& allowed_columns) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path, "cannot open the manifest");
  std::stringstream text;
  text << file.rdbuf();
  if (file.bad()) throw Error(path, "cannot read the manifest");
  std::istringstream in{std::string(WithoutUtf8Bom(text.str()))};  // spreadsheets write a byte order mark
  const fs::path base = fs::path(path).parent_path();
  int line_number = 0;
  std::vector<std::string> fields, header;
  bool open_quote = false;
  int header_line = 0;
  // The header: the first line that is neither blank nor a comment.
  while (ReadCsvRecord(in, &line_number, &fields, &open_quote)) {
    if (open_quote) throw Error(path, "line " + std::to_string(line_number) + ": unterminated quote");
    if (fields.size() == 1 && Trim(fields[0]).empty()) continue;
    if (!fields.empty() && !fields[0].empty() && fields[0][0] == '#') continue;
    header = fields;
    header_line = line_number;
    break;
  }
  if (header.empty()) throw Error(path, "the manifest is empty (it needs a header row with a 'scan' column)");
  int scan_column = -1;
  for (size_t c = 0; c < header.size(); ++c) {
    if (Trim(header[c]) == "scan" && scan_column < 0) scan_column = static_cast<int>(c);
  }
  if (scan_column < 0) throw Error(path, "line " + std::to_string(header_line) + ": no 'scan' column in the header");
  std::map<std::string, int> seen;
  for (size_t c = 0; c < header.size(); ++c) {
    const std::string name = Trim(header[c]);
    const std::string where = "line " + std::to_string(header_line) + ": ";
    if (const std::string why = TextFieldProblem(name); !why.empty()) {
      throw Error(path, where + "column " + std::to_string(c + 1) + " name " + why);
    }
    if (name.empty()) throw Error(path, where + "column " + std::to_string(c + 1) + " has no name");
    if (seen.count(name)) throw Error(path, where + "column '" + name + "' appears twice");
    seen[name] = static_cast<int>(c);
    header[c] = name;
    if (name != "scan" && !allowed_columns.empty() &&
               std::find(allowed_columns.begin(), allowed_columns.end(), name) == allowed_columns.end()) {
      std::string known;
      for (const std::string& k : allowed_columns) known += (known.empty() ? "" : ", ") + k;
      throw Error(path, where + "unknown column '" + name + "' (known: scan, " + known + ")");
    }
  }
  std::vector<ScanInput> scans;
  for (;;) {
    const int first_line = line_number + 1;
    if (!ReadCsvRecord(in, &line_number, &fields, &open_quote)) break;
    const std::string where = "line " + std::to_string(first_line) + ": ";
    if (open_quote) throw Error(path, where + "unterminated quote");
    if (fields.size() == 1 && Trim(fields[0]).empty()) continue;
    if (!fields[0].empty() && fields[0][0] == '#') continue;
    if (fields.size() != header.size()) {
      throw Error(path, where + std::to_string(fields.size()) + " fields, the header has " +
                            std::to_string(header.size()));
    }
    // Scan names become plate ids and folder names; values feed the job's options.
    for (size_t c = 0; c < header.size(); ++c) {
      if (const std::string why = TextFieldProblem(Trim(fields[c])); !why.empty()) {
        throw Error(path, where + "column '" + header[c] + "' " + why);
      }
    }
    const std::string scan = Trim(fields[scan_column]);
    if (scan.empty()) throw Error(path, where + "empty 'scan' field");
    const fs::path p(scan);
    ScanInput s = MakeInput(p.is_absolute() ? p : base / p);
    s.manifest_line = first_line;
    for (size_t c = 0; c < header.size(); ++c) {
      if (static_cast<int>(c) == scan_column) continue;
      const std::string value = Trim(fields[c]);
      if (!value.empty()) s.overrides.emplace_back(header[c], value);
    }
    scans.push_back(std::move(s));
  }
  if (scans.empty()) throw Error(path, "the manifest lists no scan");
  return scans;
}

std::vector<ScanInput> ListScans(const std::string& input, bool recursive,
                                 const std::vector<std::string>& allowed_columns) {
  std::error_code ec;
  if (fs::is_directory(input, ec)) return ListScanFolder(input, recursive);
  if (!fs::exists(input, ec)) throw Error(input, "no such folder or manifest");
  return ReadScanManifest(input, allowed_columns);
}

void CheckUniqueStems(const std::vector<ScanInput>& scans) {
  std::map<std::string, const ScanInput*> by_stem;
  for (const ScanInput& s : scans) {
    auto [it, inserted] = by_stem.emplace(s.stem, &s);
    if (inserted) continue;
    auto describe = [](const ScanInput& x) {
      return x.path + (x.manifest_line > 0 ? " (manifest line " + std::to_string(x.manifest_line) + ")" : "");
    };
    throw Error(s.path, "same stem '" + s.stem + "' as " + describe(*it->second) + " (now " + describe(s) +
                            "): both would write OUT/" + s.stem + "/; rename one or run them in separate batches");
  }
}

}  // namespace platemeter
