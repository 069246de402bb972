#include "platemeter/batch/fingerprint.h"

#include "platemeter/core/sha256.h"

namespace platemeter {

std::string ScanFingerprint(const std::string& scan_sha256, const std::string& options_text) {
  Sha256 h;
  // A version tag, so a change of this scheme invalidates old records rather than matching them.
  h.Update("platemeter-batch-fingerprint-v1\nscan_sha256 = " + scan_sha256 + "\n");
  h.Update(options_text);
  return h.FinishHex();
}

}  // namespace platemeter
