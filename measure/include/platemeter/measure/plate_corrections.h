#pragma once
// The comparator corrections end to end on one measurement file
// (docs/measure.md): pixel -> comparator -> thermal -> emulsion depth ->
// reseau fit -> local reseau correction, filling x_mm, y_mm, sigma_x_mm,
// sigma_y_mm of every measured point and recording each applied step in the
// header (AppliedCorrection, in order).
#include <optional>
#include <string>
#include <vector>

#include "platemeter/grids/definitions.h"
#include "platemeter/measure/corrections.h"
#include "platemeter/measure/fiducial_orientation.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/reseau_fit.h"

namespace platemeter {

struct PlateCorrectionOptions {
  std::optional<double> pixel_size_um;       // um; default the file header's
  std::optional<std::string> orientation;    // detect's name ("0", "90m", ...); default the header's "orientation", else "0"
  std::optional<double> temperature_degC;    // degC; measuring temperature (none: no thermal correction)
  double calibration_temperature_degC = 20.0;  // degC; of the master grid values
  double expansion_per_degC = 8.1e-6;          // 1/degC; glass linear expansion
  EmulsionDepthModel emulsion;                 // depth 0: no emulsion-depth correction
  double principal_point_x_mm = 0.0, principal_point_y_mm = 0.0;  // mm; grid frame, centre of the radial model
  ReseauFitOptions fit;
  // The bilinear local correction of every non-reseau point, applied when the
  // film deformation is detectable: the reseau fit's chi-square rejects "the
  // residuals are measuring noise" at local_reseau_significance. Otherwise it
  // would only carry the corner crosses' noise into every point of a cell as
  // an error shared by all of them (docs/measure.md, "Local reseau correction").
  bool local_reseau = true;
  double local_reseau_significance = 0.01;
  // The fiducial interior orientation. CorrectFiducialPlate always applies it;
  // CorrectPlate (reseau cameras) only when fiducial_orientation is set: the
  // fiducials' reseau-corrected positions are then fitted to `fiducials` and
  // every point is mapped into that frame.
  bool fiducial_orientation = false;
  std::vector<CalibratedFiducial> fiducials;   // calibrated camera positions (CalibratedFiducials)
  std::string fiducial_source;                 // recorded in the header (no spaces), e.g. "format_corners"
  FiducialOrientationOptions fiducial;
  bool Check(std::string* why) const;
};

struct PlateCorrectionReport {
  ComparatorCorrection comparator;
  ThermalCorrection thermal;
  EmulsionDepthCorrection emulsion;
  std::vector<ReseauObservation> observations;  // the measured crosses given to the fit
  ReseauFit fit;
  // The fit's mean scale read as an emulsion depth: (scale - 1) n c (um), with
  // its sigma; meaningful when the emulsion correction was off.
  ValueSigma emulsion_depth_reading_um;
  int points_corrected = 0;
  // The local correction's test: the fit's chi-square, its degrees of freedom
  // and the probability of a chi-square that large from noise alone.
  bool local_reseau_applied = false;
  double reseau_chi2 = 0.0;
  int reseau_dof = 0;
  double reseau_p_value = 1.0;
  std::optional<FiducialOrientation> fiducial;  // when the fiducial step ran
};

// Throws Error(plate id, reason) without a pixel size or with too few crosses.
PlateCorrectionReport CorrectPlate(MeasurementFile* file, const MasterGrid& grid, const PlateCorrectionOptions& options);

// Cameras without a reseau: pixel -> comparator -> thermal (when a
// temperature is given) -> emulsion depth (when a depth is given; the
// principal point, in camera mm, placed by a preliminary similarity fit of
// the fiducials) -> fiducial interior orientation into camera mm
// (options.fiducials). The reseau steps do not apply.
// Throws Error(plate id, reason) without a pixel size or with too few fiducials.
PlateCorrectionReport CorrectFiducialPlate(MeasurementFile* file, const PlateCorrectionOptions& options);

}  // namespace platemeter
