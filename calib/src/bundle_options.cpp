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
  if (!(robust_loss_scale >= 0.0) || !std::isfinite(robust_loss_scale)) {
    return fail("robust_loss_scale must be 0 (no robust pass) or a positive number of sigmas");
  }
  if (!(rejection_threshold >= 0.0) || !std::isfinite(rejection_threshold)) {
    return fail("rejection_threshold must be 0 (from false_rejection_rate) or a positive number of sigmas");
  }
  if (!(false_rejection_rate > 0.0 && false_rejection_rate < 0.5)) {
    return fail("false_rejection_rate must lie in (0, 0.5)");
  }
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!(function_tolerance > 0.0) || !(function_tolerance < 1.0)) {
    return fail("function_tolerance must lie in (0, 1)");
  }
  if (!(correlation_threshold > 0.0) || !(correlation_threshold <= 1.0)) {
    return fail("correlation_threshold must lie in (0, 1]");
  }
  if (!(significance_level > 0.0) || !(significance_level < 1.0)) {
    return fail("significance_level must lie in (0, 1)");
  }
  if (!(rank_tolerance > 0.0) || !(rank_tolerance < 1.0)) return fail("rank_tolerance must lie in (0, 1)");
  if (num_threads < 0) return fail("num_threads must be 0 (every core) or positive");
  return true;
}

}  // namespace platemeter
