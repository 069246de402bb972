#pragma once
// The per-scan record OUT/<stem>/<stem>.batch.json (docs/batch.md): written
// last and atomically, so its presence means the scan was finished; it lists
// every output with its size and SHA-256 so "complete" can be checked later.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace platemeter {

struct OutputFile {
  std::string name;         // file name inside the scan's folder
  uint64_t size_bytes = 0;  // bytes
  std::string sha256;       // lower-case hex
};

struct ScanRecord {
  int format_version = 1;
  std::string stem;    // the scan's stem (= its folder name)
  std::string scan;    // the scan path as listed
  std::string status;  // "ok" or "failed"
  std::string reason;  // failed: why, one line
  std::string failure;  // failed: "input" (a defect of the scan or its options: remembered) or "environment"
                        // (disk full, no permission, I/O: a plain rerun retries it); records before it: "input"
  std::string fingerprint;   // ScanFingerprint (empty when the scan could not be read)
  std::string scan_sha256;   // lower-case hex (empty when unreadable)
  uint64_t scan_size_bytes = 0;  // bytes, when hashed: with the mtime, the quick "unchanged" check
  int64_t scan_mtime_ns = 0;     // ns since the epoch, when hashed
  std::vector<std::pair<std::string, std::string>> overrides;  // manifest overrides applied
  std::map<std::string, int> counts_by_status;  // "measured", "rejected", "missing" -> points
  std::map<std::string, int> counts_by_kind;    // "reseau", "fiducial", ... -> points
  std::optional<double> reseau_rms_um;          // um
  std::optional<double> scale_x, scale_y;       // fitted reseau scales (1 = nominal)
  double seconds = 0.0;       // s; wall time of the scan's work (hash, detect, measure, writes)
  std::string finished_utc;   // ISO 8601 UTC
  std::vector<OutputFile> outputs;  // every output of the scan (not the record)
  std::string report_json;    // name of the JSON report among outputs ("" if none)
  std::string plot_png;       // name of the residual plot among outputs ("" if none)
};

// JSON text (2-space indented, trailing newline).
std::string FormatScanRecord(const ScanRecord& record);
// Throws Error(subject, reason) for malformed JSON or missing/mistyped keys.
ScanRecord ParseScanRecord(const std::string& text, const std::string& subject);

// The name of a scan's folder and record: its stem; a stem too long for the file system's names with
// measure's longest suffix (".measurements.csv", 255 bytes in all) is cut to 200 bytes + "~" + 12 hex digits
// of its SHA-256, so that the scan's failure ("file name too long") is still recorded and listed.
std::string ScanFolderName(const std::string& stem);
// OUT/<folder name>/ and OUT/<folder name>/<folder name>.batch.json.
std::string ScanFolder(const std::string& out_dir, const std::string& stem);
std::string RecordPath(const std::string& out_dir, const std::string& stem);

// The record at `path`; nullopt when absent or unreadable (`why` says which, if given).
std::optional<ScanRecord> ReadScanRecord(const std::string& path, std::string* why = nullptr);
// Writes it atomically (a temporary name, then a rename).
void WriteScanRecord(const std::string& path, const ScanRecord& record);

// True when every output listed exists in `folder` with its size and SHA-256; else `why` says what differs.
bool OutputsIntact(const ScanRecord& record, const std::string& folder, std::string* why);

// Describes a file of `folder` as an OutputFile (size and hash). Throws Error if it cannot be read.
OutputFile DescribeOutput(const std::string& folder, const std::string& name);

// Every record found in OUT (OUT/*/<name>.batch.json), sorted by stem; unreadable ones are skipped
// with a warning.
std::vector<ScanRecord> ReadAllRecords(const std::string& out_dir);

}  // namespace platemeter
