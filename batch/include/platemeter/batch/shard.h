#pragma once
// Splitting a batch over machines with no coordination (`--shard K/N`): the
// i-th scan of the list (0-based, in list order) belongs to shard (i mod N) + 1.
// Every shard lists the same inputs in the same order, so the N shards
// partition the list exactly and their sizes differ by at most one.
#include <cstddef>
#include <string>
#include <vector>

namespace platemeter {

struct Shard {
  int index = 1;  // K, 1..count
  int count = 1;  // N >= 1
};

// Parses "K/N" (1 <= K <= N). Throws Error("--shard", reason).
Shard ParseShard(const std::string& text);

// True when position i (0-based) of the list belongs to `shard`.
bool InShard(size_t position, const Shard& shard);

// The positions of a list of `total` scans that belong to `shard`, ascending.
std::vector<size_t> ShardPositions(size_t total, const Shard& shard);

}  // namespace platemeter
