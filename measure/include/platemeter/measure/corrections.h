#pragma once
// The comparator corrections before the reseau fit (docs/measure.md): each a
// small struct with its parameters, switchable, recorded in the measurement
// file header (AppliedCorrection) in application order. Every step maps a
// position and its 2x2 covariance: cov' = J cov J^T with J the step's
// Jacobian d(out)/d(in).
#include <string>

#include "platemeter/measure/emulsion_depth.h"
#include "platemeter/measure/measurement_file.h"

namespace platemeter {

// A symmetric 2x2 covariance (unit squared).
struct Covariance2 {
  double xx = 0.0, xy = 0.0, yy = 0.0;
  // J cov J^T for the row-major 2x2 Jacobian j.
  Covariance2 Transformed(const double j[4]) const;
  Covariance2 operator+(const Covariance2& o) const { return {xx + o.xx, xy + o.xy, yy + o.yy}; }
};

// A position (px or mm) with its covariance.
struct PlanePoint {
  double x = 0.0, y = 0.0;
  Covariance2 cov;
};

// Pixel -> comparator millimetres: x = col * p, y = -row * p (rows grow
// downward, y up), then the scan orientation undone (the plate image appeared
// rotated counter-clockwise by orientation_deg, after a mirror for emulsion-down
// scans), so the comparator frame is the plate frame up to a small rotation,
// scale and offset (which the reseau fit takes).
struct ComparatorCorrection {
  double pixel_size_um = 0.0;  // um; nominal scan pixel size
  int orientation_deg = 0;     // 0, 90, 180, 270 (detect's header "orientation")
  bool mirrored = false;       // detect's orientation name ends with "m"
  PlanePoint Apply(const PlanePoint& px) const;
  void Jacobian(double j[4]) const;  // mm per px
  AppliedCorrection Record() const;
  bool Check(std::string* why) const;
};

// Thermal scaling from the measuring temperature to the grid's calibration
// temperature: the glass grew by 1 + a (T - T_cal), so the factor is its
// inverse (seed 001: 22 -> 20 degC at 8.1e-6 gives 0.9999838).
struct ThermalCorrection {
  bool enabled = true;
  double temperature_degC = 20.0;              // degC; plate/glass temperature when measured
  double calibration_temperature_degC = 20.0;  // degC; of the master grid values
  double expansion_per_degC = 8.1e-6;          // 1/degC; glass linear expansion
  double Factor() const { return 1.0 / (1.0 + expansion_per_degC * (temperature_degC - calibration_temperature_degC)); }
  PlanePoint Apply(const PlanePoint& mm) const;
  AppliedCorrection Record() const;
  bool Check(std::string* why) const;
};

// Emulsion depth: the exact radial model (emulsion_depth.h) inverted about the
// principal point's position in the comparator frame.
struct EmulsionDepthCorrection {
  bool enabled = true;
  EmulsionDepthModel model;
  double centre_x_mm = 0.0, centre_y_mm = 0.0;  // mm; principal point in the comparator frame
  PlanePoint Apply(const PlanePoint& mm) const;
  AppliedCorrection Record() const;
  bool Check(std::string* why) const;
};

}  // namespace platemeter
