#include "platemeter/batch/interrupt.h"

#include <unistd.h>

#include <atomic>
#include <csignal>

namespace platemeter {
namespace {

std::atomic<int> g_count{0};
std::atomic<int> g_signal{0};

// Async-signal-safe: counts and writes one fixed line.
extern "C" void OnInterrupt(int signal) {
  int expected = 0;
  g_signal.compare_exchange_strong(expected, signal);
  if (g_count.fetch_add(1) == 0) {
    static const char kMessage[] =
        "\nbatch: interrupted: no new scans; the running ones finish (interrupt again to abandon them)\n";
    [[maybe_unused]] ssize_t n = ::write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
  }
}

}  // namespace

void InstallBatchInterruptHandlers() {
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int BatchInterruptCount() { return g_count.load(); }
int BatchInterruptSignal() { return g_signal.load(); }

}  // namespace platemeter
