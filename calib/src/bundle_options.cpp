// BundleOptions (bundle_options.h): the datum names and the options' ranges.
#include "platemeter/calib/bundle_options.h"

#include <cmath>

namespace platemeter {
namespace {

struct DatumName {
  DatumKind kind;
  const char* name;
};
constexpr DatumName kDatumNames[] = {
    {DatumKind::kAuto, "auto"},
    {DatumKind::kControlPoints, "control"},
    {DatumKind::kFixedFrames, "fixed-frames"},
    {DatumKind::kInnerConstraints, "inner-constraints"},
};

}  // namespace

const char* DatumKindName(DatumKind kind) {
  for (const DatumName& d : kDatumNames) {
    if (d.kind == kind) return d.name;
  }
  return "unknown";
}

bool ParseDatumKind(const std::string& name, DatumKind* kind) {
  for (const DatumName& d : kDatumNames) {
    if (name == d.name) {
      if (kind != nullptr) *kind = d.kind;
      return true;
    }
  }
  return false;
}

bool BundleOptions::Check(std::string* why) const {
  auto fail = [why](const char* reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  bool known_datum = false;
  for (const DatumName& d : kDatumNames) known_datum = known_datum || d.kind == datum;
  if (!known_datum) return fail("datum is not one of auto, control, fixed-frames, inner-constraints");
  if (!adjustment.Check(why)) return false;
  return true;
}

}  // namespace platemeter
