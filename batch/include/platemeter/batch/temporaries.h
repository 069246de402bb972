#pragma once
// Temporaries left by a killed run. Every writer of the project names its
// temporary "." + name + ".partial" + ... in the target's folder
// (core/atomic_file.h, the residual plot, core/image_writer.h), so a file
// whose name starts with '.' and contains ".partial" is never a final output.
#include <string>

namespace platemeter {

bool IsTemporaryName(const std::string& file_name);

// Removes the temporaries directly inside `folder` (not recursive); returns how many.
int RemoveTemporaries(const std::string& folder);

// Writes `contents` to `path` atomically through a temporary unique to this process
// (".<name>.partial.<pid>"), for files that several processes (shards) may write at once.
void WriteSharedFileAtomically(const std::string& path, const std::string& contents);

}  // namespace platemeter
