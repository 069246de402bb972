#pragma once
// The batch summary: a CSV with one row per scan record and an HTML index
// linking each scan's report, measurements and plot (docs/batch.md). Built from
// ALL records in OUT, so shards sharing OUT give the union.
#include <string>
#include <vector>

#include "platemeter/batch/scan_record.h"

namespace platemeter {

// The summary CSV's columns, in order (docs/batch.md gives their units).
const std::vector<std::string>& SummaryColumns();
std::string FormatSummaryCsv(const std::vector<ScanRecord>& records);
// The index page; links are relative to OUT.
std::string FormatHtmlIndex(const std::vector<ScanRecord>& records);

struct SummaryFiles {
  std::string csv_path;   // OUT/batch-summary.csv
  std::string html_path;  // OUT/index.html
  int scans = 0, ok = 0, failed = 0;
};

// Reads every record of OUT and rewrites both files atomically.
SummaryFiles WriteBatchSummary(const std::string& out_dir);

}  // namespace platemeter
