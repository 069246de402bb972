// Output files written as one set (output_set.h); the interrupt clean-up's
// registry of open staging folders is in output_set_interrupt.cpp.
#include "platemeter/core/output_set.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "output_set_interrupt.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace fs = std::filesystem;
namespace {

constexpr char kStagingPrefix[] = ".output.partial-";

std::atomic<int> g_staging_counter{0};

// Signals held back while a set is renamed into place.
class HeldInterrupts {
 public:
  HeldInterrupts() {
    sigset_t held;
    sigemptyset(&held);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&held, s);
    pthread_sigmask(SIG_BLOCK, &held, &previous_);
    internal::BeginCommit();
  }
  ~HeldInterrupts() {
    internal::EndCommit();
    pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
  }

 private:
  sigset_t previous_;
};

// Creates `dir`; returns the folders it created, deepest first (removed again when no set lands in them).
std::vector<fs::path> CreateFolder(const std::string& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw EnvironmentError(dir, "the output folder is a file, not a folder");
  std::vector<fs::path> missing;
  for (fs::path p = fs::absolute(dir).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (ec) throw EnvironmentError(dir, "cannot create the output folder (" + ec.message() + ")");
  return missing;
}

void CheckNameLengths(const std::string& dir, const std::vector<std::string>& names) {
  const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  if (name_max <= 0) return;
  for (const std::string& member : names) {
    const std::string name = fs::path(member).filename().string();
    if (static_cast<long>(name.size()) <= name_max) continue;
    throw Error((fs::path(dir) / member).string(), "file name too long: " + std::to_string(name.size()) +
                                                     " characters, the file system allows " + std::to_string(name_max) +
                                                     " (give the scan a shorter name)");
  }
}

}  // namespace

OutputSet::OutputSet(const std::string& dir, const std::vector<std::string>& member_names)
    : dir_(dir), members_(member_names) {
  created_ = CreateFolder(dir_);
  CheckNameLengths(dir_, members_);
  RemoveAbandonedStaging(dir_);
  staging_ = (fs::path(dir_) / (kStagingPrefix + std::to_string(::getpid()) + "-" +
                                std::to_string(g_staging_counter.fetch_add(1))))
                 .string();
  if (::mkdir(staging_.c_str(), 0755) != 0) {
    throw EnvironmentError(dir_, std::string("cannot write into the output folder (") + std::strerror(errno) + ")");
  }
  cleanup_slot_ = internal::RegisterStaging(staging_);
}

OutputSet::~OutputSet() {
  if (committed_) return;
  internal::UnregisterStaging(cleanup_slot_);
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
  for (const fs::path& folder : created_) fs::remove(folder, ignored);  // only while empty
}

std::string OutputSet::Stage(const std::string& name) {
  if (std::find(members_.begin(), members_.end(), name) == members_.end()) {
    throw Error(name, "not a member of this output set (internal error)");
  }
  if (std::find(staged_.begin(), staged_.end(), name) == staged_.end()) staged_.push_back(name);
  const fs::path staged = fs::path(staging_) / name;
  if (staged.parent_path() != fs::path(staging_)) {  // a member in a sub-folder (plots/x.png)
    std::error_code ec;
    fs::create_directories(staged.parent_path(), ec);
    if (ec) throw EnvironmentError(FinalPath(name), "cannot create its folder (" + ec.message() + ")");
  }
  return staged.string();
}

std::string OutputSet::FinalPath(const std::string& name) const { return (fs::path(dir_) / name).string(); }

void OutputSet::Commit() {
  for (const std::string& name : staged_) {
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(staging_) / name, ec)) throw Error(FinalPath(name), "was not written");
  }
  {
    HeldInterrupts held;
    for (const std::string& name : staged_) {
      std::error_code ec;
      const fs::path target = FinalPath(name);
      if (target.parent_path() != fs::path(dir_)) fs::create_directories(target.parent_path(), ec);
      if (!ec) fs::rename(fs::path(staging_) / name, target, ec);
      if (ec) throw EnvironmentError(FinalPath(name), "cannot rename into place (" + ec.message() + ")");
    }
    for (const std::string& name : members_) {
      if (std::find(staged_.begin(), staged_.end(), name) != staged_.end()) continue;
      std::error_code ignored;
      fs::remove(FinalPath(name), ignored);
    }
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
    committed_ = true;
    internal::UnregisterStaging(cleanup_slot_);
  }
}

int RemoveAbandonedStaging(const std::string& dir) {
  int removed = 0;
  std::error_code ec;
  std::vector<fs::path> abandoned;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(kStagingPrefix, 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + sizeof kStagingPrefix - 1, nullptr, 10);
    // A running process's set is in progress (kill(pid, 0) succeeds or is not permitted).
    if (pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)) continue;
    abandoned.push_back(it->path());
  }
  for (const fs::path& path : abandoned) {
    std::error_code e;
    if (fs::remove_all(path, e) > 0) ++removed;
  }
  return removed;
}

}  // namespace platemeter
