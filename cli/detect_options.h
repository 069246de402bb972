#pragma once
// The detection options shared by `platemeter detect` and `platemeter measure`,
// registered over a base request (a job file's): option_overlay.h.
#include "option_overlay.h"
#include "platemeter/pipeline/detect_run.h"

namespace platemeter::cli {

using pipeline::DetectRequest;
using pipeline::PasspointRequest;
using pipeline::TrailRequest;

// --pixel-size-um, --orientation, --allow-ambiguous-orientation.
void AddScanOptions(OptionOverlay<DetectRequest>& overlay);

// --stars, --bright-stars, --star-fwhm-px; the duty-cycle trails (--trails-start-utc switches them on,
// --trail-dashes, --trail-break-s); the passpoints (--passpoint-diameter-um switches them on, --passpoint-shape,
// --passpoint-line-width-um, --passpoint-polarity, --passpoints). A trail or passpoint detail given without
// the switch changes the job's trails or passpoints, if it has them.
void AddFeatureOptions(OptionOverlay<DetectRequest>& overlay);

}  // namespace platemeter::cli
