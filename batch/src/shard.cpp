#include "platemeter/batch/shard.h"

#include <charconv>

#include "platemeter/core/error.h"

namespace platemeter {

Shard ParseShard(const std::string& text) {
  const size_t slash = text.find('/');
  Shard s;
  auto parse = [](const std::string& t, int* v) {
    const auto r = std::from_chars(t.data(), t.data() + t.size(), *v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size() && !t.empty();
  };
  if (slash == std::string::npos || !parse(text.substr(0, slash), &s.index) || !parse(text.substr(slash + 1), &s.count)) {
    throw Error("--shard", "'" + text + "' is not K/N (e.g. 2/8)");
  }
  if (s.count < 1 || s.index < 1 || s.index > s.count) {
    throw Error("--shard", "'" + text + "': K must be 1..N and N >= 1 (shards are numbered from 1)");
  }
  return s;
}

bool InShard(size_t position, const Shard& shard) {
  return position % static_cast<size_t>(shard.count) == static_cast<size_t>(shard.index - 1);
}

std::vector<size_t> ShardPositions(size_t total, const Shard& shard) {
  std::vector<size_t> positions;
  for (size_t i = static_cast<size_t>(shard.index - 1); i < total; i += static_cast<size_t>(shard.count)) {
    positions.push_back(i);
  }
  return positions;
}

}  // namespace platemeter
