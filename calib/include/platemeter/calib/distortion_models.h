#pragma once
// Lens distortion models of the seeds, as small structs (DESIGN.md "Shape of an
// algorithm"): kNumParams, Name(), the parameter order with units, and a
// templated Apply<T>() that works with double and with ceres::Jet (automatic
// differentiation). Every model takes image coordinates in millimetres
// relative to the principal point (x right, y up) and returns a shift in mm.
//
// Direction. Each model states which way its published formula goes:
//   kCorrection: Apply gives the correction ADDED TO MEASURED coordinates to
//                obtain ideal (distortion-free, central-perspective) ones:
//                ideal = measured + Apply(measured). Seeds 000 (eq. 1) and 004
//                ("corrections added to the image coordinates") are written so.
//   kDistortion: Apply gives the distortion ADDED TO IDEAL coordinates to obtain
//                measured ones: measured = ideal + Apply(ideal). Seed 001
//                (Slama's model gives the measured x*, y* from the true image).
// IdealFromMeasured / MeasuredFromIdeal below use the closed form where the
// model's direction allows and a Newton iteration (with a convergence check)
// otherwise, so callers never care which way a model was published.
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace platemeter {

enum class DistortionDirection { kCorrection, kDistortion };

// ---------------------------------------------------------------------------
// Seed 004 (Lunar Mapping Camera SN-004, SMAC): equations before Table A.4.
//   dx = x (K1 r^2 + K2 r^4 + K3 r^6)
//        - (J1 r^2 + J2 r^4) [ (1 + 2 x^2/r^2) sin(theta0) - 2 x y / r^2 cos(theta0) ]
//   dy = y (K1 r^2 + K2 r^4 + K3 r^6)
//        + (J1 r^2 + J2 r^4) [ (1 + 2 y^2/r^2) cos(theta0) - 2 x y / r^2 sin(theta0) ]
// "dx and dy are the corrections added to the image coordinates" -> kCorrection.
// The decentering bracket is multiplied out with r^2 so that it is smooth at r = 0;
// it equals Brown's p1 = -J1 sin(theta0), p2 = J1 cos(theta0), so theta0 is
// Brown's decentering phase angle phi0 (seed 000 eq. 16).
// Parameters: K1 [1/mm^2], K2 [1/mm^4], K3 [1/mm^6], J1 [1/mm], J2 [1/mm^3], theta0 [rad].
struct SmacRadialDecentering {
  static constexpr int kNumParams = 6;
  static constexpr DistortionDirection kDirection = DistortionDirection::kCorrection;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "K1_per_mm2", "K2_per_mm4", "K3_per_mm6", "J1_per_mm", "J2_per_mm3", "theta0_rad"};
  static const char* Name() { return "smac-radial-decentering"; }

  template <typename T>
  static void Apply(const T* params, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
    using std::cos;
    using std::sin;
    const T r2 = x_mm * x_mm + y_mm * y_mm;
    const T radial = r2 * (params[0] + r2 * (params[1] + r2 * params[2]));
    const T profile = params[3] + params[4] * r2;  // (J1 r^2 + J2 r^4) / r^2
    const T s = sin(params[5]);
    const T c = cos(params[5]);
    const T two_xy = T(2.0) * x_mm * y_mm;
    *dx_mm = x_mm * radial - profile * ((r2 + T(2.0) * x_mm * x_mm) * s - two_xy * c);
    *dy_mm = y_mm * radial + profile * ((r2 + T(2.0) * y_mm * y_mm) * c - two_xy * s);
  }
};

// ---------------------------------------------------------------------------
// Seed 000 (Apollo 14 Hasselblad), eq. (1): Brown's model with Gaussian radial
// coefficients. The left side of eq. (1) is x - xp + dx with
//   dx = xb (k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 xb^2) + 2 p2 xb yb
//   dy = yb (k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 xb yb + p2 (r^2 + 2 yb^2)
// (xb = x - xp, yb = y - yp), equated to the central projection -> kCorrection.
// Parameters: k1 [1/mm^2], k2 [1/mm^4], k3 [1/mm^6], p1 [1/mm], p2 [1/mm].
struct BrownConrady {
  static constexpr int kNumParams = 5;
  static constexpr DistortionDirection kDirection = DistortionDirection::kCorrection;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "k1_per_mm2", "k2_per_mm4", "k3_per_mm6", "p1_per_mm", "p2_per_mm"};
  static const char* Name() { return "brown-conrady"; }

  template <typename T>
  static void Apply(const T* params, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
    const T r2 = x_mm * x_mm + y_mm * y_mm;
    const T radial = r2 * (params[0] + r2 * (params[1] + r2 * params[2]));
    const T two_xy = T(2.0) * x_mm * y_mm;
    *dx_mm = x_mm * radial + params[3] * (r2 + T(2.0) * x_mm * x_mm) + params[4] * two_xy;
    *dy_mm = y_mm * radial + params[3] * two_xy + params[4] * (r2 + T(2.0) * y_mm * y_mm);
  }
};

// ---------------------------------------------------------------------------
// Seed 000 eq. (1) with an affinity of the image frame: Brown's correction plus
//   dx += b1 xb + b2 yb      (dy unchanged)
// b1 absorbs a different scale of x and y (seed 001's Cx != Cy: a measured x
// that is (1 + s) times the ideal one is corrected by b1 = -s), b2 a
// non-orthogonality of the axes (seed 001's epsilon: x* = x - y epsilon is
// corrected by b2 = +epsilon). kCorrection, like BrownConrady. The bundle
// adjustment's camera: c, xp, yp (InteriorOrientation) and these seven.
// Parameters: k1 [1/mm^2], k2 [1/mm^4], k3 [1/mm^6], p1 [1/mm], p2 [1/mm], b1 [-], b2 [-].
struct BrownAffine {
  static constexpr int kNumParams = 7;
  static constexpr DistortionDirection kDirection = DistortionDirection::kCorrection;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "k1_per_mm2", "k2_per_mm4", "k3_per_mm6", "p1_per_mm", "p2_per_mm", "b1", "b2"};
  static const char* Name() { return "brown-affine"; }

  template <typename T>
  static void Apply(const T* params, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
    BrownConrady::Apply(params, x_mm, y_mm, dx_mm, dy_mm);
    *dx_mm += params[5] * x_mm + params[6] * y_mm;
  }
};

// ---------------------------------------------------------------------------
// Seed 000, eq. (14)-(15) and Tables 1, 3, 6: the "balanced" form that goes with
// the calibrated focal length c'. The radial function
//   delta_r' = k0' r + k1' r^3 + k2' r^5            (mm; eq. 14 with Table 6's k2')
// replaces the Gaussian k1 r^3 + ... of eq. (1): a Gaussian function re-expressed
// for c' = c (1 + k0') has k0' as its linear term, so it enters eq. (1) the same
// way: dx = xb delta_r'/r + decentering (kCorrection, like BrownConrady).
// The seed calls delta_r' "distortion ... positive when directed away from the
// principal point"; we keep eq. (1)'s sign (the term added to the measured
// coordinates), which is how c', k0', k1' are used in the adjustment that
// produced them. The profile values of Tables 2, 4 and 7 do not depend on this.
// Parameters: k0' [-], k1' [1/mm^2], k2' [1/mm^4], p1 [1/mm], p2 [1/mm].
struct BrownBalanced {
  static constexpr int kNumParams = 5;
  static constexpr DistortionDirection kDirection = DistortionDirection::kCorrection;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "k0", "k1_per_mm2", "k2_per_mm4", "p1_per_mm", "p2_per_mm"};
  static const char* Name() { return "brown-balanced"; }

  template <typename T>
  static void Apply(const T* params, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
    const T r2 = x_mm * x_mm + y_mm * y_mm;
    const T radial = params[0] + r2 * (params[1] + r2 * params[2]);  // delta_r' / r
    const T two_xy = T(2.0) * x_mm * y_mm;
    *dx_mm = x_mm * radial + params[3] * (r2 + T(2.0) * x_mm * x_mm) + params[4] * two_xy;
    *dy_mm = y_mm * radial + params[3] * two_xy + params[4] * (r2 + T(2.0) * y_mm * y_mm);
  }
};

// ---------------------------------------------------------------------------
// Seed 001 (Orbigon, Slama 1972): the lens part of the 11-parameter model.
//   dR = K1 d^3 + K2 d^5 + K3 d^7,  d = distance of the TRUE image from the
//   point of symmetry (xs, ys); dx = x - xs, dy = y - ys;
//   x* = x + dx (dR/d + Dx),  y* = y + dy (dR/d + Dy), with
//   dx Dx = (K4 + K5 d^2) ((3 dx^2 + dy^2) cos(Phi_T) + 2 dx dy sin(Phi_T))
//   dy Dy = (K4 + K5 d^2) ((3 dy^2 + dx^2) sin(Phi_T) + 2 dx dy cos(Phi_T))
// x*, y* are the measured coordinates -> kDistortion (ideal -> measured).
// (The seed writes (C m/q + xp)(1 + dR/d + Dx) - xs (dR/d + Dx), which is the same;
// the per-plate scalars Cx, Cy and the non-orthogonality epsilon are in
// SlamaImageEquation below.)
//
// Units. The paper prints K1..K5 without units. Only d and dR in METRES make the
// three radial terms comparable over the 80 mm half-diagonal (combined solution,
// Table 3, at d = 0.08 m: +187, -361, +200 um) and reproduce the abstract: the
// radial distortion at the primary focal length reaches ~27 um at the corner, and
// after the equal-area transformation to another focal length (Fig. 8) it stays
// within about 4 um (4.3 um over 0..57 mm or 0..80.6 mm; the abstract says
// 4.1 um); the decentering profile (K4 + K5 d^2) d^2 is 3.07 um at d = 57 mm, the
// half side of the format (abstract: "does not exceed 3.0 um"). With d in mm or cm the terms differ by orders of magnitude. So
// K1 [1/m^2], K2 [1/m^4], K3 [1/m^6], K4 [1/m], K5 [1/m^3], as printed.
// Parameters: xs [mm], ys [mm] (point of symmetry RELATIVE TO THE PRINCIPAL POINT;
// the paper gives it in um from the reseau centre: subtract xp, yp),
// K1 [1/m^2], K2 [1/m^4], K3 [1/m^6], K4 [1/m], K5 [1/m^3], Phi_T [rad].
struct SlamaDistortion {
  static constexpr int kNumParams = 8;
  static constexpr DistortionDirection kDirection = DistortionDirection::kDistortion;
  static constexpr std::array<const char*, kNumParams> kParamNames = {
      "xs_mm", "ys_mm", "K1_per_m2", "K2_per_m4", "K3_per_m6", "K4_per_m", "K5_per_m3", "Phi_T_rad"};
  static const char* Name() { return "orbigon-11"; }

  template <typename T>
  static void Apply(const T* params, const T& x_mm, const T& y_mm, T* dx_mm, T* dy_mm) {
    using std::cos;
    using std::sin;
    // Work in metres, the unit of the published coefficients.
    const T dx = (x_mm - params[0]) * T(1e-3);
    const T dy = (y_mm - params[1]) * T(1e-3);
    const T d2 = dx * dx + dy * dy;
    const T radial = d2 * (params[2] + d2 * (params[3] + d2 * params[4]));  // dR / d
    const T profile = params[5] + params[6] * d2;
    const T c = cos(params[7]);
    const T s = sin(params[7]);
    const T two_dxdy = T(2.0) * dx * dy;
    const T ex = dx * radial + profile * ((T(3.0) * dx * dx + dy * dy) * c + two_dxdy * s);
    const T ey = dy * radial + profile * ((T(3.0) * dy * dy + dx * dx) * s + two_dxdy * c);
    *dx_mm = ex * T(1e3);
    *dy_mm = ey * T(1e3);
  }
};
using Orbigon11 = SlamaDistortion;

// Seed 001's complete image equation for one star: measured plate coordinates
// (mm, relative to the reseau origin) from the rotated direction (m, n, q) = M (X, Y, Z):
//   x_i = Cx m/q + xp,  y_i = Cy n/q + yp          (true image)
//   x* = x_i + [lens distortion]_x - y_i epsilon,  y* = y_i + [lens distortion]_y
// cx_mm, cy_mm: per-plate principal distances (the "differential scalars"),
// epsilon_rad: non-orthogonality of the axes, slama: SlamaDistortion parameters.
template <typename T>
void SlamaImageEquation(const T* slama, const T& cx_mm, const T& cy_mm, const T& xp_mm,
                        const T& yp_mm, const T& epsilon_rad, const T& m, const T& n,
                        const T& q, T* x_mm, T* y_mm) {
  const T xb = cx_mm * m / q;  // true image relative to the principal point
  const T yb = cy_mm * n / q;
  T ex, ey;
  SlamaDistortion::Apply(slama, xb, yb, &ex, &ey);
  *x_mm = xb + xp_mm + ex - (yb + yp_mm) * epsilon_rad;
  *y_mm = yb + yp_mm + ey;
}

// ---------------------------------------------------------------------------
// Profile functions of seed 000 (non-templated; reports and tests).
// eq. (14): balanced radial distortion delta_r' = k0 r + k1 r^3 + k2 r^5 [mm].
double BalancedRadialDistortion_mm(double k0, double k1_per_mm2, double k2_per_mm4, double r_mm);
// eq. (15): profile of maximum tangential distortion P_r = sqrt(p1^2 + p2^2) r^2 [mm].
double DecenteringProfile_mm(double p1_per_mm, double p2_per_mm, double r_mm);
// eq. (16): decentering phase angle phi0 = atan(-p1 / p2), measured from +x toward +y,
// taken in the quadrant of (-p1, p2) (atan2), which is what Table 8 prints
// (Table 3's p1 > 0, p2 < 0 gives -92 deg, not +88 deg).
double DecenteringPhaseAngle_rad(double p1_per_mm, double p2_per_mm);

// ---------------------------------------------------------------------------
// The generic inverse.
struct DistortionInverseOptions {
  double tolerance_mm = 1e-12;     // mm; stop when the Newton step is below this
  int max_iterations = 50;         // give up (return false) after this many steps
  double jacobian_step_mm = 1e-4;  // mm; central-difference step for the 2x2 Jacobian
  bool Check(std::string* why) const;
};

namespace distortion_internal {

// The value part of a double or a ceres::Jet (member `a`), without naming Ceres.
template <typename T>
double ScalarPart(const T& v) {
  if constexpr (requires { v.a; }) {
    return ScalarPart(v.a);
  } else {
    return static_cast<double>(v);
  }
}

// Solves u + Apply(u) = target for u by Newton's method: the 2x2 Jacobian of the
// map is taken by central differences on the value parts and held fixed for the
// step, so that for Jets the derivative parts converge with the values (the
// iteration matrix at the solution is ~0). Two more steps after convergence
// settle the derivative parts. A root on a folded branch (an eigenvalue of the
// Jacobian with non-positive real part) is rejected: returns false.
template <typename Model, typename T>
bool SolveForward(const T* params, const T& target_x, const T& target_y, T* u_x, T* u_y,
                  const DistortionInverseOptions& options) {
  std::array<double, (Model::kNumParams > 0 ? Model::kNumParams : 1)> p{};
  for (int i = 0; i < Model::kNumParams; ++i) p[i] = ScalarPart(params[i]);
  T ux = target_x;
  T uy = target_y;
  int settle = 0;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const double x0 = ScalarPart(ux);
    const double y0 = ScalarPart(uy);
    if (!std::isfinite(x0) || !std::isfinite(y0)) return false;
    const double h = options.jacobian_step_mm;
    double ax, ay, bx, by, cx, cy, ex, ey;
    Model::Apply(p.data(), x0 + h, y0, &ax, &ay);
    Model::Apply(p.data(), x0 - h, y0, &bx, &by);
    Model::Apply(p.data(), x0, y0 + h, &cx, &cy);
    Model::Apply(p.data(), x0, y0 - h, &ex, &ey);
    const double j11 = 1.0 + (ax - bx) / (2 * h), j21 = (ay - by) / (2 * h);
    const double j12 = (cx - ex) / (2 * h), j22 = 1.0 + (cy - ey) / (2 * h);
    const double det = j11 * j22 - j12 * j21;
    if (!(std::abs(det) > 1e-12)) return false;
    T fx, fy;
    Model::Apply(params, ux, uy, &fx, &fy);
    const T rx = ux + fx - target_x;
    const T ry = uy + fy - target_y;
    const T step_x = (j22 * rx - j12 * ry) / det;
    const T step_y = (-j21 * rx + j11 * ry) / det;
    ux = ux - step_x;
    uy = uy - step_y;
    const double step = std::hypot(ScalarPart(step_x), ScalarPart(step_y));
    if (step <= options.tolerance_mm) {
      // A root where the map folds over is not the inverse: the physical branch
      // is the one connected to the identity, where both eigenvalues of the
      // Jacobian have positive real parts (det > 0 and trace > 0).
      if (!(det > 0.0) || !(j11 + j22 > 0.0)) return false;
      if (++settle >= 2) {
        *u_x = ux;
        *u_y = uy;
        return true;
      }
    }
  }
  return false;
}

}  // namespace distortion_internal

// Ideal (distortion-free) coordinates from measured ones, both in mm relative to
// the principal point. Returns false if the iteration (kDistortion models) fails.
template <typename Model, typename T>
bool IdealFromMeasured(const T* params, const T& x_mm, const T& y_mm, T* ideal_x_mm,
                       T* ideal_y_mm, const DistortionInverseOptions& options = {}) {
  if constexpr (Model::kNumParams == 0) {
    *ideal_x_mm = x_mm;
    *ideal_y_mm = y_mm;
    return true;
  } else if constexpr (Model::kDirection == DistortionDirection::kCorrection) {
    T dx, dy;
    Model::Apply(params, x_mm, y_mm, &dx, &dy);
    *ideal_x_mm = x_mm + dx;
    *ideal_y_mm = y_mm + dy;
    return true;
  } else {
    return distortion_internal::SolveForward<Model>(params, x_mm, y_mm, ideal_x_mm, ideal_y_mm,
                                                    options);
  }
}

// Measured coordinates from ideal ones (the inverse of IdealFromMeasured).
template <typename Model, typename T>
bool MeasuredFromIdeal(const T* params, const T& x_mm, const T& y_mm, T* measured_x_mm,
                       T* measured_y_mm, const DistortionInverseOptions& options = {}) {
  if constexpr (Model::kNumParams == 0) {
    *measured_x_mm = x_mm;
    *measured_y_mm = y_mm;
    return true;
  } else if constexpr (Model::kDirection == DistortionDirection::kDistortion) {
    T dx, dy;
    Model::Apply(params, x_mm, y_mm, &dx, &dy);
    *measured_x_mm = x_mm + dx;
    *measured_y_mm = y_mm + dy;
    return true;
  } else {
    return distortion_internal::SolveForward<Model>(params, x_mm, y_mm, measured_x_mm,
                                                    measured_y_mm, options);
  }
}

// ---------------------------------------------------------------------------
// Run-time choice of a model (camera definitions name it by string).
enum class DistortionModelId {
  kNone,
  kSmacRadialDecentering,
  kBrownConrady,
  kBrownBalanced,
  kSlama,
  kBrownAffine
};

// The identity model (no distortion), so that a camera without a lens
// calibration goes through the same code.
struct NoDistortion {
  static constexpr int kNumParams = 0;
  static constexpr DistortionDirection kDirection = DistortionDirection::kCorrection;
  static constexpr std::array<const char*, 0> kParamNames = {};
  static const char* Name() { return "none"; }
  template <typename T>
  static void Apply(const T* /*params*/, const T& /*x_mm*/, const T& /*y_mm*/, T* dx_mm,
                    T* dy_mm) {
    *dx_mm = T(0.0);
    *dy_mm = T(0.0);
  }
};

const char* DistortionModelName(DistortionModelId id);
int DistortionModelNumParams(DistortionModelId id);
std::vector<std::string> DistortionModelParamNames(DistortionModelId id);
// Accepts the names returned by Name() ("none", "smac-radial-decentering",
// "brown-conrady", "brown-balanced", "orbigon-11", "brown-affine"); false otherwise.
bool ParseDistortionModel(const std::string& name, DistortionModelId* id);

// Calls f(Model{}) with the struct for `id`, e.g. to build an AutoDiffCostFunction
// with the right parameter block size:
//   VisitDistortionModel(id, [&](auto model) { using M = decltype(model); ... });
template <typename F>
decltype(auto) VisitDistortionModel(DistortionModelId id, F&& f) {
  switch (id) {
    case DistortionModelId::kSmacRadialDecentering: return f(SmacRadialDecentering{});
    case DistortionModelId::kBrownConrady: return f(BrownConrady{});
    case DistortionModelId::kBrownBalanced: return f(BrownBalanced{});
    case DistortionModelId::kSlama: return f(SlamaDistortion{});
    case DistortionModelId::kBrownAffine: return f(BrownAffine{});
    case DistortionModelId::kNone: break;
  }
  return f(NoDistortion{});
}

}  // namespace platemeter
