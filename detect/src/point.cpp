#include "platemeter/detect/point.h"

namespace platemeter {

const char* PointStatusName(PointStatus status) {
  switch (status) {
    case PointStatus::kMeasured: return "measured";
    case PointStatus::kRejected: return "rejected";
    case PointStatus::kMissing: return "missing";
    case PointStatus::kPredicted: return "predicted";
  }
  return "?";
}

}  // namespace platemeter
