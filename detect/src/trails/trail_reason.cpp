// The words of the trail linker's reasons and steps (trail_linker.h): the measurement file's `trail:<reason>`
// flags and the detection summary's `decoded_trails_by_step`; the code itself compares the enums.
#include "platemeter/detect/trail_linker.h"

namespace platemeter {

const char* TrailReasonName(TrailReason reason) {
  switch (reason) {
    case TrailReason::kNone: return "";
    case TrailReason::kNotStar: return "not_star";
    case TrailReason::kUnlinked: return "unlinked";
    case TrailReason::kAtEdge: return "at_edge";
    case TrailReason::kImageBeforeRun: return "image_before_run";
    case TrailReason::kShortPattern: return "short_pattern";
    case TrailReason::kAmbiguous: return "ambiguous";
    case TrailReason::kContested: return "contested";
    case TrailReason::kLeadingDashesIncomplete: return "leading_dashes_incomplete";
    case TrailReason::kDoubtfulNumber: return "doubtful_number";
    case TrailReason::kLoneTrail: return "lone_trail";
    case TrailReason::kPoorTrack: return "poor_track";
    case TrailReason::kUnconfirmed: return "unconfirmed";
    case TrailReason::kRunFlux: return "run_flux";
    case TrailReason::kOffTrack: return "off_track";
    case TrailReason::kUnverified: return "unverified";
    case TrailReason::kBlended: return "blended";
    case TrailReason::kUnjoined: return "unjoined";
    case TrailReason::kUnresolvedRun: return "unresolved_run";
    case TrailReason::kOffFlow: return "off_flow";
    case TrailReason::kEmptyPlaces: return "empty_dash_places";
    case TrailReason::kBadFit: return "bad_fit";
  }
  return "";
}

const char* TrailStepName(TrailStep step) {
  switch (step) {
    case TrailStep::kRun: return "run";
    case TrailStep::kSibling: return "sibling";
    case TrailStep::kSeparators: return "separators";
    case TrailStep::kFlow: return "flow";
    case TrailStep::kLone: return "lone";
    case TrailStep::kFlowFill: return "flow_fill";
  }
  return "";
}

}  // namespace platemeter
