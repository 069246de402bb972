#pragma once
// Building the bundle's adjustment problem (bundle_build.cpp).
#include <map>
#include <string>
#include <vector>

#include "platemeter/calib/adjustment.h"
#include "platemeter/calib/bundle_adjustment.h"

namespace platemeter::bundle_internal {

struct BuiltBundle {
  std::vector<int> camera_blocks;  // per input camera
  std::vector<int> frame_blocks;   // per input frame
  std::vector<std::string> point_ids;
  std::vector<int> point_blocks;   // per point_ids
  std::vector<bool> point_control;
  DatumKind datum = DatumKind::kAuto;
  std::string datum_words;
};

// The datum actually used for `requested` (kAuto resolved) and the frames it holds.
DatumKind ResolveDatum(const BundleInput& input, DatumKind requested);

BuiltBundle BuildBundleProblem(const BundleInput& input, const BundleApproximations& approximations,
                               DatumKind requested, AdjustmentProblem* problem);

}  // namespace platemeter::bundle_internal
