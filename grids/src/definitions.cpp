#include "platemeter/grids/definitions.h"

namespace platemeter {

const char* MarkTypeName(MarkType type) {
  switch (type) {
    case MarkType::kCross: return "cross";
    case MarkType::kDot: return "dot";
    case MarkType::kRing: return "ring";
    case MarkType::kCorner: return "corner";
  }
  return "?";
}

bool ParseMarkType(const std::string& name, MarkType* type) {
  for (MarkType candidate : {MarkType::kCross, MarkType::kDot, MarkType::kRing, MarkType::kCorner}) {
    if (name == MarkTypeName(candidate)) {
      *type = candidate;
      return true;
    }
  }
  return false;
}

const GridPoint* MasterGrid::Find(const std::string& id) const {
  for (const GridPoint& point : points) {
    if (point.id == id) return &point;
  }
  return nullptr;
}

const FiducialMark* FiducialSet::Find(const std::string& id) const {
  for (const FiducialMark& mark : marks) {
    if (mark.id == id) return &mark;
  }
  return nullptr;
}

}  // namespace platemeter
