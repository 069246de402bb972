#pragma once
// The scans of a batch: a folder of scan files or a manifest CSV (docs/batch.md).
#include <string>
#include <utility>
#include <vector>

namespace platemeter {

struct ScanInput {
  std::string path;  // the scan file (a manifest's relative paths resolved against the manifest's folder)
  std::string stem;  // file name without its extension: the scan's output folder OUT/<stem>/
  std::vector<std::pair<std::string, std::string>> overrides;  // manifest columns other than `scan`, non-empty values
  int manifest_line = 0;  // 1-based line in the manifest; 0 for a folder listing
};

// True for the scan extensions .tif .tiff .png .jpg .jpeg .fits .fit (any case).
bool IsScanFileName(const std::string& file_name);

// The scan files of a folder, sorted by their path relative to it (byte order); sub-folders
// too when `recursive`. Hidden files (a leading '.') are skipped: they are temporaries.
// Throws Error(folder, ...) when it cannot be read.
std::vector<ScanInput> ListScanFolder(const std::string& folder, bool recursive);

// A manifest: CSV (RFC 4180 quoting), '#' comment lines and blank lines ignored, a header row
// with a `scan` column and optional override columns. `allowed_columns` (when not empty) lists
// the override keys accepted. Rows keep the manifest's order. Throws Error(path, "line N: ...").
std::vector<ScanInput> ReadScanManifest(const std::string& path, const std::vector<std::string>& allowed_columns);

// A folder is listed, anything else is read as a manifest.
std::vector<ScanInput> ListScans(const std::string& input, bool recursive,
                                 const std::vector<std::string>& allowed_columns);

// Two scans with the same stem would share one output folder: throws Error naming both.
void CheckUniqueStems(const std::vector<ScanInput>& scans);

}  // namespace platemeter
