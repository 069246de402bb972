// Issue #28: batch failures are classified. A scan that failed because the machine
// failed (a full disk) is retried by a plain rerun once space is free; a scan that
// failed for its own defect (a truncated TIFF) is remembered and skipped.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "batch/batch_fixture.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using batch_test::GetFixture;
using testing::CommandResult;
using testing::RunShell;
using testing::TempDir;

int Occurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(BatchEnvironment, ADiskFullFailureHealsOnAPlainRerunATruncatedScanStaysFailed) {
  if (!testing::PrivateMountsAvailable()) GTEST_SKIP() << "no private mount namespace (unshare -rm) on this machine";
  TempDir tmp;
  const std::filesystem::path in = tmp.path() / "in";
  std::filesystem::create_directories(in);
  for (int i : {0, 1, 2, batch_test::kTruncated}) {
    std::filesystem::create_symlink(GetFixture().Scan(i), in / (GetFixture().names[i] + ".tif"));
  }
  const std::string batch = "\"$PLATEMETER\" --definitions '" + GetFixture().defs + "' batch '" + in.string() +
                            "' -o \"$d/out\" --camera batchtest --orientation 0 --jobs 2 2>&1 | grep -v '^batch: \\['";
  // A 1 MB file system with 24 kB free: the records (2 kB) fit, a scan's outputs (35 kB) do not.
  const CommandResult r = RunShell("d=$(mktemp -d) && mount -t tmpfs -o size=1m tmpfs \"$d\" || exit 9\n"
                                   "dd if=/dev/zero of=\"$d/filler\" bs=1k count=1000 2>/dev/null\n" +
                                   batch + "\necho '== failure kinds'\n"
                                   "cat \"$d\"/out/*/*.batch.json | grep '\"failure\"'\n"
                                   "rm \"$d/filler\"\necho '== rerun'\n" + batch + "\n",
                                   /*private_mounts=*/true);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const size_t kinds = r.out.find("== failure kinds"), rerun = r.out.find("== rerun");
  ASSERT_NE(rerun, std::string::npos) << r.out;
  const std::string first = r.out.substr(0, kinds), recorded = r.out.substr(kinds, rerun - kinds),
                    second = r.out.substr(rerun);
  EXPECT_NE(first.find("4 scans: 0 measured, 0 already current, 4 failed"), std::string::npos) << first;
  EXPECT_NE(first.find("write failed (No space left on device)"), std::string::npos) << first;
  // The message names the file that could not be written, not the staging folder's copy.
  EXPECT_EQ(first.find(".output.partial"), std::string::npos) << first;
  EXPECT_EQ(Occurrences(recorded, "\"failure\": \"environment\""), 3) << recorded;
  EXPECT_EQ(Occurrences(recorded, "\"failure\": \"input\""), 1) << recorded;
  EXPECT_NE(second.find("4 scans: 3 measured, 0 already current, 1 failed (1 of them earlier; --retry-failed redoes them)"),
            std::string::npos)
      << second;
  EXPECT_NE(second.find("plate-07: "), std::string::npos) << second;
  EXPECT_NE(second.find("the file is truncated"), std::string::npos) << second;
}

// A scan whose name is too long for its outputs' names (245 characters + ".measurements.csv") fails with the
// reason and is still recorded and listed (its folder gets a shortened name), instead of vanishing.
TEST(BatchEnvironment, AScanNameTooLongForItsOutputsIsListedAsFailed) {
  TempDir tmp;
  const std::filesystem::path in = tmp.path() / "in";
  std::filesystem::create_directories(in);
  const std::string long_stem(245, 'a');
  std::filesystem::create_symlink(GetFixture().Scan(0), in / (long_stem + ".tif"));
  std::filesystem::create_symlink(GetFixture().Scan(1), in / "short.tif");
  const testing::CommandResult r = testing::RunPlatemeter(
      "--definitions '" + GetFixture().defs + "' batch '" + in.string() + "' -o '" + tmp.file("out") +
      "' --camera batchtest --orientation 0 --jobs 2");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("2 scans: 1 measured, 0 already current, 1 failed"), std::string::npos) << r.out;
  const std::string csv = testing::ReadTextFile(tmp.file("out/batch-summary.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << csv;  // header + 2 rows
  EXPECT_NE(csv.find("\n" + long_stem + ","), std::string::npos) << csv;  // its row, under its own stem
  EXPECT_NE(csv.find(",failed,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("file name too long: 262 characters, the file system allows 255"), std::string::npos) << csv;
  EXPECT_NE(testing::ReadTextFile(tmp.file("out/index.html")).find("file name too long"), std::string::npos);
}

}  // namespace
}  // namespace platemeter
