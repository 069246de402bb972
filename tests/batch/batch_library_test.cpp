// The batch library on its own: sharding, fingerprints, manifests, folder listing, records,
// summary, temporaries and the run loop with a stand-in for the measurement.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "platemeter/batch/batch_run.h"
#include "platemeter/batch/fingerprint.h"
#include "platemeter/batch/scan_list.h"
#include "platemeter/batch/scan_record.h"
#include "platemeter/batch/shard.h"
#include "platemeter/batch/summary.h"
#include "platemeter/batch/temporaries.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/error.h"
#include "platemeter/core/sha256.h"
#include "support/test_support.h"

namespace platemeter {
namespace {
namespace fs = std::filesystem;
using testing::TempDir;

void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

std::string ReadTextOfLibrary(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Shard, ParsesKOverN) {
  const Shard s = ParseShard("3/8");
  EXPECT_EQ(s.index, 3);
  EXPECT_EQ(s.count, 8);
  for (const char* bad : {"0/3", "4/3", "1/0", "3", "a/b", "1/3x", "/3", "-1/3", ""}) {
    EXPECT_NE(ErrorOf([&] { ParseShard(bad); }), "") << bad;
  }
}

TEST(Shard, ShardsPartitionTheListExactly) {
  for (int n = 1; n <= 7; ++n) {
    for (size_t total = 0; total <= 45; ++total) {
      std::vector<int> owner(total, 0);
      size_t smallest = total, largest = 0;
      for (int k = 1; k <= n; ++k) {
        const std::vector<size_t> positions = ShardPositions(total, {k, n});
        smallest = std::min(smallest, positions.size());
        largest = std::max(largest, positions.size());
        for (size_t p : positions) {
          ASSERT_LT(p, total);
          EXPECT_TRUE(InShard(p, {k, n}));
          ++owner[p];
        }
      }
      for (size_t p = 0; p < total; ++p) EXPECT_EQ(owner[p], 1) << "position " << p << " of " << total << ", N " << n;
      EXPECT_LE(largest - smallest, 1u);
    }
  }
  // The documented rule: position i goes to shard (i mod N) + 1.
  EXPECT_EQ(ShardPositions(10, {2, 3}), (std::vector<size_t>{1, 4, 7}));
}

TEST(Fingerprint, ChangesWithBytesAndOptions) {
  const std::string a = Sha256Hex("scan bytes"), b = Sha256Hex("scan bytez");
  const std::string f = ScanFingerprint(a, "camera = x\nmodel = scales\n");
  EXPECT_EQ(f.size(), 64u);
  EXPECT_EQ(f, ScanFingerprint(a, "camera = x\nmodel = scales\n"));
  EXPECT_NE(f, ScanFingerprint(b, "camera = x\nmodel = scales\n"));
  EXPECT_NE(f, ScanFingerprint(a, "camera = x\nmodel = affine\n"));
  EXPECT_NE(f, ScanFingerprint(a, "camera = x\nmodel = scales\ntemperature_degC = 21\n"));
}

TEST(ScanList, FolderListingFiltersAndSorts) {
  TempDir dir;
  for (const char* name : {"b.tif", "a.TIFF", "c.png", "d.jpg", "e.jpeg", "f.fits", "g.fit", "notes.txt",
                           ".hidden.tif", "sub/h.tif", "sub/deeper/i.png", ".git/j.tif"}) {
    WriteText(dir.path() / name, "x");
  }
  fs::create_directories(dir.path() / "folder.tif");  // a folder with a scan's name is not a scan
  std::vector<std::string> flat, deep;
  for (const ScanInput& s : ListScanFolder(dir.path().string(), false)) flat.push_back(fs::path(s.path).filename().string());
  for (const ScanInput& s : ListScanFolder(dir.path().string(), true)) {
    deep.push_back(fs::relative(s.path, dir.path()).generic_string());
  }
  EXPECT_EQ(flat, (std::vector<std::string>{"a.TIFF", "b.tif", "c.png", "d.jpg", "e.jpeg", "f.fits", "g.fit"}));
  EXPECT_EQ(deep, (std::vector<std::string>{"a.TIFF", "b.tif", "c.png", "d.jpg", "e.jpeg", "f.fits", "g.fit",
                                            "sub/deeper/i.png", "sub/h.tif"}));
  EXPECT_EQ(ListScanFolder(dir.path().string(), false)[0].stem, "a");
  EXPECT_NE(ErrorOf([&] { ListScanFolder(dir.file("missing"), false); }), "");
}

TEST(ScanList, ManifestWithOverridesAndQuoting) {
  TempDir dir;
  const std::string manifest = dir.file("plates/manifest.csv");
  WriteText(manifest,
            "# plates of the 1972 campaign\n"
            "scan,orientation,trails.start_utc,temperature_degC\n"
            "a.tif,90m,1972-05-12T05:30:00Z,21.5\n"
            "\n"
            "\"sub dir/b, second.tif\",,1972-05-13T05:30:00Z,\n"
            "# a comment between rows\n"
            "/abs/c.tif,0,,\r\n");
  const std::vector<ScanInput> scans =
      ReadScanManifest(manifest, {"orientation", "trails.start_utc", "temperature_degC"});
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[0].path, (dir.path() / "plates" / "a.tif").string());
  EXPECT_EQ(scans[0].manifest_line, 3);
  EXPECT_EQ(scans[0].overrides, (std::vector<std::pair<std::string, std::string>>{
                                    {"orientation", "90m"}, {"trails.start_utc", "1972-05-12T05:30:00Z"},
                                    {"temperature_degC", "21.5"}}));
  EXPECT_EQ(scans[1].path, (dir.path() / "plates" / "sub dir" / "b, second.tif").string());
  EXPECT_EQ(scans[1].stem, "b, second");
  EXPECT_EQ(scans[1].manifest_line, 5);
  EXPECT_EQ(scans[1].overrides.size(), 1u);  // empty fields are no override
  EXPECT_EQ(scans[2].path, "/abs/c.tif");
  EXPECT_EQ(scans[2].overrides, (std::vector<std::pair<std::string, std::string>>{{"orientation", "0"}}));
}

TEST(ScanList, ManifestErrorsNameTheLine) {
  TempDir dir;
  auto error = [&](const std::string& text) {
    WriteText(dir.path() / "m.csv", text);
    return ErrorOf([&] { ReadScanManifest(dir.file("m.csv"), {"orientation", "temperature_degC"}); });
  };
  EXPECT_NE(error("path,orientation\na.tif,0\n").find("line 1: no 'scan' column"), std::string::npos);
  EXPECT_NE(error("# c\nscan,colour\na.tif,red\n").find("line 2: unknown column 'colour'"), std::string::npos);
  EXPECT_NE(error("scan,orientation\na.tif,0\nb.tif\n").find("line 3: 1 fields, the header has 2"), std::string::npos);
  EXPECT_NE(error("scan,orientation\na.tif,0\n,90\n").find("line 3: empty 'scan' field"), std::string::npos);
  EXPECT_NE(error("scan,orientation\na.tif,0\n\"b.tif,0\n").find("line 3: unterminated quote"), std::string::npos);
  EXPECT_NE(error("scan,scan\na.tif,b.tif\n").find("line 1: column 'scan' appears twice"), std::string::npos);
  EXPECT_NE(error("scan\n").find("lists no scan"), std::string::npos);
  EXPECT_NE(error("").find("empty"), std::string::npos);
}

TEST(ScanList, SameStemIsRefusedBeforeStarting) {
  std::vector<ScanInput> scans(3);
  scans[0] = {"/x/a.tif", "a", {}, 2};
  scans[1] = {"/x/b.tif", "b", {}, 3};
  scans[2] = {"/y/a.png", "a", {}, 4};
  const std::string e = ErrorOf([&] { CheckUniqueStems(scans); });
  EXPECT_NE(e.find("/x/a.tif (manifest line 2)"), std::string::npos) << e;
  EXPECT_NE(e.find("/y/a.png (manifest line 4)"), std::string::npos) << e;
  scans.pop_back();
  EXPECT_EQ(ErrorOf([&] { CheckUniqueStems(scans); }), "");
}

ScanRecord SampleRecord() {
  ScanRecord r;
  r.stem = "plate-07";
  r.scan = "/archive/plate-07.tif";
  r.status = "ok";
  r.fingerprint = std::string(64, 'a');
  r.scan_sha256 = std::string(64, 'b');
  r.scan_size_bytes = 123456789012ull;
  r.scan_mtime_ns = 1700000000123456789ll;
  r.overrides = {{"orientation", "90m"}, {"temperature_degC", "21.5"}};
  r.counts_by_status = {{"measured", 118}, {"rejected", 2}, {"missing", 1}};
  r.counts_by_kind = {{"reseau", 121}, {"fiducial", 8}};
  r.reseau_rms_um = 0.1 + 0.2;  // not exactly representable in short decimal: must round-trip
  r.scale_x = 1.0000123456789;
  r.seconds = 12.25;
  r.finished_utc = "2026-11-21T08:00:00Z";
  r.outputs = {{"plate-07.measurements.csv", 4567, std::string(64, 'c')}};
  r.report_json = "plate-07.measure.json";
  return r;
}

TEST(ScanRecord, RoundTrip) {
  const ScanRecord r = SampleRecord();
  const ScanRecord back = ParseScanRecord(FormatScanRecord(r), "record");
  EXPECT_EQ(back.stem, r.stem);
  EXPECT_EQ(back.scan, r.scan);
  EXPECT_EQ(back.status, r.status);
  EXPECT_EQ(back.fingerprint, r.fingerprint);
  EXPECT_EQ(back.scan_size_bytes, r.scan_size_bytes);
  EXPECT_EQ(back.scan_mtime_ns, r.scan_mtime_ns);
  EXPECT_EQ(back.overrides, r.overrides);
  EXPECT_EQ(back.counts_by_status, r.counts_by_status);
  EXPECT_EQ(back.counts_by_kind, r.counts_by_kind);
  EXPECT_EQ(back.reseau_rms_um, r.reseau_rms_um);
  EXPECT_EQ(back.scale_x, r.scale_x);
  EXPECT_FALSE(back.scale_y.has_value());
  EXPECT_EQ(back.seconds, r.seconds);
  ASSERT_EQ(back.outputs.size(), 1u);
  EXPECT_EQ(back.outputs[0].name, r.outputs[0].name);
  EXPECT_EQ(back.outputs[0].size_bytes, r.outputs[0].size_bytes);
  EXPECT_EQ(back.outputs[0].sha256, r.outputs[0].sha256);
  EXPECT_EQ(back.report_json, r.report_json);
  EXPECT_EQ(FormatScanRecord(back), FormatScanRecord(r));
  EXPECT_NE(ErrorOf([] { ParseScanRecord("{\"format\": \"platemeter-batch-record\"}", "r"); }), "");
  EXPECT_NE(ErrorOf([] { ParseScanRecord("{\"format\": ", "r"); }), "");
  std::string bad_status = FormatScanRecord(r);
  bad_status.replace(bad_status.find("\"ok\""), 4, "\"done\"");
  EXPECT_NE(ErrorOf([&] { ParseScanRecord(bad_status, "r"); }), "");
}

TEST(ScanRecord, OutputsIntactNoticesChanges) {
  TempDir dir;
  WriteText(dir.path() / "a.csv", "id,x\n1,2\n");
  ScanRecord r = SampleRecord();
  r.outputs = {DescribeOutput(dir.path().string(), "a.csv")};
  EXPECT_EQ(r.outputs[0].size_bytes, 9u);
  EXPECT_EQ(r.outputs[0].sha256, Sha256Hex("id,x\n1,2\n"));
  std::string why;
  EXPECT_TRUE(OutputsIntact(r, dir.path().string(), &why)) << why;
  WriteText(dir.path() / "a.csv", "id,x\n1,3\n");  // same size, other bytes
  EXPECT_FALSE(OutputsIntact(r, dir.path().string(), &why));
  EXPECT_NE(why.find("changed"), std::string::npos);
  fs::remove(dir.path() / "a.csv");
  EXPECT_FALSE(OutputsIntact(r, dir.path().string(), &why));
  EXPECT_NE(why.find("missing"), std::string::npos);
}

TEST(Summary, BuiltFromEveryRecordInOut) {
  TempDir out;
  ScanRecord a = SampleRecord();
  ScanRecord b = SampleRecord();
  b.stem = "plate-02";
  b.status = "failed";
  b.reason = "plate-02.tif: only 3 crosses found, \"too few\"";
  b.counts_by_status.clear();
  b.reseau_rms_um.reset();
  b.scale_x.reset();
  b.outputs.clear();
  b.report_json.clear();
  fs::create_directories(out.path() / a.stem);
  WriteScanRecord(RecordPath(out.path().string(), a.stem), a);
  fs::create_directories(out.path() / b.stem);
  WriteScanRecord(RecordPath(out.path().string(), b.stem), b);
  fs::create_directories(out.path() / "plate-09");  // a scan still running: no record, not listed
  const SummaryFiles files = WriteBatchSummary(out.path().string());
  EXPECT_EQ(files.scans, 2);
  EXPECT_EQ(files.ok, 1);
  EXPECT_EQ(files.failed, 1);
  const std::string csv = ReadTextOfLibrary(files.csv_path);
  std::vector<std::string> lines;
  std::stringstream s(csv);
  for (std::string line; std::getline(s, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0].substr(0, 40), "stem,scan,status,reason,points_measured,");
  EXPECT_EQ(std::count(lines[0].begin(), lines[0].end(), ','), static_cast<long>(SummaryColumns().size() - 1));
  // Sorted by stem; the failure's reason quoted (comma, quotes); the numbers exact.
  EXPECT_EQ(lines[1].substr(0, 9), "plate-02,");
  EXPECT_NE(lines[1].find("\"plate-02.tif: only 3 crosses found, \"\"too few\"\"\""), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find(",118,2,1,121,8,0,0,0,0,0.30000000000000004,1.0000123456789,,12.250,"), std::string::npos)
      << lines[2];
  const std::string html = ReadTextOfLibrary(files.html_path);
  EXPECT_NE(html.find("href=\"plate-07/plate-07.measure.json\""), std::string::npos);
  EXPECT_NE(html.find("href=\"plate-07/plate-07.measurements.csv\""), std::string::npos);
  EXPECT_NE(html.find("only 3 crosses found, &quot;too few&quot;"), std::string::npos);
  EXPECT_NE(html.find("2 scans: 1 ok, 1 failed"), std::string::npos);
}

TEST(Temporaries, RecognisesEveryWritersTemporaryName) {
  TempDir dir;
  // The names core/atomic_file.h uses, seen while a write is in flight: make one and look.
  EXPECT_TRUE(IsTemporaryName(".p.measurements.partial.csv"));  // WriteFileAtomically(p.measurements.csv)
  EXPECT_TRUE(IsTemporaryName(".p.residuals.png.partial"));     // the residual plot
  EXPECT_TRUE(IsTemporaryName(".batch-summary.csv.partial.1234"));
  EXPECT_FALSE(IsTemporaryName("p.measurements.csv"));
  EXPECT_FALSE(IsTemporaryName("partial.csv"));
  WriteText(dir.path() / ".p.measurements.partial.csv", "half");
  WriteText(dir.path() / "p.measurements.csv", "whole");
  EXPECT_EQ(RemoveTemporaries(dir.path().string()), 1);
  EXPECT_TRUE(fs::exists(dir.path() / "p.measurements.csv"));
  WriteSharedFileAtomically(dir.file("s.csv"), "a,b\n");
  EXPECT_EQ(ReadTextOfLibrary(dir.path() / "s.csv"), "a,b\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 2);
}

// The run loop with a stand-in measurement that writes two outputs and counts its calls.
struct FakeMeasure {
  std::atomic<int> calls{0};
  std::set<std::string> failing;  // stems that throw
  ScanWorkResult operator()(const BatchItem& item, const std::string& folder) {
    ++calls;
    if (failing.count(item.input.stem)) throw Error(item.input.path, "too few crosses (3 of 121)");
    const std::string csv = (fs::path(folder) / (item.input.stem + ".measurements.csv")).string();
    const std::string json = (fs::path(folder) / (item.input.stem + ".measure.json")).string();
    WriteFileAtomically(csv, "id\n" + ReadTextOfLibrary(item.input.path) + "\n" + item.options_text);
    WriteFileAtomically(json, "{}\n");
    ScanWorkResult r;
    r.counts_by_status = {{"measured", 5}};
    r.reseau_rms_um = 0.25;
    r.written_files = {csv, json};
    r.report_json = json;
    return r;
  }
};

TEST(RunBatch, RecordsSkipsRedoesAndCleans) {
  TempDir in, out;
  std::vector<BatchItem> items;
  for (int i = 0; i < 6; ++i) {
    const std::string stem = "s" + std::to_string(i);
    WriteText(in.path() / (stem + ".tif"), "bytes of " + stem);
    items.push_back({{in.file(stem + ".tif"), stem, {}, 0}, "model = scales\n"});
  }
  items.push_back({{in.file("gone.tif"), "gone", {}, 0}, "model = scales\n"});  // unreadable
  FakeMeasure fake;
  fake.failing = {"s3"};
  const ScanWork work = [&](const BatchItem& item, const std::string& folder) { return fake(item, folder); };
  BatchOptions options;
  options.out_dir = out.path().string();
  options.jobs = 2;
  // A killed earlier run left a temporary and a stale output in s1's folder, and no record.
  WriteText(out.path() / "s1" / ".s1.measurements.partial.csv", "half");
  WriteText(out.path() / "s1" / "s1.old-plot.png", "from other options");

  BatchOutcome first = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(first.ok, 5);
  EXPECT_EQ(first.failed, 2);
  EXPECT_FALSE(first.AllOk());
  EXPECT_EQ(fake.calls.load(), 6);  // the unreadable scan never reaches the work
  ASSERT_EQ(first.failures.size(), 2u);
  EXPECT_NE(first.failures[0].find("s3: "), std::string::npos);
  EXPECT_NE(first.failures[0].find("too few crosses"), std::string::npos);
  EXPECT_NE(first.failures[1].find("cannot read the scan"), std::string::npos);
  EXPECT_FALSE(fs::exists(out.path() / "s1" / ".s1.measurements.partial.csv"));
  EXPECT_FALSE(fs::exists(out.path() / "s1" / "s1.old-plot.png"));
  const std::optional<ScanRecord> r0 = ReadScanRecord(RecordPath(options.out_dir, "s0"));
  ASSERT_TRUE(r0);
  EXPECT_EQ(r0->status, "ok");
  EXPECT_EQ(r0->scan_sha256, Sha256Hex("bytes of s0"));
  EXPECT_EQ(r0->fingerprint, ScanFingerprint(Sha256Hex("bytes of s0"), "model = scales\n"));
  EXPECT_EQ(r0->outputs.size(), 2u);
  EXPECT_EQ(r0->report_json, "s0.measure.json");
  const std::optional<ScanRecord> r3 = ReadScanRecord(RecordPath(options.out_dir, "s3"));
  ASSERT_TRUE(r3);
  EXPECT_EQ(r3->status, "failed");
  EXPECT_TRUE(r3->outputs.empty());

  // Rerun: everything current, nothing measured (the failed ones stay failed).
  BatchOutcome second = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(fake.calls.load(), 6);
  EXPECT_EQ(second.skipped_ok, 5);
  EXPECT_EQ(second.skipped_failed, 1);
  EXPECT_EQ(second.failed, 1);  // the unreadable scan has no fingerprint: tried again

  // A changed scan, a changed option and a tampered output are each redone; the rest skipped.
  WriteText(in.path() / "s0.tif", "new bytes of s0");
  items[1].options_text = "model = affine\n";
  WriteText(out.path() / "s2" / "s2.measure.json", "{ }\n");
  fake.failing.clear();
  BatchOutcome third = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(fake.calls.load(), 9);
  EXPECT_EQ(third.ok, 3);
  EXPECT_EQ(third.skipped_ok, 2);
  EXPECT_EQ(third.skipped_failed, 1);
  options.retry_failed = true;
  BatchOutcome fourth = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(fake.calls.load(), 10);  // s3 retried, now ok
  EXPECT_EQ(fourth.ok, 1);
  options.force = true;
  BatchOutcome fifth = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(fake.calls.load(), 16);
  EXPECT_EQ(fifth.ok, 6);
  EXPECT_EQ(fifth.failed, 1);
}

TEST(RunBatch, AScanLockedByAnotherProcessIsLeftToIt) {
  TempDir in, out;
  std::vector<BatchItem> items;
  for (int i = 0; i < 3; ++i) {
    const std::string stem = "s" + std::to_string(i);
    WriteText(in.path() / (stem + ".tif"), "bytes of " + stem);
    items.push_back({{in.file(stem + ".tif"), stem, {}, 0}, "model = scales\n"});
  }
  FakeMeasure fake;
  const ScanWork work = [&](const BatchItem& item, const std::string& folder) { return fake(item, folder); };
  BatchOptions options;
  options.out_dir = out.path().string();
  options.jobs = 2;
  // Another batch holds s1 (an flock on its lock file, as the run loop takes it).
  fs::create_directories(out.path() / "s1");
  const std::string lock_path = (out.path() / "s1" / ".s1.batch.lock").string();
  const int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const BatchOutcome held = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(held.ok, 2);
  EXPECT_EQ(held.busy, 1);
  EXPECT_FALSE(held.AllOk());
  EXPECT_EQ(fake.calls.load(), 2);
  EXPECT_FALSE(fs::exists(RecordPath(options.out_dir, "s1")));
  ::close(fd);  // the other process ends
  const BatchOutcome after = RunBatch(items, work, options, nullptr);
  EXPECT_EQ(after.ok, 1);
  EXPECT_EQ(after.skipped_ok, 2);
  EXPECT_TRUE(after.AllOk());
  EXPECT_FALSE(fs::exists(lock_path));  // removed once the scan is done
}

// Issue #28: a manifest saved with a byte order mark reads; fields that are
// not UTF-8 or hold control characters are refused with the line.
TEST(ScanList, ManifestWithAByteOrderMarkReads) {
  TempDir dir;
  WriteText(dir.path() / "m.csv", "\xEF\xBB\xBFscan,orientation\na.tif,90\n");
  const std::vector<ScanInput> scans = ReadScanManifest(dir.file("m.csv"), {"orientation"});
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].stem, "a");
  EXPECT_EQ(scans[0].overrides, (std::vector<std::pair<std::string, std::string>>{{"orientation", "90"}}));
}

TEST(ScanList, ManifestFieldsMustBeUtf8WithoutControlCharacters) {
  TempDir dir;
  auto error = [&](const std::string& text) {
    WriteText(dir.path() / "m.csv", text);
    return ErrorOf([&] { ReadScanManifest(dir.file("m.csv"), {"orientation"}); });
  };
  EXPECT_EQ(error("scan,orientation\np\xff.tif,90\n"),
            dir.file("m.csv") + ": line 2: column 'scan' byte 0xff at position 2 is not valid UTF-8");
  EXPECT_EQ(error("scan,orientation\n\"a\nb.tif\",90\n"),
            dir.file("m.csv") + ": line 2: column 'scan' contains the control character 0x0a at position 2");
}

}  // namespace
}  // namespace platemeter
