#pragma once
// A run's output files written as one set (DESIGN.md error policy: nothing already
// written is lost or half-written). Every file is written into a staging folder
// beside its target (".<tag>.partial-<pid>-<n>", which batch and git ignore), and all
// are renamed into place by Commit() with interrupts held back, so the output folder
// holds the earlier run's set or the new one, never a mix. A set never committed
// (an error, an exception) leaves the folder as it was; an interrupt before the
// commit removes the staging folder too, when the command installed
// InstallOutputSetInterruptCleanup().
#include <filesystem>
#include <string>
#include <vector>

#include "platemeter/core/error.h"

namespace platemeter {

class OutputSet {
 public:
  // Creates `dir` and the staging folder in it. `member_names`: every file name a set
  // of this kind may hold (not paths); the ones a run does not write are removed by
  // its commit, so an earlier run's plot does not stay beside a new set without one.
  // Throws Error with the OS's reason when the folder cannot be created or written
  // (a file in the way, no permission) and when a member's name is longer than the
  // file system allows.
  OutputSet(const std::string& dir, const std::vector<std::string>& member_names);
  ~OutputSet();  // not committed: the staging folder and all in it are removed, and the folders it created
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // The path to write member `name` to (in the staging folder).
  std::string Stage(const std::string& name);
  // Calls write(Stage(name)); an Error it throws names the member's final path, not the staging path.
  template <class Writer>
  void Write(const std::string& name, Writer write) {
    const std::string staged = Stage(name);
    try {
      write(staged);
    } catch (const EnvironmentError& e) {
      throw EnvironmentError(FinalPath(name), e.reason());
    } catch (const Error& e) {
      throw Error(FinalPath(name), e.reason());
    }
  }
  // Where member `name` lands at the commit.
  std::string FinalPath(const std::string& name) const;
  // Renames every staged file into place (interrupts held back until all are in),
  // removes the members not staged, and the staging folder. Throws Error naming the
  // file when a staged member was not written.
  void Commit();

 private:
  std::string dir_, staging_;
  std::vector<std::string> members_, staged_;
  std::vector<std::filesystem::path> created_;  // folders this set created, deepest first
  int cleanup_slot_ = -1;
  bool committed_ = false;
};

// Staging folders of sets whose process no longer runs (killed with -9, a power
// cut) in `dir`; returns how many were removed. Safe beside running processes.
int RemoveAbandonedStaging(const std::string& dir);

// For single-scan commands: SIGINT, SIGTERM and SIGHUP remove every open set's
// staging folder, then end the process as the signal would have. Not for batch,
// which handles its own interrupts (running scans finish their sets).
void InstallOutputSetInterruptCleanup();

}  // namespace platemeter
