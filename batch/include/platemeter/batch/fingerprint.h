#pragma once
// The resume fingerprint of a scan: SHA-256 over the scan's bytes (its SHA-256)
// and the canonical text of every option that changes the outputs (including the
// per-scan overrides and the software version). Equal fingerprint = same result.
#include <string>

namespace platemeter {

// Lower-case hex SHA-256 of "platemeter-batch-fingerprint-v1\n", the scan digest and the options text.
std::string ScanFingerprint(const std::string& scan_sha256, const std::string& options_text);

}  // namespace platemeter
