#pragma once
// What every detector returns: a position with its formal sigma and a status.
// A point that could not be measured is data too: status missing or rejected
// with a reason. A predicted position is never a measurement.
#include <string>

#include "platemeter/core/pixel.h"
#include "platemeter/core/point_status.h"

namespace platemeter {

struct DetectedPoint {
  std::string id;                 // X{i}Y{j} for reseau crosses, the table name for fiducials
  PointKind kind = PointKind::kReseau;
  PointStatus status = PointStatus::kMissing;
  std::string reason;             // for rejected/missing: low_contrast, defect, poor_fit, outlier, outside_scan, not_found
  PixelPoint position_px;         // measured (or, for kPredicted/kMissing, predicted) centre
  double sigma_x_px = 0.0;        // formal standard deviations from the fit
  double sigma_y_px = 0.0;
  double correlation_xy = 0.0;
};

}  // namespace platemeter
