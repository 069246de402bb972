// Seed 000's distortion products with first-order sigmas (distortion_profile.h
// has the formulas and the propagation).
#include "platemeter/calib/distortion_profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <ceres/jet.h>
#include <fmt/format.h>

#include <Eigen/Dense>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

constexpr int kMaxDim = 9;  // c plus brown-affine's 7 parameters, with room
using Jet = ceres::Jet<double, kMaxDim>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// g(r) = 1 + a0 + a1 r^2 + a2 r^4 + a3 r^6: the scale of the measured point.
template <typename T>
T RadialScale(const GeneralLens<T>& g, double r_mm) {
  const double r2 = r_mm * r_mm;
  return T(1.0) + g.a[0] + r2 * (g.a[1] + r2 * (g.a[2] + r2 * g.a[3]));
}

// delta(r; lambda) = lambda r g(r) - r: the balanced radial function for the scale lambda.
double BalancedRadial(const GeneralLens<double>& g, double lambda, double r_mm) {
  return r_mm * (lambda * RadialScale(g, r_mm) - 1.0);
}

struct Extremes {
  double r_max_mm = 0.0, value_max = 0.0;  // the largest delta and where
  double r_min_mm = 0.0, value_min = 0.0;  // the smallest delta and where
};

// Golden-section search for an extremum of f on [lo, hi] (sign = +1 maximum, -1 minimum).
template <typename F>
double GoldenSection(const F& f, double lo, double hi, double sign) {
  const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = lo, b = hi;
  double c = b - inv_phi * (b - a), d = a + inv_phi * (b - a);
  double fc = sign * f(c), fd = sign * f(d);
  for (int i = 0; i < 200 && (b - a) > 1e-13 * std::max(1.0, hi); ++i) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - inv_phi * (b - a);
      fc = sign * f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + inv_phi * (b - a);
      fd = sign * f(d);
    }
  }
  return 0.5 * (a + b);
}

// The extremes of delta(r; lambda) over [0, M]: dense samples, then refined.
Extremes FindExtremes(const GeneralLens<double>& g, double lambda, double max_radius_mm) {
  constexpr int kSamples = 2000;
  auto f = [&](double r) { return BalancedRadial(g, lambda, r); };
  int k_max = 0, k_min = 0;
  double v_max = f(0.0), v_min = v_max;
  for (int k = 1; k <= kSamples; ++k) {
    const double v = f(max_radius_mm * k / kSamples);
    if (v > v_max) v_max = v, k_max = k;
    if (v < v_min) v_min = v, k_min = k;
  }
  auto refine = [&](int k, double sign) {
    if (k == 0 || k == kSamples) return max_radius_mm * k / kSamples;  // an end of the range
    return GoldenSection(f, max_radius_mm * (k - 1) / kSamples, max_radius_mm * (k + 1) / kSamples, sign);
  };
  Extremes e;
  e.r_max_mm = refine(k_max, +1.0);
  e.value_max = f(e.r_max_mm);
  e.r_min_mm = refine(k_min, -1.0);
  e.value_min = f(e.r_min_mm);
  return e;
}

// The minimax scale: max delta = -min delta over [0, M]. F(lambda) = max + min
// grows with lambda (r g(r) > 0), so bisection between 1/max g (delta <= 0
// everywhere) and 1/min g (delta >= 0 everywhere) finds it.
Extremes MinimaxExtremes(const GeneralLens<double>& g, double max_radius_mm, double* lambda) {
  constexpr int kSamples = 2000;
  double g_min = std::numeric_limits<double>::infinity(), g_max = -g_min;
  for (int k = 0; k <= kSamples; ++k) {
    const double v = RadialScale(g, max_radius_mm * k / kSamples);
    g_min = std::min(g_min, v);
    g_max = std::max(g_max, v);
  }
  if (!(g_min > 0.0)) {
    throw Error("distortion profile", fmt::format("the radial function turns the scale over within {:g} mm "
                                                  "(1 + a0 + a1 r^2 + ... = {:g})",
                                                  max_radius_mm, g_min));
  }
  double lo = 1.0 / g_max, hi = 1.0 / g_min;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;  // adjacent doubles
    const Extremes e = FindExtremes(g, mid, max_radius_mm);
    (e.value_max + e.value_min > 0.0 ? hi : lo) = mid;
  }
  *lambda = 0.5 * (lo + hi);
  return FindExtremes(g, *lambda, max_radius_mm);
}

Eigen::VectorXd Gradient(const Jet& v, int n) { return v.v.head(n); }

ValueWithSigma WithSigma(const Jet& v, const Eigen::MatrixXd& covariance) {
  return {v.a, PropagatedSigma(covariance, Gradient(v, int(covariance.rows())))};
}

// |(u, v)| with its sigma; where it is 0 the sigma along the worst direction.
ValueWithSigma LengthWithSigma(const Jet& u, const Jet& v, const Eigen::MatrixXd& covariance) {
  const int n = int(covariance.rows());
  const double length = std::hypot(u.a, v.a);
  if (length > 0.0) {
    return {length, PropagatedSigma(covariance, (u.a * Gradient(u, n) + v.a * Gradient(v, n)) / length)};
  }
  Eigen::MatrixXd g(2, n);
  g.row(0) = Gradient(u, n).transpose();
  g.row(1) = Gradient(v, n).transpose();
  const Eigen::Matrix2d c2 = g * covariance * g.transpose();
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c2).eigenvalues().maxCoeff();
  return {0.0, std::sqrt(std::max(largest, 0.0))};
}

}  // namespace

const char* RadialBalanceName(RadialBalance balance) {
  switch (balance) {
    case RadialBalance::kAsGiven: return "as-given";
    case RadialBalance::kZeroAtRadius: return "zero-at-radius";
    case RadialBalance::kEqualLobePeaks: return "equal-lobe-peaks";
    case RadialBalance::kEqualLobeAreas: return "equal-lobe-areas";
  }
  return "?";
}

bool DistortionProfileOptions::Check(std::string* why) const {
  if (balance == RadialBalance::kZeroAtRadius && !(balance_radius_mm > 0.0 && std::isfinite(balance_radius_mm))) {
    *why = fmt::format("the balance radius must be > 0 mm (is {})", balance_radius_mm);
    return false;
  }
  if ((balance == RadialBalance::kEqualLobePeaks || balance == RadialBalance::kEqualLobeAreas) &&
      !(max_radius_mm > 0.0 && std::isfinite(max_radius_mm))) {
    *why = fmt::format("the range of the equal lobes must be > 0 mm (is {})", max_radius_mm);
    return false;
  }
  if (radii_mm.empty()) {
    *why = "no radii";
    return false;
  }
  for (double r : radii_mm) {
    if (!(r >= 0.0) || !std::isfinite(r)) {
      *why = fmt::format("a radius must be finite and >= 0 (is {})", r);
      return false;
    }
  }
  return true;
}

double FormatHalfDiagonal_mm(double format_width_mm, double format_height_mm) {
  return 0.5 * std::hypot(format_width_mm, format_height_mm);
}

std::vector<double> DefaultProfileRadii_mm(double format_width_mm, double format_height_mm) {
  const double end = FormatHalfDiagonal_mm(format_width_mm, format_height_mm);
  double step = 50.0;
  for (double candidate : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0}) {
    if (end / candidate <= 10.0) {
      step = candidate;
      break;
    }
  }
  std::vector<double> radii;
  for (int k = 0; k * step < end - 0.05 * step; ++k) radii.push_back(k * step);
  radii.push_back(end);
  return radii;
}

DistortionProfile ComputeDistortionProfile(const LensEstimate& lens, const DistortionProfileOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("distortion profile", why);
  if (!lens.Check(&why)) throw Error("distortion profile", why);
  if (!HasGeneralLensForm(lens.model)) {
    throw Error("distortion profile",
                fmt::format("no profile for lens model {} (seed 001's distortion form about a point of symmetry); "
                            "supported: brown-balanced, brown-conrady, brown-affine, smac-radial-decentering",
                            DistortionModelName(lens.model)));
  }
  const int n = 1 + int(lens.params.size());
  const Eigen::MatrixXd& covariance = lens.covariance;

  std::vector<Jet> x(n);
  for (int i = 0; i < n; ++i) x[i] = Jet(i == 0 ? lens.principal_distance_mm : lens.params[i - 1], i);
  GeneralLens<Jet> g;
  GeneralLensFromModel(lens.model, x[0], x.data() + 1, &g);
  GeneralLens<double> values;
  GeneralLensFromModel(lens.model, lens.principal_distance_mm, lens.params.data(), &values);

  DistortionProfile profile;
  profile.model = lens.model;
  profile.balance = options.balance;
  profile.parameter_names = lens.ParameterNames();

  // The scale lambda of the balance, as a Jet.
  Jet lambda(1.0);
  switch (options.balance) {
    case RadialBalance::kAsGiven:
      break;
    case RadialBalance::kZeroAtRadius: {
      profile.balance_radius_mm = options.balance_radius_mm;
      const Jet scale = RadialScale(g, options.balance_radius_mm);
      if (!(scale.a > 0.0)) {
        throw Error("distortion profile", fmt::format("cannot balance at {:g} mm: 1 + a0 + a1 R^2 + ... = {:g}",
                                                      options.balance_radius_mm, scale.a));
      }
      lambda = Jet(1.0) / scale;
      break;
    }
    case RadialBalance::kEqualLobePeaks: {
      profile.max_radius_mm = options.max_radius_mm;
      double lambda_value = 1.0;
      const Extremes e = MinimaxExtremes(values, options.max_radius_mm, &lambda_value);
      const double r_plus = e.r_max_mm, r_minus = e.r_min_mm;
      if (r_plus == r_minus || r_plus == 0.0 || r_minus == 0.0) {
        // No lobes: delta' = 0 for every r (a1 = a2 = a3 = 0); the scale is 1 / g.
        lambda = Jet(1.0) / RadialScale(g, options.max_radius_mm);
      } else {
        // delta'(r+) + delta'(r-) = 0 with the extremal radii held (envelope theorem).
        lambda = Jet(r_plus + r_minus) / (r_plus * RadialScale(g, r_plus) + r_minus * RadialScale(g, r_minus));
      }
      break;
    }
    case RadialBalance::kEqualLobeAreas: {
      profile.max_radius_mm = options.max_radius_mm;
      const double m = options.max_radius_mm, m2 = m * m;
      // integral_0^M r g(r) dr
      const Jet area = m2 * ((Jet(1.0) + g.a[0]) / 2.0 + m2 * (g.a[1] / 4.0 + m2 * (g.a[2] / 6.0 + m2 * g.a[3] / 8.0)));
      if (!(area.a > 0.0)) {
        throw Error("distortion profile", fmt::format("cannot balance the areas over {:g} mm", m));
      }
      lambda = Jet(m2 / 2.0) / area;
      break;
    }
  }
  const GeneralLens<Jet> balanced = RescaledGeneralLens(g, lambda);
  profile.scale = lambda.a;
  profile.calibrated_focal_length_mm = WithSigma(balanced.c_mm, covariance);
  for (int i = 0; i < 4; ++i) profile.radial_coefficients[i] = WithSigma(balanced.a[i], covariance);

  // Decentering: J1, J2 and phi0 as seed 004 writes them.
  profile.decentering_j1_per_mm = LengthWithSigma(balanced.p[0], balanced.p[1], covariance);
  std::array<Jet, 6> smac;
  ModelFromGeneralLens(DistortionModelId::kSmacRadialDecentering, balanced, smac.data());
  profile.decentering_j2_per_mm3 = WithSigma(smac[4], covariance);
  if (profile.decentering_j1_per_mm.value > 0.0) {
    // atan2(-p1, p2): the quadrant of (-p1, p2) (Table 8: Table 3's p1 > 0, p2 < 0 is -92 deg).
    profile.phase_angle_rad = WithSigma(atan2(-balanced.p[0], balanced.p[1]), covariance);
  } else {
    profile.phase_angle_rad = {kNaN, kNaN};
  }

  for (double r : options.radii_mm) {
    const double r2 = r * r;
    DistortionProfileRow row;
    row.r_mm = r;
    const Jet radial = r * (balanced.a[0] + r2 * (balanced.a[1] + r2 * (balanced.a[2] + r2 * balanced.a[3])));
    const ValueWithSigma radial_mm = WithSigma(radial, covariance);
    row.radial_um = radial_mm.value * 1e3;
    row.radial_sigma_um = radial_mm.sigma * 1e3;
    const ValueWithSigma j = LengthWithSigma(balanced.p[0] + r2 * balanced.p[2], balanced.p[1] + r2 * balanced.p[3],
                                             covariance);
    row.decentering_um = j.value * r2 * 1e3;
    row.decentering_sigma_um = j.sigma * r2 * 1e3;
    profile.rows.push_back(row);
  }

  std::string balance_text;
  switch (options.balance) {
    case RadialBalance::kAsGiven: balance_text = "as given"; break;
    case RadialBalance::kZeroAtRadius: balance_text = fmt::format("balanced to zero at {:g} mm", options.balance_radius_mm); break;
    case RadialBalance::kEqualLobePeaks: balance_text = fmt::format("equal lobe peaks over 0..{:g} mm", options.max_radius_mm); break;
    case RadialBalance::kEqualLobeAreas: balance_text = fmt::format("equal lobe areas over 0..{:g} mm", options.max_radius_mm); break;
  }
  profile.summary = fmt::format("{}, {}: c' = {:.3f} +- {:.3f} mm, phi0 = {:.1f} +- {:.1f} deg, {} radii",
                                DistortionModelName(lens.model), balance_text, profile.calibrated_focal_length_mm.value,
                                profile.calibrated_focal_length_mm.sigma, profile.phase_angle_rad.value * 180.0 / M_PI,
                                profile.phase_angle_rad.sigma * 180.0 / M_PI, profile.rows.size());
  return profile;
}

}  // namespace platemeter
