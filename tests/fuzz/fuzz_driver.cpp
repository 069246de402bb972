// The mutation driver (fuzz_driver.h).
#include "fuzz/fuzz_driver.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string.h>
#include <fstream>
#include <memory>
#include <vector>

#include "fuzz/fork_server.h"
#include "fuzz/mutator.h"
#include "platemeter/core/error.h"

namespace platemeter::fuzz {
namespace {

// The input being run, for the signal handlers (async-signal-safe writes only).
const std::string* g_current = nullptr;
char g_crash_path[4096];

void SaveCurrentFromSignal(const char* what) {
  if (g_current) {
    const int fd = ::open(g_crash_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ssize_t ignored = ::write(fd, g_current->data(), g_current->size());
      (void)ignored;
      ::close(fd);
    }
  }
  const char* parts[] = {"\nfuzz: ", what, " -- input saved as ", g_crash_path, "\n"};
  for (const char* part : parts) {
    ssize_t ignored = ::write(2, part, std::strlen(part));
    (void)ignored;
  }
}

void OnCrash(int signal_number) {
  SaveCurrentFromSignal(!g_current                  ? "crash in the harness itself (not while a reader ran)"
                        : signal_number == SIGALRM ? "hang (input time limit)"
                                                   : "crash (fatal signal)");
  ::signal(signal_number == SIGALRM ? SIGABRT : signal_number, SIG_DFL);
  ::raise(signal_number == SIGALRM ? SIGABRT : signal_number);
}

void InstallHandlers(const FuzzTarget& target, const FuzzOptions& options) {
  const std::string path = options.crash_dir + "/fuzz-crash-" + target.name + "-" + std::to_string(::getpid());
  std::strncpy(g_crash_path, path.c_str(), sizeof g_crash_path - 1);
  // Its own stack, so that a stack overflow (deep recursion) is reported too.
  static std::vector<char> alternate_stack(1 << 16);
  stack_t stack{};
  stack.ss_sp = alternate_stack.data();
  stack.ss_size = alternate_stack.size();
  ::sigaltstack(&stack, nullptr);
  struct sigaction action{};
  action.sa_handler = OnCrash;
  action.sa_flags = SA_ONSTACK;
  for (int s : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL, SIGALRM}) ::sigaction(s, &action, nullptr);
}

void RemoveHandlers() {
  for (int s : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL, SIGALRM}) ::signal(s, SIG_DFL);
  g_current = nullptr;
}

std::string SaveFinding(const FuzzTarget& target, const FuzzOptions& options, long index, const std::string& input) {
  const std::string path = options.crash_dir + "/fuzz-finding-" + target.name + "-" + std::to_string(index);
  std::ofstream(path, std::ios::binary) << input;
  return path;
}

double EnvironmentNumber(const char* name, double fallback) {
  const char* text = std::getenv(name);
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  return end && *end == '\0' && value >= 0 ? value : fallback;
}

RunOutcome RunHere(const FuzzTarget& target, const std::string& input) {
  try {
    target.run(input);
    return {RunOutcome::kAccepted, ""};
  } catch (const Error&) {
    return {RunOutcome::kRejected, ""};
  } catch (const std::exception& e) {
    return {RunOutcome::kFinding, std::string("an exception other than platemeter::Error: ") + e.what()};
  } catch (...) {
    return {RunOutcome::kFinding, "a non-std exception"};
  }
}

}  // namespace

RunOutcome RunOne(const FuzzTarget& target, const std::string& input, double input_limit_s) {
  ::alarm(static_cast<unsigned>(input_limit_s + 0.999));
  const RunOutcome outcome = RunHere(target, input);
  ::alarm(0);
  return outcome;
}

FuzzOptions OptionsFromEnvironment(double default_seconds) {
  FuzzOptions options;
  options.seconds = EnvironmentNumber("PLATEMETER_FUZZ_SECONDS", default_seconds);
  options.seed = static_cast<uint64_t>(EnvironmentNumber("PLATEMETER_FUZZ_SEED", 1));
  if (const char* dir = std::getenv("PLATEMETER_FUZZ_CRASH_DIR"); dir && *dir) options.crash_dir = dir;
  return options;
}

FuzzReport RunFuzz(const FuzzTarget& target, const std::vector<std::string>& seeds, const FuzzOptions& options) {
  FuzzReport report;
  Mutator mutator(options.seed);
  std::vector<std::string> pool = seeds;  // seeds, then accepted mutants (they reach deeper code)
  constexpr size_t kMaxPool = 512;
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_s = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  InstallHandlers(target, options);
  std::unique_ptr<ForkServer> server = target.isolate ? std::make_unique<ForkServer>(target) : nullptr;
  for (long index = 0;; ++index) {
    const bool seed_round = index < static_cast<long>(seeds.size());
    if (!seed_round && (elapsed_s() >= options.seconds ||
                        (options.max_inputs > 0 && report.inputs >= static_cast<long>(options.max_inputs)))) {
      break;
    }
    g_current = nullptr;  // a crash while mutating is the harness's, not a reader's
    const std::string input = seed_round ? seeds[index]
                              : target.binary ? mutator.MutateTiff(pool[mutator.Below(pool.size())])
                                              : mutator.MutateText(pool[mutator.Below(pool.size())], pool);
    g_current = &input;
    ++report.inputs;
    const RunOutcome outcome = server ? server->Run(input, options.input_limit_s)
                                      : RunOne(target, input, options.input_limit_s);
    switch (outcome.kind) {
      case RunOutcome::kAccepted:
        ++report.accepted;
        if (!seed_round && pool.size() < kMaxPool) pool.push_back(input);
        break;
      case RunOutcome::kRejected:
        ++report.rejected;
        break;
      case RunOutcome::kFinding:
        report.findings.push_back(outcome.what + " (input saved as " + SaveFinding(target, options, index, input) + ")");
    }
  }
  RemoveHandlers();
  return report;
}

}  // namespace platemeter::fuzz
