#pragma once
// A forked child that runs one reader's inputs one after the other (the fuzz
// harness's isolation, fuzz_driver.h): a crash, abort or hang ends only the
// child, and so does an input that leaves process-wide state (the image cache)
// broken; the next input gets a fresh child. One fork per finding, not per
// input, keeps it fast.
#include <sys/types.h>

#include <string>

#include "fuzz/fuzz_driver.h"

namespace platemeter::fuzz {

class ForkServer {
 public:
  explicit ForkServer(const FuzzTarget& target) : target_(target) {}
  ~ForkServer() { Stop(); }
  ForkServer(const ForkServer&) = delete;
  ForkServer& operator=(const ForkServer&) = delete;

  RunOutcome Run(const std::string& input, double input_limit_s);

 private:
  void Start();
  void Stop();
  RunOutcome ChildDied(const std::string& fallback);

  const FuzzTarget& target_;
  pid_t child_ = -1;
  int to_child_ = -1;
  int from_child_ = -1;
};

}  // namespace platemeter::fuzz
