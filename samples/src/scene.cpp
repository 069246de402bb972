#include "platemeter/samples/scene.h"

namespace platemeter::sim {

const char* MarkKindName(MarkKind kind) {
  switch (kind) {
    case MarkKind::kReseauCross: return "reseau-cross";
    case MarkKind::kFiducial: return "fiducial";
    case MarkKind::kPasspoint: return "passpoint";
    case MarkKind::kStar: return "star";
    case MarkKind::kTrailDot: return "trail-dot";
    case MarkKind::kTrailDash: return "trail-dash";
    case MarkKind::kFalseMark: return "false-mark";
    case MarkKind::kDust: return "dust";
    case MarkKind::kScratch: return "scratch";
  }
  return "unknown";
}

}  // namespace platemeter::sim
