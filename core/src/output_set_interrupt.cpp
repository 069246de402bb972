// The interrupt clean-up of open output sets (output_set.h). The handler may run
// at any moment on any thread, so it only reads fixed-size slots and uses
// async-signal-safe calls (open, getdents64, unlinkat, rmdir, raise).
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <climits>
#include <cstring>

#include "output_set_interrupt.h"
#include "platemeter/core/output_set.h"

namespace platemeter {
namespace {

enum SlotState : int { kFree = 0, kBusy = 1, kReady = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};

std::array<Slot, 256> g_slots;
std::atomic<int> g_committing{0};
std::atomic<int> g_pending_signal{0};

struct LinuxDirent64 {
  ino64_t d_ino;
  off64_t d_off;
  unsigned short d_reclen;
  unsigned char d_type;
  char d_name[];
};

// Removes what `dir_fd` holds (files, and sub-folders `depth` levels down: plots/), closing it.
void RemoveContents(int dir_fd, int depth) {
  alignas(LinuxDirent64) char buffer[4096];
  for (;;) {
    const long n = ::syscall(SYS_getdents64, dir_fd, buffer, sizeof buffer);
    if (n <= 0) break;
    for (long offset = 0; offset < n;) {
      const auto* entry = reinterpret_cast<const LinuxDirent64*>(buffer + offset);
      offset += entry->d_reclen;
      if (std::strcmp(entry->d_name, ".") == 0 || std::strcmp(entry->d_name, "..") == 0) continue;
      if (entry->d_type == DT_DIR && depth > 0) {
        const int sub = ::openat(dir_fd, entry->d_name, O_RDONLY | O_DIRECTORY);
        if (sub >= 0) RemoveContents(sub, depth - 1);
        ::unlinkat(dir_fd, entry->d_name, AT_REMOVEDIR);
      } else {
        ::unlinkat(dir_fd, entry->d_name, 0);
      }
    }
  }
  ::close(dir_fd);
}

void RemoveStagingFolder(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  RemoveContents(fd, 2);
  ::rmdir(path);
}

void RemoveOpenStagingFolders() {
  for (Slot& slot : g_slots) {
    if (slot.state.load() == kReady) RemoveStagingFolder(slot.path);
  }
}

void EndAsSignalWould(int signal) {
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

extern "C" void OnInterruptRemoveStaging(int signal) {
  if (g_committing.load() > 0) {
    g_pending_signal.store(signal);  // the set being renamed into place completes first
    return;
  }
  RemoveOpenStagingFolders();
  EndAsSignalWould(signal);
}

}  // namespace

namespace internal {

int RegisterStaging(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < static_cast<int>(g_slots.size()); ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kBusy)) continue;
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(kReady);
    return i;
  }
  return -1;
}

void UnregisterStaging(int slot) {
  if (slot >= 0) g_slots[slot].state.store(kFree);
}

void BeginCommit() { g_committing.fetch_add(1); }

void EndCommit() {
  if (g_committing.fetch_sub(1) != 1) return;
  const int signal = g_pending_signal.exchange(0);
  if (signal == 0) return;
  RemoveOpenStagingFolders();
  EndAsSignalWould(signal);
}

}  // namespace internal

void InstallOutputSetInterruptCleanup() {
  struct sigaction action {};
  action.sa_handler = OnInterruptRemoveStaging;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
}

}  // namespace platemeter
