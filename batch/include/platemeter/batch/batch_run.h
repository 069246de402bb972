#pragma once
// The run loop: every scan of the list measured in parallel (oneTBB, at most
// `jobs` at a time), skipped when its record is current, recorded last and
// atomically. The work on one scan is a function given by the caller
// (measure_batch.h: the pipeline's RunMeasure; tests: a fake).
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/batch/progress.h"
#include "platemeter/batch/scan_list.h"
#include "platemeter/batch/scan_record.h"

namespace platemeter {

// One scan of this run with the canonical text of its options (overrides applied).
struct BatchItem {
  ScanInput input;
  std::string options_text;
};

// What the work on one scan reports (MeasureScanWork fills it from RunMeasure).
struct ScanWorkResult {
  std::map<std::string, int> counts_by_status;
  std::map<std::string, int> counts_by_kind;
  std::optional<double> reseau_rms_um;
  std::optional<double> scale_x, scale_y;
  std::vector<std::string> written_files;  // paths of every file written (inside the scan's folder)
  std::string report_json;                 // path of the JSON report ("" if none)
  std::string plot_png;                    // path of the residual plot ("" if none)
};

// Measures item.input into `folder` (created); throws on failure (the reason becomes the record's).
using ScanWork = std::function<ScanWorkResult(const BatchItem& item, const std::string& folder)>;

struct BatchOptions {
  std::string out_dir;        // OUT
  int jobs = 1;               // scans at a time (and threads in all), >= 1
  bool force = false;         // redo every scan even when its record is current
  bool retry_failed = false;  // redo scans whose current record says failed
  bool Check(std::string* why) const;
};

struct BatchOutcome {
  int ok = 0;              // measured now, ok
  int failed = 0;          // measured now, failed
  int skipped_ok = 0;      // current record, ok
  int skipped_failed = 0;  // current record, failed (not retried)
  int not_started = 0;     // left by an interrupt
  int busy = 0;            // being measured by another batch process at the same time (left to it)
  int interrupt_signal = 0;  // SIGINT/SIGTERM that stopped the run, 0 if none
  std::vector<std::string> failures;  // "stem: reason" of the failed scans (now or skipped), list order
  bool AllOk() const {
    return failed == 0 && skipped_failed == 0 && not_started == 0 && busy == 0 && interrupt_signal == 0;
  }
  std::string Summary() const;
};

// Runs the batch. Interrupts (interrupt.h) stop it from taking new scans; a second one
// abandons the running scans: their temporaries are removed, the summary rewritten and the
// process exits with 128 + signal.
BatchOutcome RunBatch(const std::vector<BatchItem>& items, const ScanWork& work, const BatchOptions& options,
                      ProgressReporter* progress);

}  // namespace platemeter
