#include "platemeter/batch/batch_run.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <atomic>
#include <new>
#include <cerrno>
#include <cstring>
#include <condition_variable>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <set>
#include <thread>

#include "platemeter/batch/fingerprint.h"
#include "platemeter/batch/interrupt.h"
#include "platemeter/batch/summary.h"
#include "platemeter/batch/temporaries.h"
#include "platemeter/core/error.h"
#include "platemeter/core/sha256.h"

namespace platemeter {
namespace fs = std::filesystem;

namespace {

enum class Outcome { kNotStarted, kOk, kFailed, kSkippedOk, kSkippedFailed, kBusy };

struct ItemResult {
  Outcome outcome = Outcome::kNotStarted;
  std::string reason;
  double seconds = 0.0;  // s
};

// The folders of the scans being worked on: a second interrupt removes their temporaries.
struct InFlight {
  std::mutex mutex;
  std::set<std::string> folders;
};

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Files of `folder` that are not the new outputs, not the record and not temporaries: what an
// earlier run with other options left (e.g. a plot no longer made). Removed so the folder holds
// exactly what the record lists.
void RemoveLeftovers(const std::string& folder, const ScanRecord& record) {
  std::set<std::string> keep = {ScanFolderName(record.stem) + ".batch.json"};
  for (const OutputFile& o : record.outputs) keep.insert(o.name);
  std::error_code ec;
  std::vector<fs::path> doomed;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e;
    const std::string name = it->path().filename().string();
    // Outputs are never hidden: hidden files are temporaries and the lock.
    if (it->is_regular_file(e) && !keep.count(name) && name[0] != '.') doomed.push_back(it->path());
  }
  for (const fs::path& p : doomed) fs::remove(p, ec);
}

// Two batches on one scan at once (overlapping shards, a rerun started while the first one still
// runs) would write the same temporaries: a scan is measured under an exclusive flock on
// OUT/<stem>/.<stem>.batch.lock, removed when done. The kernel drops the lock of a killed process.
class ScanLock {
 public:
  explicit ScanLock(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ >= 0 && ::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      fd_ = -1;
      busy_ = true;
    }
  }
  ~ScanLock() {
    if (fd_ < 0) return;
    ::unlink(path_.c_str());  // whoever opened it meanwhile re-checks the record after locking
    ::close(fd_);
  }
  ScanLock(const ScanLock&) = delete;
  ScanLock& operator=(const ScanLock&) = delete;
  bool busy() const { return busy_; }

 private:
  std::string path_;
  int fd_ = -1;
  bool busy_ = false;
};

ItemResult ProcessOne(const BatchItem& item, const ScanWork& work, const BatchOptions& options, InFlight* in_flight) {
  const auto t0 = std::chrono::steady_clock::now();
  const ScanInput& input = item.input;
  const std::string folder = ScanFolder(options.out_dir, input.stem);
  const std::string record_path = RecordPath(options.out_dir, input.stem);
  const std::optional<ScanRecord> old = ReadScanRecord(record_path);

  ScanRecord record;
  record.stem = input.stem;
  record.scan = input.path;
  record.overrides = input.overrides;
  std::string failure;
  // The scan's digest. Unchanged size and mtime reuse the recorded digest (the quick check of
  // make and rsync): rehashing a whole archive of multi-GB scans on every rerun costs hours.
  struct stat st {};
  if (::stat(input.path.c_str(), &st) != 0) {
    failure = input.path + ": cannot read the scan (" + std::strerror(errno) + ")";
    if (errno != ENOENT && errno != ENOTDIR) record.failure = "environment";  // no permission, I/O error
  } else if (!S_ISREG(st.st_mode)) {
    failure = input.path + ": not a regular file";
  } else {
    record.scan_size_bytes = static_cast<uint64_t>(st.st_size);
    record.scan_mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
    if (!options.force && old && !old->scan_sha256.empty() && old->scan_size_bytes == record.scan_size_bytes &&
        old->scan_mtime_ns == record.scan_mtime_ns) {
      record.scan_sha256 = old->scan_sha256;
    } else {
      try {
        record.scan_sha256 = Sha256HexOfFile(input.path);
      } catch (const std::exception& e) {
        failure = OneLine(e.what());
      }
    }
    if (failure.empty()) record.fingerprint = ScanFingerprint(record.scan_sha256, item.options_text);
  }

  // A current record: nothing to do.
  auto current = [&](const std::optional<ScanRecord>& r) -> std::optional<ItemResult> {
    if (options.force || !r || record.fingerprint.empty() || r->fingerprint != record.fingerprint) return std::nullopt;
    std::string why;
    // A failure of the machine (disk full, permission) is retried; one of the input is remembered.
    if (r->status == "failed" && r->failure != "environment" && !options.retry_failed) {
      return ItemResult{Outcome::kSkippedFailed, r->reason};
    }
    if (r->status == "ok" && OutputsIntact(*r, folder, &why)) return ItemResult{Outcome::kSkippedOk, ""};
    return std::nullopt;
  };
  if (std::optional<ItemResult> skip = current(old)) return *skip;

  std::error_code ec;
  fs::create_directories(folder, ec);
  const ScanLock lock((fs::path(folder) / ("." + ScanFolderName(input.stem) + ".batch.lock")).string());
  if (lock.busy()) return {Outcome::kBusy, "being measured by another batch process"};
  // Another process may have finished it between the first look and the lock.
  if (std::optional<ItemResult> skip = current(ReadScanRecord(record_path))) return *skip;

  {
    std::lock_guard<std::mutex> guard(in_flight->mutex);
    in_flight->folders.insert(folder);
  }
  // The record goes first: from here until the new one is written the scan counts as not done.
  fs::remove(record_path, ec);
  RemoveTemporaries(folder);  // a killed run's
  if (failure.empty()) {
    try {
      const ScanWorkResult result = work(item, folder);
      record.counts_by_status = result.counts_by_status;
      record.counts_by_kind = result.counts_by_kind;
      record.reseau_rms_um = result.reseau_rms_um;
      record.scale_x = result.scale_x;
      record.scale_y = result.scale_y;
      for (const std::string& written : result.written_files) {
        const fs::path p(written);
        if (fs::weakly_canonical(p.parent_path(), ec) != fs::weakly_canonical(folder, ec)) {
          throw Error(written, "written outside the scan's folder " + folder);
        }
        record.outputs.push_back(DescribeOutput(folder, p.filename().string()));
      }
      if (!result.report_json.empty()) record.report_json = fs::path(result.report_json).filename().string();
      if (!result.plot_png.empty()) record.plot_png = fs::path(result.plot_png).filename().string();
      record.status = "ok";
    } catch (const EnvironmentError& e) {
      failure = OneLine(e.what());
      record.failure = "environment";
    } catch (const std::bad_alloc&) {
      failure = "out of memory";
      record.failure = "environment";
    } catch (const fs::filesystem_error& e) {
      failure = OneLine(e.what());
      record.failure = "environment";
    } catch (const std::exception& e) {
      failure = OneLine(e.what());
      record.failure = "input";
    }
  }
  if (!failure.empty()) {
    // Nothing of a failed scan's result is kept: its outputs go (RemoveLeftovers) and the record says why.
    record.status = "failed";
    record.reason = failure;
    if (record.failure.empty()) record.failure = "input";
    record.counts_by_status.clear();
    record.counts_by_kind.clear();
    record.reseau_rms_um.reset();
    record.scale_x.reset();
    record.scale_y.reset();
    record.outputs.clear();
    record.report_json.clear();
    record.plot_png.clear();
  }
  RemoveTemporaries(folder);
  RemoveLeftovers(folder, record);
  record.seconds = Since(t0);
  record.finished_utc = UtcNow();
  ItemResult result{record.status == "ok" ? Outcome::kOk : Outcome::kFailed, record.reason, record.seconds};
  try {
    WriteScanRecord(record_path, record);
  } catch (const std::exception& e) {
    result = {Outcome::kFailed, OneLine(e.what())};
  }
  {
    std::lock_guard<std::mutex> guard(in_flight->mutex);
    in_flight->folders.erase(folder);
  }
  return result;
}

const char* OutcomeName(Outcome o) {
  switch (o) {
    case Outcome::kOk: return "ok";
    case Outcome::kFailed: return "failed";
    case Outcome::kSkippedOk: return "skipped";
    case Outcome::kSkippedFailed: return "skipped-failed";
    case Outcome::kBusy: return "busy";
    default: return "not-started";
  }
}

}  // namespace

bool BatchOptions::Check(std::string* why) const {
  if (out_dir.empty()) {
    *why = "no output folder";
    return false;
  }
  if (jobs < 1) {
    *why = "jobs must be at least 1";
    return false;
  }
  return true;
}

std::string BatchOutcome::Summary() const {
  const int total = ok + failed + skipped_ok + skipped_failed + not_started + busy;
  std::string s = std::to_string(total) + " scans: " + std::to_string(ok) + " measured, " +
                  std::to_string(skipped_ok) + " already current, " + std::to_string(failed + skipped_failed) +
                  " failed";
  if (skipped_failed > 0) s += " (" + std::to_string(skipped_failed) + " of them earlier; --retry-failed redoes them)";
  if (busy > 0) s += ", " + std::to_string(busy) + " left to another batch process measuring them";
  if (not_started > 0) s += ", " + std::to_string(not_started) + " not started (interrupted; rerun to continue)";
  return s;
}

BatchOutcome RunBatch(const std::vector<BatchItem>& items, const ScanWork& work, const BatchOptions& options,
                      ProgressReporter* progress) {
  std::string why;
  if (!options.Check(&why)) throw Error("batch", why);
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) throw Error(options.out_dir, "cannot create the output folder (" + ec.message() + ")");

  std::vector<ItemResult> results(items.size());
  std::atomic<size_t> next{0};
  InFlight in_flight;
  std::mutex done_mutex;
  std::condition_variable done_cv;
  bool done = false;

  // The scans run in their own thread inside an arena of `jobs` threads, so this thread stays free
  // to redraw the progress line and to act on a second interrupt.
  std::thread runner([&] {
    tbb::task_arena arena(options.jobs);
    arena.execute([&] {
      tbb::task_group group;
      for (int slot = 0; slot < options.jobs; ++slot) {
        group.run([&] {
          for (;;) {
            if (BatchInterruptCount() > 0) return;  // no new scans after an interrupt
            const size_t i = next.fetch_add(1);
            if (i >= items.size()) return;
            // Isolated: a thread waiting inside one scan's parallel loops must not pick up another
            // whole scan (it would hold the first one's completion hostage).
            tbb::this_task_arena::isolate([&] {
              try {
                results[i] = ProcessOne(items[i], work, options, &in_flight);
              } catch (const std::exception& e) {  // not the work's (ProcessOne records those): e.g. no memory
                results[i] = {Outcome::kFailed, OneLine(e.what())};
              }
            });
            if (progress) {
              progress->ScanFinished(items[i].input.stem, OutcomeName(results[i].outcome), results[i].seconds,
                                    results[i].reason);
            }
          }
        });
      }
      group.wait();
    });
    std::lock_guard<std::mutex> lock(done_mutex);
    done = true;
    done_cv.notify_all();
  });

  {
    std::unique_lock<std::mutex> lock(done_mutex);
    auto last_tick = std::chrono::steady_clock::now();
    // 20 ms: a second interrupt is acted on at once; the progress line is redrawn 4 times a second.
    while (!done_cv.wait_for(lock, std::chrono::milliseconds(20), [&] { return done; })) {
      if (BatchInterruptCount() >= 2) {
        // Abandon the running scans: no final-named file is partial (every write is atomic), their
        // temporaries go, they have no record, so the next run redoes them.
        {
          std::lock_guard<std::mutex> guard(in_flight.mutex);
          for (const std::string& folder : in_flight.folders) RemoveTemporaries(folder);
        }
        if (progress) progress->Finish();
        try {
          WriteBatchSummary(options.out_dir);
        } catch (const std::exception&) {
        }
        std::fprintf(stderr, "platemeter: batch abandoned: the running scans were dropped; rerun to continue\n");
        std::fflush(stderr);
        std::_Exit(128 + (BatchInterruptSignal() ? BatchInterruptSignal() : 2));
      }
      if (progress && std::chrono::steady_clock::now() - last_tick > std::chrono::milliseconds(250)) {
        progress->Tick();
        last_tick = std::chrono::steady_clock::now();
      }
    }
  }
  runner.join();
  if (progress) progress->Finish();

  BatchOutcome outcome;
  for (size_t i = 0; i < items.size(); ++i) {
    const ItemResult& r = results[i];
    switch (r.outcome) {
      case Outcome::kOk: ++outcome.ok; break;
      case Outcome::kFailed: ++outcome.failed; break;
      case Outcome::kSkippedOk: ++outcome.skipped_ok; break;
      case Outcome::kSkippedFailed: ++outcome.skipped_failed; break;
      case Outcome::kNotStarted: ++outcome.not_started; break;
      case Outcome::kBusy: ++outcome.busy; break;
    }
    if (r.outcome == Outcome::kFailed || r.outcome == Outcome::kSkippedFailed) {
      outcome.failures.push_back(items[i].input.stem + ": " + r.reason);
    }
  }
  outcome.interrupt_signal = BatchInterruptSignal();
  return outcome;
}

}  // namespace platemeter
