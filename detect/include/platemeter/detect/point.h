#pragma once
// What every detector returns: a position with its formal sigma and a status.
// A point that could not be measured is data too: status missing or rejected
// with a reason. A predicted position is never a measurement.
#include <string>

#include "platemeter/core/pixel.h"

namespace platemeter {

enum class PointStatus { kMeasured, kRejected, kMissing, kPredicted };
const char* PointStatusName(PointStatus status);

struct DetectedPoint {
  std::string id;                 // X{i}Y{j} for reseau crosses, the table name for fiducials
  std::string kind;               // "reseau", "fiducial", "star", "trail_dot", "passpoint"
  PointStatus status = PointStatus::kMissing;
  std::string reason;             // for rejected/missing: low_contrast, defect, poor_fit, outlier, outside_scan
  PixelPoint position_px;         // measured (or, for kPredicted, predicted) centre
  double sigma_x_px = 0.0;        // formal standard deviations from the fit
  double sigma_y_px = 0.0;
  double correlation_xy = 0.0;
};

}  // namespace platemeter
