#pragma once
// Duty-cycle star trails (seed 001, Table 1; core/duty_cycle.h): the images of
// one star exposed by the capping-shutter program lie along its diurnal arc.
// LinkTrails
//   1. links images into chains (each image to its nearest neighbour and to the
//      nearest one on the opposite side, nearly collinear; only mutual links kept);
//   2. matches each chain to the schedule: arc length along the chain against
//      the exposures' mid times of one trail (trail t has leading_dashes[t]
//      leading dashes), both directions, a quadratic s(t) refined on the matches;
//   3. accepts a match only when the leading dash run is complete (it numbers the
//      trail) and no other labelling scores as well; otherwise every image of
//      the chain stays unassigned with a reason. No guessing: a dot is either
//      tagged with its trail, dot index and mid-time or left unassigned.
// Chains are per trail, not per star: the four trails of one star are four
// chains (joining them into stars is not done here).
#include <string>
#include <vector>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/detect/star_detector.h"

namespace platemeter {

struct TrailOptions {
  double max_link_px = 40.0;       // px; longest link between consecutive images (the 100-108 s gaps of group 3 must fit)
  double max_gap_ratio = 4.0;      // a chain is cut where a link exceeds this times its median link (trail breaks)
  double min_link_px = 1.0;        // px; images closer than this are not linked (blends)
  double max_bend_deg = 35.0;      // deg; largest turn of the chain at an image
  double match_tolerance = 0.3;    // fraction of the smaller neighbouring schedule gap an image may sit off its exposure
  int min_images = 8;              // chains with fewer images are left unassigned
  // The scanned area (px). A trail whose leading run starts near its edge may have lost dashes
  // beyond it (trail 3 minus one dash looks like a complete trail 2): the position one dash before
  // the run must lie inside by edge_margin_px, else the chain stays unassigned. Unset (max <= min):
  // no check, the caller guarantees that trails are not cut by the scan's edge.
  PixelPoint image_min_px{0.0, 0.0};
  PixelPoint image_max_px{0.0, 0.0};
  double edge_margin_px = 10.0;    // px
  bool require_elongated_dashes = true;  // the leading dashes must be flagged elongated (20 s exposures)
  int min_exposures_after_run = 11;  // the match must reach this many exposures past the leading run (dots 1-10 + separator)
  double min_elongated_exposure_s = 5.0;  // s; an image flagged elongated only matches exposures at least this long
  int max_unmatched = 2;           // chain images matching no exposure (strays) tolerated in an accepted chain
  bool Check(std::string* why) const;
};

// The outcome for one input image (same order as the input).
struct TrailImage {
  int chain = -1;                  // chain id (index into TrailLinkResult::chains), -1 if not linked
  bool assigned = false;           // true: trail/kind/indices/mid_s are valid
  int trail = 0;                   // 1..number of trails (T1..T4), in time order
  ExposureKind kind = ExposureKind::kDot;
  int dot_index = 0;               // 1..25 for dots
  int dash_index = 0;              // 1.. for dashes
  double mid_s = 0.0;              // mid-exposure, on the scale of DutyCycleScheduleOptions::start_s
  double residual_s = 0.0;         // position along the chain expressed in time, minus mid_s
  std::string reason;              // why not assigned: not_star, unlinked, short_chain, no_schedule_match,
                                   // leading_dashes_incomplete, ambiguous, stray, at_edge,
                                   // short_pattern
};

struct TrailChain {
  std::vector<int> images;         // input indices in time order (when decoded) or chain order
  int trail = 0;                   // decoded trail, 0 if not decoded
  int leading_dashes = 0;
  double rate_px_per_s = 0.0;      // mean speed along the chain
  double rms_s = 0.0;              // rms of residual_s over the matched images
  int score = 0;                   // matched images minus expected-but-missing ones of the best labelling
  int runner_up_score = 0;         // best score of a different labelling (ambiguity margin = score - this)
  std::string reason;              // empty if decoded
};

struct TrailLinkResult {
  std::vector<TrailImage> images;  // one per input image
  std::vector<TrailChain> chains;
  long assigned_dots = 0;
  long assigned_dashes = 0;
};

// Links and decodes the trails. `program` is the plate's shutter program with
// start_s = the first opening on the caller's time scale. Images that are not
// measured stars (rejected, defects) are left unassigned ("not_star").
// Throws Error for invalid options.
TrailLinkResult LinkTrails(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options = {});

}  // namespace platemeter
