#include "platemeter/core/markup.h"
#include "platemeter/batch/summary.h"

#include <charconv>
#include <chrono>
#include <filesystem>
#include <sstream>

#include "platemeter/batch/temporaries.h"
#include "platemeter/core/number_text.h"

namespace platemeter {
namespace fs = std::filesystem;

namespace {

const char* const kStatuses[] = {"measured", "rejected", "missing"};
const char* const kKinds[] = {"reseau", "fiducial", "star", "trail_dot", "trail_dash", "passpoint"};

// Shortest text that reads back as the same double (as the measurement file does).
std::string OptionalText(const std::optional<double>& v) { return v ? ShortestText(*v) : std::string(); }

int Count(const std::map<std::string, int>& counts, const std::string& key) {
  const auto it = counts.find(key);
  return it == counts.end() ? 0 : it->second;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string Html(const std::string& s) { return EscapeMarkup(s); }

// A relative link to OUT/<folder>/<name>; both are percent-escaped where URLs need it.
std::string Href(const std::string& folder, const std::string& name) {
  std::string out;
  for (unsigned char c : folder + "/" + name) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '-' || c == '_' || c == '~') {
      out += static_cast<char>(c);
    } else {
      char buffer[4];
      std::snprintf(buffer, sizeof buffer, "%%%02X", c);
      out += buffer;
    }
  }
  return Html(out);
}

std::string MeasurementsName(const ScanRecord& r) {
  for (const OutputFile& o : r.outputs) {
    if (o.name.size() > 17 && o.name.compare(o.name.size() - 17, 17, ".measurements.csv") == 0) return o.name;
  }
  return "";
}

}  // namespace

const std::vector<std::string>& SummaryColumns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> c = {"stem", "scan", "status", "reason"};
    for (const char* s : kStatuses) c.push_back(std::string("points_") + s);
    for (const char* k : kKinds) c.push_back(std::string(k) + "_points");
    for (const char* x : {"reseau_rms_um", "scale_x", "scale_y", "seconds", "finished_utc", "fingerprint", "report"}) {
      c.push_back(x);
    }
    return c;
  }();
  return columns;
}

std::string FormatSummaryCsv(const std::vector<ScanRecord>& records) {
  std::ostringstream out;
  const std::vector<std::string>& columns = SummaryColumns();
  for (size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
  out << "\n";
  for (const ScanRecord& r : records) {
    std::vector<std::string> row = {r.stem, r.scan, r.status, r.reason};
    for (const char* s : kStatuses) row.push_back(std::to_string(Count(r.counts_by_status, s)));
    for (const char* k : kKinds) row.push_back(std::to_string(Count(r.counts_by_kind, k)));
    row.push_back(OptionalText(r.reseau_rms_um));
    row.push_back(OptionalText(r.scale_x));
    row.push_back(OptionalText(r.scale_y));
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.3f", r.seconds);
    row.push_back(seconds);
    row.push_back(r.finished_utc);
    row.push_back(r.fingerprint);
    row.push_back(r.report_json.empty() ? "" : ScanFolderName(r.stem) + "/" + r.report_json);
    for (size_t c = 0; c < row.size(); ++c) out << (c ? "," : "") << CsvField(row[c]);
    out << "\n";
  }
  return out.str();
}

std::string FormatHtmlIndex(const std::vector<ScanRecord>& records) {
  int ok = 0, failed = 0;
  for (const ScanRecord& r : records) (r.status == "ok" ? ok : failed)++;
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>platemeter batch</title>\n"
      << "<style>\nbody{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse}"
      << "td,th{border:1px solid #ccc;padding:3px 6px;vertical-align:middle}th{background:#eee}"
      << "td.num{text-align:right;font-variant-numeric:tabular-nums}tr.failed{background:#fdd}"
      << "img{max-width:120px;max-height:120px}\n</style>\n</head>\n<body>\n"
      << "<h1>platemeter batch</h1>\n<p>" << records.size() << " scans: " << ok << " ok, " << failed
      << " failed. Summary table: <a href=\"batch-summary.csv\">batch-summary.csv</a>.</p>\n<table>\n<tr>"
      << "<th>scan</th><th>status</th><th>measured</th><th>rejected</th><th>missing</th>"
      << "<th>reseau RMS (um)</th><th>scale x</th><th>scale y</th><th>time (s)</th><th>outputs</th><th>plot</th></tr>\n";
  for (const ScanRecord& r : records) {
    out << "<tr class=\"" << (r.status == "ok" ? "ok" : "failed") << "\"><td><a href=\"" << Href(ScanFolderName(r.stem), "") << "\">"
        << Html(r.stem) << "</a></td><td>" << Html(r.status);
    if (!r.reason.empty()) out << ": " << Html(r.reason);
    out << "</td>";
    for (const char* s : kStatuses) out << "<td class=\"num\">" << Count(r.counts_by_status, s) << "</td>";
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.1f", r.seconds);
    auto fixed = [](const std::optional<double>& v, const char* format) {
      if (!v) return std::string();
      char b[32];
      std::snprintf(b, sizeof b, format, *v);
      return std::string(b);
    };
    out << "<td class=\"num\">" << fixed(r.reseau_rms_um, "%.2f") << "</td><td class=\"num\">"
        << fixed(r.scale_x, "%.7f") << "</td><td class=\"num\">" << fixed(r.scale_y, "%.7f")
        << "</td><td class=\"num\">" << seconds << "</td><td>";
    const std::string csv = MeasurementsName(r);
    if (!r.report_json.empty()) out << "<a href=\"" << Href(ScanFolderName(r.stem), r.report_json) << "\">report</a> ";
    if (!csv.empty()) out << "<a href=\"" << Href(ScanFolderName(r.stem), csv) << "\">measurements</a> ";
    out << "<a href=\"" << Href(ScanFolderName(r.stem), ScanFolderName(r.stem) + ".batch.json") << "\">record</a></td><td>";
    if (!r.plot_png.empty()) {
      out << "<a href=\"" << Href(ScanFolderName(r.stem), r.plot_png) << "\"><img src=\"" << Href(ScanFolderName(r.stem), r.plot_png)
          << "\" alt=\"residuals of " << Html(r.stem) << "\"></a>";
    }
    out << "</td></tr>\n";
  }
  out << "</table>\n</body>\n</html>\n";
  return out.str();
}

namespace {

// A process killed while writing the summary leaves ".batch-summary.csv.partial.<pid>". Another
// shard (maybe on another machine) may be writing its own right now, for milliseconds: only
// temporaries older than an hour are removed.
void RemoveStaleSummaryTemporaries(const std::string& out_dir) {
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (fs::directory_iterator it(out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(".batch-summary.csv.partial.", 0) != 0 && name.rfind(".index.html.partial.", 0) != 0) continue;
    std::error_code e;
    const auto modified = fs::last_write_time(it->path(), e);
    if (!e && now - modified > std::chrono::hours(1)) fs::remove(it->path(), e);
  }
}

}  // namespace

SummaryFiles WriteBatchSummary(const std::string& out_dir) {
  RemoveStaleSummaryTemporaries(out_dir);
  const std::vector<ScanRecord> records = ReadAllRecords(out_dir);
  SummaryFiles files;
  files.csv_path = (fs::path(out_dir) / "batch-summary.csv").string();
  files.html_path = (fs::path(out_dir) / "index.html").string();
  files.scans = static_cast<int>(records.size());
  for (const ScanRecord& r : records) (r.status == "ok" ? files.ok : files.failed)++;
  WriteSharedFileAtomically(files.csv_path, FormatSummaryCsv(records));
  WriteSharedFileAtomically(files.html_path, FormatHtmlIndex(records));
  return files;
}

}  // namespace platemeter
