#pragma once
// Options of the self-calibrating bundle adjustment (bundle_adjustment.h), with
// units and a one-line meaning each (DESIGN.md "Shape of an algorithm").
#include <string>

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
  // A robust first pass (Cauchy loss, scale in units of each observation's
  // sigma) finds gross errors; 0 = no robust pass. Always followed by a plain
  // weighted pass whose statistics are reported.
  double robust_loss_scale = 0.0;  // sigma units
  // After the robust pass, an observation whose normalized residual (residual /
  // its a-priori sigma, scaled by the pass's robust sigma0) exceeds this is
  // rejected; 0 = from false_rejection_rate (adjustment.h).
  double rejection_threshold = 0.0;   // sigma units
  double false_rejection_rate = 0.01; // -; chance that any good observation is rejected (threshold 0)
  int max_iterations = 100;          // trust-region (Powell dogleg) iterations per pass
  // Relative change of v'Pv that ends a pass: at v'Pv = 4e5 (a block of
  // 400 000 observations) a step changing it by 1e-10 of itself moves the
  // solution by under 0.01 sigma in any direction.
  double function_tolerance = 1e-10;
  // Correlations of the inner cone (and of any reported block) at or above
  // this magnitude are named in the report.
  double correlation_threshold = 0.9;  // |rho|
  double significance_level = 0.05;    // alpha of the chi-square and t tests
  // An eigenvalue of the diagonally scaled reduced normal matrix below this
  // times the largest counts as zero (numerical rank).
  double rank_tolerance = 1e-12;     // relative
  int num_threads = 0;               // 0 = every core
  bool Check(std::string* why) const;
};

}  // namespace platemeter
