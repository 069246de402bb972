#pragma once
// Coarse search: cross-like places on an overview, by normalized correlation
// with a cross template. Dark and bright crosses give correlation peaks of
// opposite sign, so one search finds both polarities.
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/detect/overview.h"

namespace platemeter {

struct CrossCandidate {
  PixelPoint position_px;  // full-resolution scan pixels
  double score = 0.0;      // normalized correlation, -1..1; negative: dark cross on bright ground
};

struct CrossCandidateOptions {
  double line_width_px = 4.0;     // px (full resolution); nominal line width
  double arm_length_px = 100.0;   // px (full resolution); nominal tip-to-tip length
  double max_template_arm_overview_px = 12.0;  // overview px; longer arms are cut (rotation tolerance)
  double min_abs_score = 0.3;     // correlation below this is no candidate
  int max_candidates = 2000;      // strongest kept (both polarities together)
  bool Check(std::string* why) const;
};

std::vector<CrossCandidate> FindCrossCandidates(const Overview& overview, const CrossCandidateOptions& options);

// The overview factor that keeps a line of this width about `target_line_px`
// wide, raised if needed so the overview's long side stays within max_overview_px
// (its memory: 4 bytes a pixel); a power of two.
int OverviewFactorFor(double line_width_px, long scan_long_side_px, double target_line_px = 1.5,
                      long max_overview_px = 4096);

}  // namespace platemeter
