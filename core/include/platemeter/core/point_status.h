#pragma once
// What a measured point is and where its numbers come from. Shared by the
// detectors (detect/) and the measurement file (measure/), which may not
// depend on each other's layer.
#include <string>

namespace platemeter {

// What a point is.
enum class PointKind { kReseau, kFiducial, kStar, kTrailDot, kTrailDash, kPasspoint };
const char* PointKindName(PointKind kind);  // "reseau", "fiducial", "star", "trail_dot", "trail_dash", "passpoint"
bool ParsePointKind(const std::string& name, PointKind* kind);

// Where a point's numbers come from. A predicted position is never a measurement.
enum class PointStatus { kMeasured, kRejected, kMissing, kPredicted, kTruth };
const char* PointStatusName(PointStatus status);  // "measured", "rejected", "missing", "predicted", "truth"
bool ParsePointStatus(const std::string& name, PointStatus* status);

}  // namespace platemeter
