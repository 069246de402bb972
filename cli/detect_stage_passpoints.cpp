// The passpoint stage of RunDetection (detect_stages.h). PLACEHOLDER being replaced in this session.
#include "detect_stages.h"
#include "platemeter/core/error.h"

namespace platemeter::cli {

StageOutput RunPasspointStage(const DetectContext& context) {
  throw Error(context.request.scan, "passpoints are not implemented yet");
}

}  // namespace platemeter::cli
