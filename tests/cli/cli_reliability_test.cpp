// Issue #28's reliability cases for `measure`: a scan's outputs are one set (an
// interrupt at any moment leaves the old set or the new one), and options and the
// output folder are checked before any work, each with its one-line reason.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "batch/batch_fixture.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::ReadTextFile;
using testing::RunPlatemeter;
using testing::RunShell;
using testing::TempDir;

// One small rendered reseau scan (the batch tests' 5 x 5 camera, 80 um pixels), made once per process.
struct SmallPlate {
  TempDir dir;
  std::string defs, scan;
};

const SmallPlate& Plate() {
  static const SmallPlate* plate = [] {
    auto* p = new SmallPlate;
    p->defs = p->dir.file("batchtest.toml");
    std::ofstream(p->defs) << batch_test::kDefinitions;
    const DefinitionRegistry registry = DefinitionRegistry::Load({p->defs});
    p->scan = p->dir.file("plate.tif");
    batch_test::Render("batchtest", 4242, registry, p->dir.path() / "render", p->scan);
    return p;
  }();
  return *plate;
}

std::vector<std::string> MeasureArgv(const fs::path& out) {
  return {PLATEMETER_BIN, "--definitions", Plate().defs, "measure", Plate().scan, "--camera", "batchtest",
          "--orientation", "0", "-o", out.string()};
}

std::string MeasureArgs(const fs::path& out, const std::string& extra) {
  // The output folder in double quotes: a shell variable in it ("$d/out") is expanded.
  return "--definitions '" + Plate().defs + "' measure '" + Plate().scan + "' --camera batchtest --orientation 0 -o \"" +
         out.string() + "\" " + extra;
}

// Every entry of `dir` (hidden ones too): name -> contents ("<folder>" for a folder).
std::map<std::string, std::string> Entries(const fs::path& dir) {
  std::map<std::string, std::string> entries;
  for (const auto& e : fs::directory_iterator(dir)) {
    entries[e.path().filename().string()] = e.is_directory() ? "<folder>" : ReadTextFile(e.path().string());
  }
  return entries;
}

// Starts argv with stdout and stderr to /dev/null.
pid_t Spawn(const std::vector<std::string>& argv) {
  const pid_t child = fork();
  if (child == 0) {
    freopen("/dev/null", "w", stdout);
    freopen("/dev/null", "w", stderr);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::_Exit(127);
  }
  return child;
}

// Returns when a file appears in a staging folder (".output.partial-*") of `out`, or the child ends.
void WaitForAStagedFile(const fs::path& out, pid_t child) {
  for (;;) {
    std::error_code ec;
    for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().filename().string().rfind(".output.partial-", 0) != 0) continue;
      std::error_code e;
      if (fs::directory_iterator(it->path(), e) != fs::directory_iterator()) return;
    }
    siginfo_t info{};
    if (waitid(P_PID, child, &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid != 0) return;  // ended
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

TEST(CliReliability, MeasureInterruptedAtAnyMomentLeavesTheOldSetOrTheNewOne) {
  TempDir tmp;
  // The new set, and an earlier run's set of the same names with other contents.
  const fs::path new_ref = tmp.path() / "new", old_ref = tmp.path() / "old";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(RunPlatemeter(MeasureArgs(new_ref, "")).exit_code, 0);
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::map<std::string, std::string> new_set = Entries(new_ref);
  ASSERT_EQ(new_set.size(), 4u);
  fs::create_directories(old_ref);
  for (const auto& [name, contents] : new_set) std::ofstream(old_ref / name) << "an earlier run's " << name << "\n";
  const std::map<std::string, std::string> old_set = Entries(old_ref);

  // 6 interrupts spread over the whole run (detection, fits), then 16 aimed at the writing of the files:
  // k * 6 ms after the first file appears in the staging folder (the plot is drawn, the files written, renamed).
  struct Aim {
    double delay_s;
    bool after_first_file;
  };
  std::vector<Aim> aims;
  for (int k = 0; k < 6; ++k) aims.push_back({run_s * k / 6.0, false});
  for (int k = 0; k < 16; ++k) aims.push_back({0.006 * k, true});
  const int signals[] = {SIGINT, SIGTERM, SIGHUP};
  int old_left = 0, new_left = 0;
  for (size_t k = 0; k < aims.size(); ++k) {
    const fs::path out = tmp.path() / ("run-" + std::to_string(k));
    fs::copy(old_ref, out);
    const pid_t child = Spawn(MeasureArgv(out));
    if (aims[k].after_first_file) WaitForAStagedFile(out, child);
    std::this_thread::sleep_for(std::chrono::duration<double>(aims[k].delay_s));
    kill(child, signals[k % 3]);
    int status = 0;
    waitpid(child, &status, 0);
    const std::map<std::string, std::string> left = Entries(out);
    SCOPED_TRACE("delay " + std::to_string(aims[k].delay_s) + " s" + (aims[k].after_first_file ? " after the first file" : "") +
                 ", signal " + std::to_string(signals[k % 3]));
    if (left == old_set) {
      ++old_left;
      EXPECT_TRUE(WIFSIGNALED(status)) << "the run finished but left the old set";
    } else {
      std::string names;
      for (const auto& [name, contents] : left) {
        const auto it = new_set.find(name);
        names += " " + name + (it == new_set.end() ? " (not in the set)" : it->second == contents ? " (new)" : " (old)");
      }
      EXPECT_TRUE(left == new_set) << "neither the old set nor the new one:" << names;
      ++new_left;
    }
  }
  // The sweep reached both sides of the commit.
  EXPECT_GT(old_left, 0);
  EXPECT_GT(new_left, 0);
  std::printf("interrupt sweep: %zu runs, %d left the old set, %d the new one (run %.2f s)\n", aims.size(),
              old_left, new_left, run_s);
}

// Runs measure into a folder holding an earlier run's set; the command must fail with `reason` before
// detecting anything, and leave that set as it was.
void ExpectRefusedBeforeAnyWork(const std::string& extra, const std::string& reason) {
  SCOPED_TRACE(extra);
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  ASSERT_EQ(RunPlatemeter(MeasureArgs(out, "")).exit_code, 0);
  const std::map<std::string, std::string> before = Entries(out);
  const CommandResult r = RunPlatemeter(MeasureArgs(out, extra));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "") << "work was done before the refusal";
  EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(Entries(out), before);
}

TEST(CliReliability, OptionsAreCheckedBeforeAnyWork) {
  ExpectRefusedBeforeAnyWork("--tolerance-um 0", "--tolerance-um: 0 is outside the accepted range (0, 1e+06]");
  ExpectRefusedBeforeAnyWork("--rejection-threshold 1", "--rejection-threshold: 1 is outside the accepted range (1, 1e+06]");
  ExpectRefusedBeforeAnyWork("--emulsion-depth-um 1e200", "--emulsion-depth-um: 1e+200 is outside the accepted range [0, 1000]");
  ExpectRefusedBeforeAnyWork("--trail-dashes 2 3 7 --trails-start-utc 1972-05-12T05:30:00Z",
                             "--trail-dashes: an invalid trail program: 7 leading dashes; Table 1 allows 2, 3, 4 or 5");
  ExpectRefusedBeforeAnyWork("--second-scan '" + Plate().scan + "'",
                             "is the scan itself; give the plate's second scan (turned 180 deg)");
}

TEST(CliReliability, AnOutputFolderThatCannotTakeTheSetFailsAtOnceWithTheReason) {
  TempDir tmp;
  std::ofstream(tmp.file("a-file")) << "not a folder\n";
  CommandResult r = RunPlatemeter(MeasureArgs(tmp.path() / "a-file", ""));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a-file: the output folder is a file, not a folder"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");

  // 245 characters + ".measurements.csv" is longer than a file name may be.
  const fs::path long_scan = tmp.path() / (std::string(245, 'a') + ".tif");
  fs::create_symlink(Plate().scan, long_scan);
  r = RunPlatemeter("--definitions '" + Plate().defs + "' measure '" + long_scan.string() +
                    "' --camera batchtest --orientation 0 -o '" + tmp.file("out") + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("file name too long: 262 characters, the file system allows 255 (give the scan a shorter name)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
}

TEST(CliReliability, AReadOnlyOutputFolderNamesTheOsReason) {
  if (!testing::PrivateMountsAvailable()) GTEST_SKIP() << "no private mount namespace (unshare -rm) on this machine";
  // A read-only file system: root cannot write it either. The earlier set stays.
  const CommandResult r = RunShell("d=$(mktemp -d) && mount -t tmpfs tmpfs \"$d\" || exit 9\n"
                                   "\"$PLATEMETER\" " + MeasureArgs("$d/out", "") + " >/dev/null || exit 9\n"
                                   "mount -o remount,ro \"$d\" || exit 9\n"
                                   "\"$PLATEMETER\" " + MeasureArgs("$d/out", "--model affine") + "\n"
                                   "echo \"exit $?\"\n"
                                   "ls -A \"$d/out\"\n",
                                   /*private_mounts=*/true);
  EXPECT_NE(r.err.find("cannot write into the output folder (Read-only file system)"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("exit 1\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("plate.measurements.csv"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find(".output.partial"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace platemeter
