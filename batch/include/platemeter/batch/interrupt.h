#pragma once
// SIGINT/SIGTERM during a batch: the first stops taking new scans (the running
// ones finish), a second abandons the running ones. The handlers only count.
namespace platemeter {

void InstallBatchInterruptHandlers();
// How many SIGINT/SIGTERM arrived since installation (0 = none).
int BatchInterruptCount();
// The first signal received (SIGINT or SIGTERM), 0 if none.
int BatchInterruptSignal();

}  // namespace platemeter
