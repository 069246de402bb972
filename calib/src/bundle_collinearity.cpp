// Seed 000 eq. (1) with analytic Jacobians (bundle_collinearity.h).
//
// Residual before the slope (the "ideal plane"), with xb = x - xp, yb = y - yp,
// d = point - station, (u, v, w) = T d:
//   ip = (xb + dx(xb, yb) - c u / w,  yb + dy(xb, yb) - c v / w)
// and the residual r = S^-1 ip with S = I + d(dx, dy)/d(xb, yb) taken on the
// values (a weight), so dr = S^-1 dip.
#include "bundle_collinearity.h"

#include <cmath>
#include <cstring>
#include <vector>

#include "bundle_equations.h"
#include "platemeter/calib/camera_model.h"

namespace platemeter::bundle_internal {
namespace {

// Seed 000's T (rotations.h TMatrixT, the same expressions, so the same bits)
// and its derivatives by phi, omega and kappa; all row-major 3x3.
struct RotationAndDerivatives {
  double t[9];
  double by_angle[3][9];  // dT/dphi, dT/domega, dT/dkappa
};

void ComputeRotation(double phi, double omega, double kappa, RotationAndDerivatives* r) {
  const double cw = std::cos(omega), sw = std::sin(omega);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double ck = std::cos(kappa), sk = std::sin(kappa);
  double* m = r->t;
  m[0] = cp * ck;
  m[1] = cw * sk - sw * sp * ck;
  m[2] = sw * sk + cw * sp * ck;
  m[3] = -cp * sk;
  m[4] = cw * ck + sw * sp * sk;
  m[5] = sw * ck - cw * sp * sk;
  m[6] = -sp;
  m[7] = -sw * cp;
  m[8] = cw * cp;
  double* p = r->by_angle[0];  // d/dphi: cp -> -sp, sp -> cp
  p[0] = -sp * ck;
  p[1] = -sw * cp * ck;
  p[2] = cw * cp * ck;
  p[3] = sp * sk;
  p[4] = sw * cp * sk;
  p[5] = -cw * cp * sk;
  p[6] = -cp;
  p[7] = sw * sp;
  p[8] = -cw * sp;
  double* o = r->by_angle[1];  // d/domega: cw -> -sw, sw -> cw
  o[0] = 0.0;
  o[1] = -sw * sk - cw * sp * ck;
  o[2] = cw * sk - sw * sp * ck;
  o[3] = 0.0;
  o[4] = -sw * ck + cw * sp * sk;
  o[5] = cw * ck + sw * sp * sk;
  o[6] = 0.0;
  o[7] = -cw * cp;
  o[8] = -sw * cp;
  double* k = r->by_angle[2];  // d/dkappa: ck -> -sk, sk -> ck
  k[0] = -cp * sk;
  k[1] = cw * ck + sw * sp * sk;
  k[2] = sw * ck - cw * sp * sk;
  k[3] = -cp * ck;
  k[4] = -cw * sk + sw * sp * ck;
  k[5] = -sw * sk - cw * sp * ck;
  k[6] = 0.0;
  k[7] = 0.0;
  k[8] = 0.0;
}

// T and its derivatives depend on the frame's three angles only, yet every
// observation of the frame needs them: their sines and cosines were most of
// the equation's cost (a 200-frame block evaluates 400 000 observations per
// pass). Each thread keeps the last ones of every frame in a table indexed by
// the frame's slot and keyed by the angles' bits: no locking while Ceres
// evaluates residual blocks in parallel, and never stale (an entry is used
// only for bit-identical angles, which give the identical matrices). The
// reference is valid until the thread's next call.
const RotationAndDerivatives& RotationOf(int frame_slot, const double* angles) {
  struct Entry {
    bool valid = false;
    double angles[3];
    RotationAndDerivatives rotation;
  };
  constexpr int kMaxEntries = 4096;  // 1.3 MB per thread at most; larger blocks share entries
  thread_local std::vector<Entry> table;
  const size_t index = static_cast<size_t>(frame_slot) % kMaxEntries;
  if (index >= table.size()) table.resize(index + 1);
  Entry& entry = table[index];
  if (!entry.valid || std::memcmp(entry.angles, angles, sizeof(entry.angles)) != 0) {
    ComputeRotation(angles[0], angles[1], angles[2], &entry.rotation);
    std::memcpy(entry.angles, angles, sizeof(entry.angles));
    entry.valid = true;
  }
  return entry.rotation;
}

// Rows of d(ip)/d(parameters): camera 10, frame 6, point 3, one row per component.
struct IdealPlaneGradient {
  double camera[2][10];
  double frame[2][6];
  double point[2][3];
};

// The inner cone's part: the BrownAffine correction (distortion_models.h)
// differentiated by xb, yb (through xp, yp) and by its seven parameters.
void CameraGradient(const double* camera, double x_mm, double y_mm, double u_over_w, double v_over_w,
                    IdealPlaneGradient* g) {
  const double k1 = camera[3], k2 = camera[4], k3 = camera[5], p1 = camera[6], p2 = camera[7];
  const double b1 = camera[8], b2 = camera[9];
  const double xb = x_mm - camera[1];
  const double yb = y_mm - camera[2];
  const double r2 = xb * xb + yb * yb;
  const double r4 = r2 * r2;
  const double radial = r2 * (k1 + r2 * (k2 + r2 * k3));  // dx = xb radial + ..., dy = yb radial + ...
  const double radial_by_r2 = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
  const double xy = xb * yb;
  // Slope of the correction in xb, yb.
  const double dx_by_xb = radial + 2.0 * xb * xb * radial_by_r2 + 6.0 * p1 * xb + 2.0 * p2 * yb + b1;
  const double dx_by_yb = 2.0 * xy * radial_by_r2 + 2.0 * p1 * yb + 2.0 * p2 * xb + b2;
  const double dy_by_xb = 2.0 * xy * radial_by_r2 + 2.0 * p1 * yb + 2.0 * p2 * xb;
  const double dy_by_yb = radial + 2.0 * yb * yb * radial_by_r2 + 2.0 * p1 * xb + 6.0 * p2 * yb;
  double* gx = g->camera[0];
  double* gy = g->camera[1];
  gx[0] = -u_over_w;
  gy[0] = -v_over_w;
  gx[1] = -(1.0 + dx_by_xb);  // xb = x - xp
  gy[1] = -dy_by_xb;
  gx[2] = -dx_by_yb;
  gy[2] = -(1.0 + dy_by_yb);
  gx[3] = xb * r2, gy[3] = yb * r2;
  gx[4] = xb * r4, gy[4] = yb * r4;
  gx[5] = xb * r4 * r2, gy[5] = yb * r4 * r2;
  gx[6] = r2 + 2.0 * xb * xb, gy[6] = 2.0 * xy;
  gx[7] = 2.0 * xy, gy[7] = r2 + 2.0 * yb * yb;
  gx[8] = xb, gy[8] = 0.0;
  gx[9] = yb, gy[9] = 0.0;
}

// The central projection's part: ip = ... - c (u, v) / w.
void ProjectionGradient(double c, const RotationAndDerivatives& rotation, const double* direction, double u,
                        double v, double w, IdealPlaneGradient* g) {
  const double* t = rotation.t;
  const double x = c * u / w, y = c * v / w;  // the ideal point
  for (int k = 0; k < 3; ++k) {
    // d(c u / w)/d direction_k = (c T0k - x T2k) / w; the station enters as -direction.
    const double by_direction_x = (c * t[k] - x * t[6 + k]) / w;
    const double by_direction_y = (c * t[3 + k] - y * t[6 + k]) / w;
    g->point[0][k] = -by_direction_x;
    g->point[1][k] = -by_direction_y;
    g->frame[0][k] = by_direction_x;
    g->frame[1][k] = by_direction_y;
  }
  for (int a = 0; a < 3; ++a) {
    const double* m = rotation.by_angle[a];
    const double du = m[0] * direction[0] + m[1] * direction[1] + m[2] * direction[2];
    const double dv = m[3] * direction[0] + m[4] * direction[1] + m[5] * direction[2];
    const double dw = m[6] * direction[0] + m[7] * direction[1] + m[8] * direction[2];
    g->frame[0][3 + a] = -(c * du - x * dw) / w;
    g->frame[1][3 + a] = -(c * dv - y * dw) / w;
  }
}

// One block's rows of d(residual) = S^-1 d(ip), row-major (Ceres' layout).
template <int kSize>
void WriteJacobian(const double (&gradient)[2][kSize], const double* slope_inverse, double* jacobian) {
  if (jacobian == nullptr) return;
  for (int k = 0; k < kSize; ++k) {
    jacobian[k] = slope_inverse[0] * gradient[0][k] + slope_inverse[1] * gradient[1][k];
    jacobian[kSize + k] = slope_inverse[2] * gradient[0][k] + slope_inverse[3] * gradient[1][k];
  }
}

}  // namespace

bool CollinearityCost::Evaluate(double const* const* parameters, double* residuals_mm, double** jacobians) const {
  const double* camera = parameters[0];
  const double* frame = parameters[1];
  const double* point = parameters[2];
  const RotationAndDerivatives& rotation = RotationOf(frame_slot_, frame + 3);
  const double direction[3] = {point[0] - frame[0], point[1] - frame[1], point[2] - frame[2]};
  // The residual as CollinearityEquation computes it, operation for operation.
  double ideal_plane[2];
  if (!CollinearityResidualT<BrownAffine>(camera, camera + 3, rotation.t, direction, x_mm_, y_mm_, ideal_plane)) {
    return false;
  }
  double j[4];
  CorrectionSlope(camera, x_mm_, y_mm_, j);
  const double det = j[0] * j[3] - j[1] * j[2];
  residuals_mm[0] = (j[3] * ideal_plane[0] - j[1] * ideal_plane[1]) / det;
  residuals_mm[1] = (-j[2] * ideal_plane[0] + j[0] * ideal_plane[1]) / det;
  if (jacobians == nullptr) return true;

  const double* t = rotation.t;
  const double u = t[0] * direction[0] + t[1] * direction[1] + t[2] * direction[2];
  const double v = t[3] * direction[0] + t[4] * direction[1] + t[5] * direction[2];
  const double w = t[6] * direction[0] + t[7] * direction[1] + t[8] * direction[2];
  IdealPlaneGradient gradient;
  CameraGradient(camera, x_mm_, y_mm_, u / w, v / w, &gradient);
  ProjectionGradient(camera[0], rotation, direction, u, v, w, &gradient);
  const double slope_inverse[4] = {j[3] / det, -j[1] / det, -j[2] / det, j[0] / det};
  WriteJacobian(gradient.camera, slope_inverse, jacobians[0]);
  WriteJacobian(gradient.frame, slope_inverse, jacobians[1]);
  WriteJacobian(gradient.point, slope_inverse, jacobians[2]);
  return true;
}

}  // namespace platemeter::bundle_internal
