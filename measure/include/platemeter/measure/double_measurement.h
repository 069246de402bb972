#pragma once
// The double measurement: the plate scanned twice (the second time rotated
// 180 degrees on the scanner, so the scanner's systematic errors change sign
// in the plate frame), each scan corrected on its own into the master-grid
// frame (CorrectPlate), then the two sets paired by (kind, id) and meaned with
// inverse-variance weights per axis:
//   x = (x1 / v1 + x2 / v2) / (1 / v1 + 1 / v2),  v = 1 / (1 / v1 + 1 / v2).
// The discrepancies d = x1 - x2 are reported with their normalized values
// d / sqrt(v1 + v2) (about 1 RMS when the sigmas are right).
#include <string>
#include <vector>

#include "platemeter/measure/measurement_file.h"

namespace platemeter {

struct PointDiscrepancy {
  std::string id;
  PointKind kind = PointKind::kReseau;
  double dx_mm = 0.0, dy_mm = 0.0;        // mm; first - second
  double normalized_x = 0.0, normalized_y = 0.0;  // d / sqrt(v1 + v2)
};

struct DoubleMeasurementReport {
  std::vector<PointDiscrepancy> discrepancies;  // paired points, in the first file's order
  int paired = 0;
  int only_first = 0, only_second = 0;          // points in one file only (kept as they are / dropped)
  double rms_discrepancy_mm = 0.0;              // per axis
  double rms_normalized = 0.0;                  // per axis
};

// `first` becomes the mean (points with x_mm in both files); points measured
// in the first file only keep their values and get the flag
// "double_measurement:first_only". The header records the correction
// "double_measurement" with the second scan's file and the figures.
DoubleMeasurementReport MeanDoubleMeasurement(MeasurementFile* first, const MeasurementFile& second);

}  // namespace platemeter
