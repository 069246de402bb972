// `platemeter batch` end to end on the fixture archive (batch_fixture.h): 40 scans with 3 bad
// ones against single `platemeter measure` runs, kill and rerun, SIGINT, three shards with GNU
// parallel against one run, --force and changed options, manifests, exit codes.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "batch/batch_fixture.h"
#include "platemeter/batch/scan_record.h"
#include "platemeter/batch/temporaries.h"
#include "platemeter/measure/measurement_file.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

namespace fs = std::filesystem;
using batch_test::Fixture;
using batch_test::GetFixture;
using testing::CommandResult;
using testing::RunPlatemeter;
using testing::TempDir;

std::string Q(const std::string& s) { return "'" + s + "'"; }
std::string Q(const fs::path& p) { return Q(p.string()); }

std::string ReadTextOfCli(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `platemeter --definitions DEFS batch INPUT -o OUT --camera batchtest --orientation 0 --jobs 2 EXTRA`
std::string BatchArgs(const std::string& input, const fs::path& out, const std::string& extra = "") {
  return "--definitions " + Q(GetFixture().defs) + " batch " + Q(input) + " -o " + Q(out) +
         " --camera batchtest --orientation 0 --jobs 2 " + extra;
}

std::vector<std::string> BatchArgv(const std::string& input, const fs::path& out) {
  return {PLATEMETER_BIN, "--definitions", GetFixture().defs, "batch", input, "-o", out.string(),
          "--camera", "batchtest", "--orientation", "0", "--jobs", "2"};
}

// A folder of symlinks to the fixture's scans `indices` (same bytes, their own folder).
fs::path LinkScans(const TempDir& dir, const std::string& name, const std::vector<int>& indices) {
  const fs::path folder = dir.path() / name;
  fs::create_directories(folder);
  for (int i : indices) fs::create_symlink(GetFixture().Scan(i), folder / (GetFixture().names[i] + ".tif"));
  return folder;
}

std::vector<int> GoodIndices(size_t count) {
  std::vector<int> good;
  for (int i = 0; i < batch_test::kScans && good.size() < count; ++i) {
    if (!GetFixture().IsBad(i)) good.push_back(i);
  }
  return good;
}

// name -> contents of the regular files directly in `folder`.
std::map<std::string, std::string> FilesIn(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.is_regular_file()) files[e.path().filename().string()] = ReadTextOfCli(e.path());
  }
  return files;
}

int CountRecords(const fs::path& out) {
  int n = 0;
  std::error_code ec;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string stem = it->path().filename().string();
    std::error_code e;
    if (fs::exists(it->path() / (stem + ".batch.json"), e)) ++n;
  }
  return n;
}

std::vector<fs::path> TemporariesUnder(const fs::path& out) {
  std::vector<fs::path> found;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (IsTemporaryName(e.path().filename().string())) found.push_back(e.path());
  }
  return found;
}

// Every file with a final name under OUT is whole: measurement files parse with their 25
// crosses, JSON parses, PNGs end with their IEND chunk, records match their outputs.
void ExpectNoPartialFile(const fs::path& out) {
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    if (IsTemporaryName(name)) continue;
    const std::string text = ReadTextOfCli(e.path());
    SCOPED_TRACE(e.path().string());
    if (name.size() > 17 && name.substr(name.size() - 17) == ".measurements.csv") {
      const MeasurementFile file = ReadMeasurementFile(e.path().string());
      EXPECT_EQ(file.points.size(), 25u);
    } else if (name.size() > 11 && name.substr(name.size() - 11) == ".batch.json") {
      std::string why;
      const std::optional<ScanRecord> r = ReadScanRecord(e.path().string(), &why);
      ASSERT_TRUE(r) << why;
      EXPECT_TRUE(OutputsIntact(*r, e.path().parent_path().string(), &why)) << why;
    } else if (name.size() > 5 && name.substr(name.size() - 5) == ".json") {
      EXPECT_TRUE(nlohmann::json::accept(text));
    } else if (name.size() > 4 && name.substr(name.size() - 4) == ".png") {
      ASSERT_GE(text.size(), 20u);
      EXPECT_EQ(text.substr(1, 3), "PNG");
      EXPECT_EQ(text.substr(text.size() - 8, 4), "IEND");
    } else if (name.size() > 4 && name.substr(name.size() - 4) == ".xml") {
      EXPECT_EQ(text.substr(text.find_last_not_of(" \n") , 1), ">");
    }
  }
}

struct FileId {
  ino_t inode = 0;
  int64_t mtime_ns = 0;
  bool operator==(const FileId& o) const { return inode == o.inode && mtime_ns == o.mtime_ns; }
};

std::map<std::string, FileId> RecordIds(const fs::path& out) {
  std::map<std::string, FileId> ids;
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string stem = e.path().filename().string();
    struct stat st {};
    if (::stat((e.path() / (stem + ".batch.json")).c_str(), &st) == 0) {
      ids[stem] = {st.st_ino, int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
    }
  }
  return ids;
}

pid_t Spawn(const std::vector<std::string>& argv, const fs::path& log) {
  const pid_t child = fork();
  if (child == 0) {
    if (!std::freopen(log.c_str(), "w", stdout) || !std::freopen(log.c_str(), "a", stderr)) _exit(126);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return child;
}

// Waits until OUT holds `records` records or the child ends; true if it is still running.
bool WaitForRecords(pid_t child, const fs::path& out, int records) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(child, &status, WNOHANG) == child) return false;
    if (CountRecords(out) >= records) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// The fields of one CSV line (RFC 4180 quoting, as the summary writes it).
std::vector<std::string> CsvFields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// A summary CSV without the columns that differ between runs (seconds, finished_utc).
std::vector<std::vector<std::string>> SummaryWithoutTimes(const fs::path& csv) {
  std::stringstream in(ReadTextOfCli(csv));
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields = CsvFields(line);
    EXPECT_EQ(fields.size(), 20u) << line;
    if (fields.size() != 20u) continue;
    if (rows.empty()) {
      EXPECT_EQ(fields[16] + "," + fields[17], "seconds,finished_utc");
    }
    fields.erase(fields.begin() + 16, fields.begin() + 18);  // seconds, finished_utc
    rows.push_back(fields);
  }
  return rows;
}

TEST(BatchCli, FortyScansThreeBadMatchSingleRuns) {
  const Fixture& f = GetFixture();
  TempDir dir;
  const fs::path out = dir.path() / "out";
  const CommandResult r = RunPlatemeter(BatchArgs(f.scans, out));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;  // some scans failed
  EXPECT_NE(r.out.find("batch: 40 scans: 37 measured, 0 already current, 3 failed"), std::string::npos) << r.out;
  // The three bad ones, each with its reason, on stdout and in the summary.
  const std::map<int, std::string> expected_reason = {
      {batch_test::kTruncated, "the file is truncated"},
      {batch_test::kNotAnImage, "cannot read as an image"},
      {batch_test::kWrongCamera, "no arrangement of the grid fits the cross candidates"}};
  for (const auto& [i, reason] : expected_reason) {
    const std::string line_start = "failed: " + f.names[i] + ": ";
    const size_t at = r.out.find(line_start);
    ASSERT_NE(at, std::string::npos) << r.out;
    const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NE(line.find(reason), std::string::npos) << line;
    const std::optional<ScanRecord> record = ReadScanRecord(RecordPath(out.string(), f.names[i]));
    ASSERT_TRUE(record);
    EXPECT_EQ(record->status, "failed");
    EXPECT_EQ(line, line_start + record->reason);
    EXPECT_EQ(FilesIn(out / f.names[i]).size(), 1u);  // the record alone
  }
  const std::string csv = ReadTextOfCli(out / "batch-summary.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 41);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n') - 1,
            static_cast<long>(ReadAllRecords(out.string()).size()));
  const std::string html = ReadTextOfCli(out / "index.html");
  EXPECT_NE(html.find("40 scans: 37 ok, 3 failed"), std::string::npos);

  // Every good scan measured alone by `platemeter measure`, two at a time.
  const fs::path single = dir.path() / "single";
  std::vector<int> good = GoodIndices(40);
  ASSERT_EQ(good.size(), 37u);
  std::vector<CommandResult> singles(good.size());
  auto run = [&](size_t first) {
    for (size_t k = first; k < good.size(); k += 2) {
      singles[k] = RunPlatemeter("--definitions " + Q(f.defs) + " measure " + Q(f.Scan(good[k])) +
                                 " --camera batchtest --orientation 0 -o " + Q(single / f.names[good[k]]));
    }
  };
  std::thread other(run, 1);
  run(0);
  other.join();
  for (size_t k = 0; k < good.size(); ++k) {
    const std::string& stem = f.names[good[k]];
    SCOPED_TRACE(stem);
    ASSERT_EQ(singles[k].exit_code, 0) << singles[k].err;
    std::map<std::string, std::string> batch_files = FilesIn(out / stem);
    ASSERT_EQ(batch_files.erase(stem + ".batch.json"), 1u);
    const std::map<std::string, std::string> single_files = FilesIn(single / stem);
    ASSERT_GE(single_files.size(), 3u);  // measurements, report, plot, MicMac
    ASSERT_TRUE(single_files.count(stem + ".measurements.csv"));
    // The same files, byte for byte (both name the scan by the same path).
    EXPECT_EQ(batch_files, single_files);
    const std::optional<ScanRecord> record = ReadScanRecord(RecordPath(out.string(), stem));
    ASSERT_TRUE(record);
    EXPECT_EQ(record->status, "ok");
    EXPECT_EQ(record->outputs.size(), single_files.size());
    EXPECT_EQ(record->counts_by_kind.at("reseau"), 25);
    ASSERT_TRUE(record->reseau_rms_um);
    EXPECT_LT(*record->reseau_rms_um, 20.0);
    EXPECT_NE(html.find("href=\"" + stem + "/" + stem + ".measure.json\""), std::string::npos);
  }

  // A rerun finds everything current and touches no record.
  const std::map<std::string, FileId> before = RecordIds(out);
  const CommandResult again = RunPlatemeter(BatchArgs(f.scans, out));
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.out.find("40 scans: 0 measured, 37 already current, 3 failed (3 of them earlier"),
            std::string::npos)
      << again.out;
  EXPECT_EQ(RecordIds(out), before);
}

TEST(BatchCli, KilledHalfWayRerunDoesEveryScanOnce) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(12)), out = dir.path() / "out";
  const pid_t child = Spawn(BatchArgv(in.string(), out), dir.path() / "killed.log");
  const bool running = WaitForRecords(child, out, 4);
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(running && WIFSIGNALED(status)) << "the batch ended before it could be killed: "
                                              << ReadTextOfCli(dir.path() / "killed.log");
  const std::map<std::string, FileId> finished = RecordIds(out);
  ASSERT_GE(finished.size(), 4u);
  ASSERT_LT(finished.size(), 12u) << "the kill came too late to test anything";
  ExpectNoPartialFile(out);

  const CommandResult r = RunPlatemeter(BatchArgs(in.string(), out));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string expected = "12 scans: " + std::to_string(12 - finished.size()) + " measured, " +
                               std::to_string(finished.size()) + " already current, 0 failed";
  EXPECT_NE(r.out.find(expected), std::string::npos) << r.out;
  // The scans finished before the kill were not redone: their records are the same files.
  const std::map<std::string, FileId> after = RecordIds(out);
  EXPECT_EQ(after.size(), 12u);
  for (const auto& [stem, id] : finished) EXPECT_TRUE(after.at(stem) == id) << stem;
  for (const ScanRecord& record : ReadAllRecords(out.string())) EXPECT_EQ(record.status, "ok") << record.stem;
  EXPECT_TRUE(TemporariesUnder(out).empty());
  ExpectNoPartialFile(out);
}

TEST(BatchCli, SigintFinishesRunningScansAndExits130) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(12)), out = dir.path() / "out";
  const pid_t child = Spawn(BatchArgv(in.string(), out), dir.path() / "interrupted.log");
  const bool running = WaitForRecords(child, out, 3);
  kill(child, SIGINT);
  int status = 0;
  waitpid(child, &status, 0);
  const std::string log = ReadTextOfCli(dir.path() / "interrupted.log");
  ASSERT_TRUE(running) << log;
  ASSERT_TRUE(WIFEXITED(status)) << log;
  EXPECT_EQ(WEXITSTATUS(status), 130) << log;
  EXPECT_NE(log.find("batch interrupted (SIGINT)"), std::string::npos) << log;
  const int done = CountRecords(out);
  EXPECT_LT(done, 12) << log;
  // The summary was rewritten with what is done; nothing partial, nothing temporary.
  const std::string csv = ReadTextOfCli(out / "batch-summary.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), done + 1);
  EXPECT_TRUE(TemporariesUnder(out).empty());
  ExpectNoPartialFile(out);
  const CommandResult r = RunPlatemeter(BatchArgs(in.string(), out));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find(std::to_string(done) + " already current"), std::string::npos) << r.out;
  EXPECT_EQ(CountRecords(out), 12);
}

TEST(BatchCli, SecondSigintAbandonsRunningScans) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(6)), out = dir.path() / "out";
  const pid_t child = Spawn(BatchArgv(in.string(), out), dir.path() / "abandoned.log");
  const bool running = WaitForRecords(child, out, 1);
  // Let the scan that replaces the finished one start (~1 s each): interrupted at the very moment of the
  // first record, no new scan starts and the other running one may finish before the second interrupt
  // (seen once under load: nothing left to abandon).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(child, SIGINT);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  kill(child, SIGINT);
  int status = 0;
  waitpid(child, &status, 0);
  const std::string log = ReadTextOfCli(dir.path() / "abandoned.log");
  ASSERT_TRUE(running) << log;
  ASSERT_TRUE(WIFEXITED(status)) << log;
  EXPECT_EQ(WEXITSTATUS(status), 130) << log;
  EXPECT_NE(log.find("batch abandoned"), std::string::npos) << log;
  ExpectNoPartialFile(out);
  const int done = CountRecords(out);
  const CommandResult r = RunPlatemeter(BatchArgs(in.string(), out));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("6 scans: " + std::to_string(6 - done) + " measured, " + std::to_string(done) +
                       " already current"),
            std::string::npos)
      << r.out;
  EXPECT_TRUE(TemporariesUnder(out).empty());
}

TEST(BatchCli, ThreeShardsWithGnuParallelEqualOneRun) {
  // GNU parallel is a declared dependency (scripts/setup): missing, the test fails.
  ASSERT_EQ(std::system("command -v parallel >/dev/null 2>&1"), 0) << "GNU parallel is not installed";
  const Fixture& f = GetFixture();
  TempDir dir;
  // 15 scans, two of them bad (plate-07 and plate-19 at positions 7 and 13).
  std::vector<int> indices = GoodIndices(13);
  indices.push_back(batch_test::kTruncated);
  indices.push_back(batch_test::kNotAnImage);
  const fs::path in = LinkScans(dir, "in", indices);
  const fs::path one = dir.path() / "one", sharded = dir.path() / "sharded";
  const CommandResult single = RunPlatemeter(BatchArgs(in.string(), one));
  ASSERT_EQ(single.exit_code, 1) << single.err;

  const std::string command = "parallel --will-cite '" + std::string(PLATEMETER_BIN) + "' --definitions " + Q(f.defs) +
                              " batch " + Q(in) + " -o " + Q(sharded) +
                              " --camera batchtest --orientation 0 --jobs 1 --shard {}/3 '>' " +
                              Q(dir.path() / "shard-{}.log") + " '2>&1' ::: 1 2 3";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  // Sorted, plate-07 is at position 7 (shard 2) and plate-19 at 14 (shard 3): shards 2 and 3 fail.
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(ReadTextOfCli(dir.path() / "shard-1.log").find("5 scans: 5 measured, 0 already current, 0 failed"),
            std::string::npos)
      << ReadTextOfCli(dir.path() / "shard-1.log");
  EXPECT_NE(ReadTextOfCli(dir.path() / "shard-2.log").find("5 scans: 4 measured, 0 already current, 1 failed"),
            std::string::npos)
      << ReadTextOfCli(dir.path() / "shard-2.log");
  EXPECT_NE(ReadTextOfCli(dir.path() / "shard-3.log").find("5 scans: 4 measured, 0 already current, 1 failed"),
            std::string::npos)
      << ReadTextOfCli(dir.path() / "shard-3.log");
  const CommandResult summary = RunPlatemeter("batch --summary-only -o " + Q(sharded));
  EXPECT_EQ(summary.exit_code, 1);  // some records say failed
  EXPECT_NE(summary.out.find("15 scan records: 13 ok, 2 failed"), std::string::npos) << summary.out;

  // The union equals the single run: the same folders, the same outputs byte for byte, the same
  // records but for their times, the same summary but for its time columns.
  const std::vector<ScanRecord> a = ReadAllRecords(one.string()), b = ReadAllRecords(sharded.string());
  ASSERT_EQ(a.size(), 15u);
  ASSERT_EQ(b.size(), 15u);
  for (size_t k = 0; k < a.size(); ++k) {
    SCOPED_TRACE(a[k].stem);
    EXPECT_EQ(a[k].stem, b[k].stem);
    EXPECT_EQ(a[k].status, b[k].status);
    EXPECT_EQ(a[k].reason, b[k].reason);
    EXPECT_EQ(a[k].fingerprint, b[k].fingerprint);
    std::map<std::string, std::string> fa = FilesIn(one / a[k].stem), fb = FilesIn(sharded / b[k].stem);
    fa.erase(a[k].stem + ".batch.json");
    fb.erase(b[k].stem + ".batch.json");
    EXPECT_EQ(fa, fb);
  }
  const auto rows_one = SummaryWithoutTimes(one / "batch-summary.csv");
  EXPECT_EQ(rows_one.size(), 16u);
  EXPECT_EQ(rows_one, SummaryWithoutTimes(sharded / "batch-summary.csv"));
}

TEST(BatchCli, ForceAndChangedOptionsRedoScans) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(3)), out = dir.path() / "out";
  ASSERT_EQ(RunPlatemeter(BatchArgs(in.string(), out)).exit_code, 0);
  const std::map<std::string, FileId> first = RecordIds(out);
  CommandResult r = RunPlatemeter(BatchArgs(in.string(), out));
  EXPECT_NE(r.out.find("3 scans: 0 measured, 3 already current"), std::string::npos) << r.out;
  r = RunPlatemeter(BatchArgs(in.string(), out, "--force"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("3 scans: 3 measured, 0 already current"), std::string::npos) << r.out;
  const std::map<std::string, FileId> forced = RecordIds(out);
  for (const auto& [stem, id] : first) EXPECT_FALSE(forced.at(stem) == id) << stem;
  // An option that changes the outputs makes every record stale.
  r = RunPlatemeter(BatchArgs(in.string(), out, "--temperature-degC 25"));
  EXPECT_NE(r.out.find("3 scans: 3 measured, 0 already current"), std::string::npos) << r.out;
  r = RunPlatemeter(BatchArgs(in.string(), out, "--temperature-degC 25"));
  EXPECT_NE(r.out.find("3 scans: 0 measured, 3 already current"), std::string::npos) << r.out;
  // A tampered output makes its scan incomplete: redone.
  const std::string stem = GetFixture().names[GoodIndices(1)[0]];
  std::ofstream(out / stem / (stem + ".measure.json"), std::ios::app) << " ";
  r = RunPlatemeter(BatchArgs(in.string(), out, "--temperature-degC 25"));
  EXPECT_NE(r.out.find("3 scans: 1 measured, 2 already current"), std::string::npos) << r.out;
}

TEST(BatchCli, ManifestOverridesApplyPerScan) {
  const Fixture& f = GetFixture();
  TempDir dir;
  const std::vector<int> good = GoodIndices(2);
  const fs::path manifest = dir.path() / "plates.csv", out = dir.path() / "out";
  std::ofstream(manifest) << "# two plates, the first measured warm\nscan,temperature_degC\n"
                          << f.Scan(good[0]) << ",25\n"
                          << fs::relative(f.Scan(good[1]), dir.path()).string() << ",\n";
  const CommandResult r = RunPlatemeter(BatchArgs(manifest.string(), out));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const MeasurementFile warm = ReadMeasurementFile((out / f.names[good[0]] / (f.names[good[0]] + ".measurements.csv")).string());
  const MeasurementFile plain = ReadMeasurementFile((out / f.names[good[1]] / (f.names[good[1]] + ".measurements.csv")).string());
  auto has_thermal = [](const MeasurementFile& m) {
    for (const AppliedCorrection& c : m.header.corrections) {
      if (c.name == "thermal") return true;
    }
    return false;
  };
  EXPECT_TRUE(has_thermal(warm));
  EXPECT_FALSE(has_thermal(plain));
  const std::optional<ScanRecord> record = ReadScanRecord(RecordPath(out.string(), f.names[good[0]]));
  ASSERT_TRUE(record);
  EXPECT_EQ(record->overrides, (std::vector<std::pair<std::string, std::string>>{{"temperature_degC", "25"}}));
}

TEST(BatchCli, JobFileEqualsTheSameFlags) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(2)), out = dir.path() / "out";
  ASSERT_EQ(RunPlatemeter(BatchArgs(in.string(), out, "--temperature-degC 25")).exit_code, 0);
  // The same options from a job file: the same fingerprints, so nothing is redone.
  std::ofstream(dir.path() / "job.toml") << "camera = \"batchtest\"\norientation = \"0\"\n[measure]\ntemperature_degC = 25.0\n";
  CommandResult r = RunPlatemeter("--definitions " + Q(GetFixture().defs) + " batch " + Q(in) + " -o " + Q(out) +
                                  " --job " + Q(dir.path() / "job.toml") + " --jobs 2");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("2 scans: 0 measured, 2 already current"), std::string::npos) << r.out << r.err;
  // A flag given with --job overrides the job's value: other options, redone.
  r = RunPlatemeter("--definitions " + Q(GetFixture().defs) + " batch " + Q(in) + " -o " + Q(out) + " --job " +
                    Q(dir.path() / "job.toml") + " --temperature-degC 21 --jobs 2");
  EXPECT_NE(r.out.find("2 scans: 2 measured, 0 already current"), std::string::npos) << r.out << r.err;
}

TEST(BatchCli, OutputInsideInputIsNotScanned) {
  TempDir dir;
  const fs::path in = LinkScans(dir, "in", GoodIndices(2)), out = in / "results";
  ASSERT_EQ(RunPlatemeter(BatchArgs(in.string(), out)).exit_code, 0);
  const CommandResult r = RunPlatemeter(BatchArgs(in.string(), out, "--recursive"));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;  // the residual plots in OUT are not taken for scans
  EXPECT_NE(r.out.find("2 scans: 0 measured, 2 already current"), std::string::npos) << r.out;
}

TEST(BatchCli, UsageAndInputErrorsExit2BeforeAnyScan) {
  const Fixture& f = GetFixture();
  TempDir dir;
  const fs::path out = dir.path() / "out";
  auto expect_usage = [&](const std::string& args, const std::string& message) {
    const CommandResult r = RunPlatemeter(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;  // one line
    EXPECT_FALSE(fs::exists(out)) << args;                                 // nothing started
  };
  const std::string defs = "--definitions " + Q(f.defs) + " ";
  expect_usage(defs + "batch " + Q(f.scans) + " -o " + Q(out), "give --camera NAME or --job JOB.toml");
  expect_usage(defs + "batch -o " + Q(out) + " --camera batchtest", "INPUT");
  expect_usage(defs + "batch " + Q(f.scans) + " -o " + Q(out) + " --camera batchtest --shard 4/3", "--shard");
  expect_usage(defs + "batch " + Q(dir.path() / "nowhere") + " -o " + Q(out) + " --camera batchtest",
               "no such folder or manifest");
  fs::create_directories(dir.path() / "empty");
  std::ofstream(dir.path() / "empty" / "notes.txt") << "no scans here\n";
  expect_usage(defs + "batch " + Q(dir.path() / "empty") + " -o " + Q(out) + " --camera batchtest", "no scan files");
  std::ofstream(dir.path() / "bad-column.csv") << "scan,colour\n" << f.Scan(0) << ",red\n";
  expect_usage(defs + "batch " + Q(dir.path() / "bad-column.csv") + " -o " + Q(out) + " --camera batchtest",
               "line 1: unknown column 'colour'");
  std::ofstream(dir.path() / "bad-value.csv") << "scan,orientation\n" << f.Scan(0) << ",0\n" << f.Scan(1) << ",sideways\n";
  expect_usage(defs + "batch " + Q(dir.path() / "bad-value.csv") + " -o " + Q(out) + " --camera batchtest", "line 3");
  std::ofstream(dir.path() / "same-stem.csv") << "scan\n" << f.Scan(0) << "\n" << (dir.path() / "other" / "plate-00.png").string() << "\n";
  expect_usage(defs + "batch " + Q(dir.path() / "same-stem.csv") + " -o " + Q(out) + " --camera batchtest",
               "same stem 'plate-00'");
  expect_usage("batch --summary-only -o " + Q(out), "");
}

}  // namespace
}  // namespace platemeter
