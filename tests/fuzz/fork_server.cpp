// The fork server of the fuzz harness (fork_server.h).
#include "fuzz/fork_server.h"

#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <stdexcept>

namespace platemeter::fuzz {
namespace {

bool WriteAll(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

bool ReadAll(int fd, void* data, size_t size) {
  char* p = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// The child: [size][bytes] in, [kind][size][what] out, until its input closes.
[[noreturn]] void ServeInputs(const FuzzTarget& target, int in, int out) {
  for (int s : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL, SIGALRM}) ::signal(s, SIG_DFL);
  for (;;) {
    uint64_t size = 0;
    if (!ReadAll(in, &size, sizeof size)) ::_exit(0);
    std::string input(size, '\0');
    if (!ReadAll(in, input.data(), size)) ::_exit(0);
    const RunOutcome outcome = RunOne({target.name, target.run, target.binary, false}, input, 1e6);
    const uint8_t kind = static_cast<uint8_t>(outcome.kind);
    const uint32_t length = static_cast<uint32_t>(outcome.what.size());
    if (!WriteAll(out, &kind, 1) || !WriteAll(out, &length, 4) || !WriteAll(out, outcome.what.data(), length)) {
      ::_exit(0);
    }
  }
}

}  // namespace

void ForkServer::Start() {
  int down[2], up[2];
  if (::pipe(down) != 0 || ::pipe(up) != 0) throw std::runtime_error("fuzz: pipe() failed");
  ::signal(SIGPIPE, SIG_IGN);  // a dead child shows as a failed write, not a signal
  child_ = ::fork();
  if (child_ < 0) throw std::runtime_error("fuzz: fork() failed");
  if (child_ == 0) {
    ::close(down[1]);
    ::close(up[0]);
    ServeInputs(target_, down[0], up[1]);
  }
  ::close(down[0]);
  ::close(up[1]);
  to_child_ = down[1];
  from_child_ = up[0];
}

void ForkServer::Stop() {
  if (child_ <= 0) return;
  ::close(to_child_);
  ::close(from_child_);
  ::kill(child_, SIGKILL);
  ::waitpid(child_, nullptr, 0);
  child_ = -1;
}

RunOutcome ForkServer::ChildDied(const std::string& fallback) {
  ::close(to_child_);
  ::close(from_child_);
  int status = 0;
  ::waitpid(child_, &status, 0);
  child_ = -1;
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    return {RunOutcome::kFinding, "crash (signal " + std::to_string(s) + ", " + strsignal(s) + ")"};
  }
  return {RunOutcome::kFinding, fallback};
}

RunOutcome ForkServer::Run(const std::string& input, double input_limit_s) {
  if (child_ <= 0) Start();
  const uint64_t size = input.size();
  if (!WriteAll(to_child_, &size, sizeof size) || !WriteAll(to_child_, input.data(), input.size())) {
    return ChildDied("the child stopped reading");
  }
  pollfd ready{from_child_, POLLIN, 0};
  if (::poll(&ready, 1, static_cast<int>(input_limit_s * 1000)) == 0) {
    Stop();
    return {RunOutcome::kFinding, "hang (input time limit)"};
  }
  uint8_t kind = 0;
  uint32_t length = 0;
  if (!ReadAll(from_child_, &kind, 1) || !ReadAll(from_child_, &length, 4)) return ChildDied("the child exited");
  std::string what(length, '\0');
  if (!ReadAll(from_child_, what.data(), length)) return ChildDied("the child exited");
  const RunOutcome outcome{static_cast<RunOutcome::Kind>(kind), what};
  if (outcome.kind == RunOutcome::kFinding) Stop();  // its state may be broken: a fresh child next
  return outcome;
}

}  // namespace platemeter::fuzz
