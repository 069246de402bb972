#include "platemeter/core/point_status.h"

namespace platemeter {
namespace {
constexpr const char* kKindNames[] = {"reseau", "fiducial", "star", "trail_dot", "trail_dash", "passpoint"};
constexpr const char* kStatusNames[] = {"measured", "rejected", "missing", "predicted", "truth"};
}  // namespace

const char* PointKindName(PointKind kind) { return kKindNames[static_cast<int>(kind)]; }

bool ParsePointKind(const std::string& name, PointKind* kind) {
  for (int i = 0; i < 6; ++i) {
    if (name == kKindNames[i]) {
      *kind = static_cast<PointKind>(i);
      return true;
    }
  }
  return false;
}

const char* PointStatusName(PointStatus status) { return kStatusNames[static_cast<int>(status)]; }

bool ParsePointStatus(const std::string& name, PointStatus* status) {
  for (int i = 0; i < 5; ++i) {
    if (name == kStatusNames[i]) {
      *status = static_cast<PointStatus>(i);
      return true;
    }
  }
  return false;
}

}  // namespace platemeter
