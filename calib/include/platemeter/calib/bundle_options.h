#pragma once
// Options of the self-calibrating bundle adjustment (bundle_adjustment.h), with
// units and a one-line meaning each (DESIGN.md "Shape of an algorithm").
#include <string>

#include "platemeter/calib/adjustment.h"

namespace platemeter {

// How the datum (the object frame's origin, orientation and scale) is fixed.
enum class DatumKind {
  kAuto,              // control if any point or station has a prior, else fixed frames if any, else inner constraints
  kControlPoints,     // by ground points (GroundPoint sigmas) and stations (position covariance) with a-priori coordinates
  kFixedFrames,       // by frames held fixed (FrameSetup::fixed) plus distances (scale) where given
  kInnerConstraints,  // free network: minimum trace over the exposure stations (positions and attitudes)
};
const char* DatumKindName(DatumKind kind);           // "auto", "control", "fixed-frames", "inner-constraints"
bool ParseDatumKind(const std::string& name, DatumKind* kind);  // false for an unknown name

struct BundleOptions {
  DatumKind datum = DatumKind::kAuto;
  // The engine's options (adjustment.h): the robust pass and its rejection
  // level, iterations and tolerance, the correlation threshold, the tests'
  // significance level, the rank tolerance, threads.
  AdjustmentOptions adjustment;
  bool Check(std::string* why) const;
};

}  // namespace platemeter
