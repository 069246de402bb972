#pragma once
// A metric camera as the adjustments see it: interior orientation (principal
// distance c, principal point xp, yp) plus one distortion model, and the
// collinearity equations of seed 000 eq. (1):
//   x - xp + dx(xb, yb) = c (A, B, C)·(X - Xc) / (D, E, F)·(X - Xc)
//   y - yp + dy(xb, yb) = c (A', B', C')·(X - Xc) / (D, E, F)·(X - Xc)
// with T = [A B C; A' B' C'; D E F] the image_from_object rotation (rotations.h)
// and dx, dy the distortion correction (distortion_models.h). A direction d in
// the object frame (a star, or X - Xc for a ground point) is in front of the
// camera when (D, E, F)·d > 0, as eq. (1) is written with +c.
// Image coordinates are plate millimetres, x right, y up (DESIGN.md).
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "platemeter/calib/distortion_models.h"
#include "platemeter/grids/definitions.h"

namespace platemeter {

struct InteriorOrientation {
  double principal_distance_mm = 0.0;  // mm; c (calibrated focal length)
  double principal_point_x_mm = 0.0;   // mm; xp, from the origin of the plate frame
  double principal_point_y_mm = 0.0;   // mm; yp
};

class CameraModel {
 public:
  // Throws platemeter::Error("camera model", why) if the principal distance is not
  // positive or params has the wrong length for the model.
  CameraModel(const InteriorOrientation& interior, DistortionModelId model,
              std::vector<double> params);

  const InteriorOrientation& interior() const { return interior_; }
  DistortionModelId model() const { return model_; }
  const std::vector<double>& params() const { return params_; }

  // Image point (mm) of a direction given in the object frame, seen by a camera
  // whose rotation is `image_from_object`. Returns nullopt if the direction is not
  // in front of the camera or the distortion inverse does not converge.
  std::optional<Eigen::Vector2d> ProjectDirection(const Eigen::Matrix3d& image_from_object,
                                                  const Eigen::Vector3d& direction_in_object) const;
  // Unit direction in the object frame of the ray through a measured image point.
  // Returns nullopt only if the distortion inverse does not converge.
  std::optional<Eigen::Vector3d> DirectionFromImage(const Eigen::Matrix3d& image_from_object,
                                                    const Eigen::Vector2d& point_mm) const;

  // Ideal (distortion-free) image coordinates relative to the principal point from
  // measured plate coordinates, and back. nullopt if an iteration fails.
  std::optional<Eigen::Vector2d> IdealFromMeasured(const Eigen::Vector2d& point_mm) const;
  std::optional<Eigen::Vector2d> MeasuredFromIdeal(const Eigen::Vector2d& ideal_mm) const;

 private:
  InteriorOrientation interior_;
  DistortionModelId model_;
  std::vector<double> params_;
};

// Builds the camera model of a published lens calibration
// (grids/definitions.h LensCalibration; coefficient keys as grids/lens_models.h
// lists them). Converts the published units to the models' units: seed 001's
// xs_um, ys_um become mm relative to the principal point, Phi_T_deg radians.
// Throws platemeter::Error(subject, reason) for an unknown model name or a
// missing, unknown or non-finite coefficient. `subject` names the definition in
// messages (e.g. the camera name).
CameraModel CameraModelFromLensCalibration(const LensCalibration& lens,
                                           const std::string& subject = "lens calibration");

// ---------------------------------------------------------------------------
// Templated forms for the adjustments (automatic differentiation).
// interior = {c_mm, xp_mm, yp_mm}; rotation = image_from_object, row-major 3x3;
// direction = 3 object-frame components (need not be unit).

// Ideal image point relative to the principal point (right side of eq. 1).
// Returns false if the direction is not in front of the camera.
template <typename T>
bool IdealFromDirectionT(const T* interior, const T* rotation, const T* direction, T* x_mm,
                         T* y_mm) {
  const T u = rotation[0] * direction[0] + rotation[1] * direction[1] + rotation[2] * direction[2];
  const T v = rotation[3] * direction[0] + rotation[4] * direction[1] + rotation[5] * direction[2];
  const T w = rotation[6] * direction[0] + rotation[7] * direction[1] + rotation[8] * direction[2];
  if (!(distortion_internal::ScalarPart(w) > 0.0)) return false;
  *x_mm = interior[0] * u / w;
  *y_mm = interior[0] * v / w;
  return true;
}

// Measured plate coordinates of a direction (forward model for the simulator and
// for adjustments written in the "predicted minus measured" form).
template <typename Model, typename T>
bool ProjectDirectionT(const T* interior, const T* distortion, const T* rotation,
                       const T* direction, T* x_mm, T* y_mm,
                       const DistortionInverseOptions& options = {}) {
  T xi, yi;
  if (!IdealFromDirectionT(interior, rotation, direction, &xi, &yi)) return false;
  T xb, yb;
  if (!MeasuredFromIdeal<Model>(distortion, xi, yi, &xb, &yb, options)) return false;
  *x_mm = xb + interior[1];
  *y_mm = yb + interior[2];
  return true;
}

// Residual of eq. (1) as the seed writes it (no inverse needed for kCorrection
// models): corrected measurement minus central projection, mm.
template <typename Model, typename T>
bool CollinearityResidualT(const T* interior, const T* distortion, const T* rotation,
                           const T* direction, const T& x_mm, const T& y_mm, T* residual_mm,
                           const DistortionInverseOptions& options = {}) {
  T xi, yi;
  if (!IdealFromDirectionT(interior, rotation, direction, &xi, &yi)) return false;
  T cx, cy;
  if (!IdealFromMeasured<Model>(distortion, x_mm - interior[1], y_mm - interior[2], &cx, &cy,
                                options)) {
    return false;
  }
  residual_mm[0] = cx - xi;
  residual_mm[1] = cy - yi;
  return true;
}

}  // namespace platemeter
