#pragma once
// The randomized-mutation driver (docs/fuzzing.md): runs one reader on mutated
// seed inputs for a bounded time. platemeter::Error is the expected rejection;
// any other exception is a finding, saved with its input. A crash (SIGSEGV,
// SIGABRT, SIGFPE, SIGBUS) or a hang (an input taking longer than the
// per-input limit) saves the input first, then ends the process.
#include <cstdint>
#include <string>
#include <vector>

namespace platemeter::fuzz {

struct FuzzTarget {
  std::string name;                       // "measurement_file", used for the corpus folder and crash files
  void (*run)(const std::string& bytes);  // throws Error on bad input
  bool binary = false;                    // true: TIFF mutations, else text mutations
  // Each input in a forked child: for readers with process-wide state (the
  // image cache), which one bad input may leave broken for the next.
  bool isolate = false;
};

struct FuzzOptions {
  double seconds = 6.0;           // s; time budget of one reader
  uint64_t seed = 1;              // the mutation sequence
  double input_limit_s = 20.0;    // s; an input running longer is a hang
  std::string crash_dir = ".";    // where findings' inputs are written
  size_t max_inputs = 0;          // 0 = until the time is up
};

struct FuzzReport {
  long inputs = 0;     // inputs tried, seeds included
  long accepted = 0;   // read without an error
  long rejected = 0;   // platemeter::Error
  std::vector<std::string> findings;  // "what happened (input saved as FILE)"
};

// How one input ended.
struct RunOutcome {
  enum Kind { kAccepted, kRejected, kFinding } kind = kAccepted;
  std::string what;  // kFinding: what happened
};

// Runs one input in this process (a crash ends it; RunFuzz runs isolated
// targets through a ForkServer instead, fork_server.h).
RunOutcome RunOne(const FuzzTarget& target, const std::string& input, double input_limit_s);

// The options from the environment: PLATEMETER_FUZZ_SECONDS (per reader),
// PLATEMETER_FUZZ_SEED, PLATEMETER_FUZZ_CRASH_DIR; `default_seconds` otherwise.
FuzzOptions OptionsFromEnvironment(double default_seconds);

// Runs every seed once, then mutations of them (and of accepted mutants).
FuzzReport RunFuzz(const FuzzTarget& target, const std::vector<std::string>& seeds, const FuzzOptions& options);

}  // namespace platemeter::fuzz
