// OutputSet (core/output_set.h): a run's files land as one set or not at all.
#include "platemeter/core/output_set.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "platemeter/core/atomic_file.h"
#include "platemeter/core/error.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

namespace fs = std::filesystem;
using testing::ReadTextFile;
using testing::TempDir;

std::set<std::string> Entries(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

void WriteOldSet(const fs::path& dir) {
  fs::create_directories(dir);
  for (const char* name : {"a.csv", "a.json", "a.png"}) WriteFileAtomically((dir / name).string(), "old\n");
}

TEST(OutputSet, CommitReplacesTheWholeSetAndRemovesMembersNotWritten) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "out";
  WriteOldSet(dir);
  std::ofstream(dir / "notes.txt") << "the user's own file\n";
  {
    OutputSet set(dir.string(), {"a.csv", "a.json", "a.png"});
    WriteFileAtomically(set.Stage("a.csv"), "new\n");
    WriteFileAtomically(set.Stage("a.json"), "new\n");
    // Before the commit the folder still holds the old set (and the staging folder).
    EXPECT_EQ(ReadTextFile((dir / "a.csv").string()), "old\n");
    set.Commit();
  }
  EXPECT_EQ(ReadTextFile((dir / "a.csv").string()), "new\n");
  EXPECT_EQ(ReadTextFile((dir / "a.json").string()), "new\n");
  // a.png belongs to the old set only: it does not stay beside the new one. The user's file does.
  EXPECT_EQ(Entries(dir), (std::set<std::string>{"a.csv", "a.json", "notes.txt"}));
}

TEST(OutputSet, ASetNeverCommittedLeavesTheOldSetUntouched) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "out";
  WriteOldSet(dir);
  try {
    OutputSet set(dir.string(), {"a.csv", "a.json", "a.png"});
    WriteFileAtomically(set.Stage("a.csv"), "new\n");
    throw Error("test", "a failure half way through the outputs");
  } catch (const Error&) {
  }
  EXPECT_EQ(Entries(dir), (std::set<std::string>{"a.csv", "a.json", "a.png"}));
  EXPECT_EQ(ReadTextFile((dir / "a.csv").string()), "old\n");
}

TEST(OutputSet, RefusesAFolderThatCannotTakeTheSetBeforeAnyWork) {
  TempDir tmp;
  std::ofstream(tmp.path() / "file") << "x";
  try {
    OutputSet set((tmp.path() / "file").string(), {"a.csv"});
    FAIL() << "a file accepted as the output folder";
  } catch (const EnvironmentError& e) {
    EXPECT_EQ(e.reason(), "the output folder is a file, not a folder");
  }
  const std::string long_name(250, 'a');
  try {
    OutputSet set((tmp.path() / "out").string(), {long_name + ".measurements.csv"});
    FAIL() << "a 267-character file name accepted";
  } catch (const EnvironmentError&) {
    FAIL() << "a name too long is the input's defect, not the machine's";
  } catch (const Error& e) {
    EXPECT_EQ(e.reason(), "file name too long: 267 characters, the file system allows 255 (give the scan a shorter name)");
  }
}

TEST(OutputSet, AbandonedStagingOfADeadProcessIsRemovedALiveOneIsKept) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "out";
  fs::create_directories(dir);
  // A child that dies (as under kill -9) with its set staged.
  const pid_t child = fork();
  if (child == 0) {
    OutputSet set(dir.string(), {"a.csv"});
    WriteFileAtomically(set.Stage("a.csv"), "never committed\n");
    std::_Exit(0);  // no destructor: the staging folder stays, as after kill -9
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_EQ(Entries(dir).size(), 1u);
  ASSERT_EQ(Entries(dir).begin()->rfind(".output.partial-" + std::to_string(child) + "-", 0), 0u);
  OutputSet mine(dir.string(), {"a.csv"});  // runs RemoveAbandonedStaging first
  const std::set<std::string> left = Entries(dir);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left.begin()->rfind(".output.partial-" + std::to_string(::getpid()) + "-", 0), 0u);
  EXPECT_EQ(RemoveAbandonedStaging(dir.string()), 0);  // this process's own set is in progress
}

}  // namespace
}  // namespace platemeter
