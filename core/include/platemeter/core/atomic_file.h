#pragma once
// Small text outputs (measurement files, reports, JSON) written atomically:
// a temporary file in the same folder, then a rename, so a reader never sees a
// half-written file and an earlier result is never lost to a failed write.
#include <functional>
#include <ostream>
#include <string>
#include <string_view>

namespace platemeter {

// Writes `contents` to `path` through ".<name>.partial.<ext>" and a rename.
// Throws Error naming `path` on failure (the temporary file is removed).
void WriteFileAtomically(const std::string& path, std::string_view contents);
// The same through a given temporary path (same folder as `path`), for writers
// that need their own temporary name (several processes writing one file).
void WriteFileAtomicallyThrough(const std::string& path, const std::string& temp_path, std::string_view contents);
// The same with the contents streamed by `put` (large files are never held whole in memory). Whatever
// `put` throws is rethrown after the temporary file is removed; the target is then untouched.
void WriteFileAtomicallyStreamed(const std::string& path, const std::function<void(std::ostream&)>& put);

}  // namespace platemeter
