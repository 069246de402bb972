#pragma once
// The registry of open staging folders that an interrupt removes (output_set.h).
#include <string>

namespace platemeter::internal {

// Records a staging folder for the interrupt clean-up; returns its slot (-1: the
// registry is full, the folder is then left to RemoveAbandonedStaging).
int RegisterStaging(const std::string& path);
void UnregisterStaging(int slot);
// A commit in progress defers an interrupt until it ends (EndCommit re-raises it).
void BeginCommit();
void EndCommit();

}  // namespace platemeter::internal
