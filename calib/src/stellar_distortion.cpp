// The stellar lens's distortion fields and profiles with propagated sigmas
// (stellar_distortion.h).
#include "platemeter/calib/stellar_distortion.h"

#include <cmath>
#include <functional>


#include <fmt/format.h>

#include "platemeter/calib/stellar_lens.h"
#include "platemeter/core/error.h"
#include "stellar_internal.h"

namespace platemeter {
namespace {

constexpr int kCircleSamples = 720;   // directions searched for the largest tangential component
constexpr int kIntegralSteps = 400;   // Simpson steps of the equal-area integral (even)

// Indices (in the camera values) of the lens's radial coefficients and decentering amplitudes, by name.
void PartIndices(DistortionModelId lens, std::vector<int>* radial, std::vector<int>* decentering) {
  const std::vector<std::string> names = StellarCameraParamNames(lens);
  for (int i = 3; i < static_cast<int>(names.size()); ++i) {
    const char a = names[i][0], b = names[i].size() > 1 ? names[i][1] : ' ';
    if ((a == 'K' || a == 'k') && b >= '1' && b <= '3') radial->push_back(i);
    if ((a == 'K' && (b == '4' || b == '5')) || a == 'J' || a == 'p') decentering->push_back(i);
  }
}

StellarCamera PartValues(const StellarLensEstimate& e, StellarLensPart part) {
  StellarCamera v = e.values;
  std::vector<int> radial, decentering;
  PartIndices(e.lens, &radial, &decentering);
  if (part == StellarLensPart::kRadial) {
    for (int i : decentering) v[i] = 0.0;
  } else if (part == StellarLensPart::kDecentering) {
    for (int i : radial) v[i] = 0.0;
  }
  return v;
}

// The lens term at (x, y) mm from the reseau origin, as a distortion (um).
Eigen::Vector2d DistortionOf(DistortionModelId lens, const StellarCamera& v, double x_mm, double y_mm) {
  return VisitStellarLens(lens, [&](auto model) {
    using Lens = decltype(model);
    double dx = 0.0, dy = 0.0;
    Lens::Apply(v.data() + 3, x_mm - v[1], y_mm - v[2], &dx, &dy);
    const double sign = Lens::kDirection == DistortionDirection::kDistortion ? 1.0 : -1.0;
    return Eigen::Vector2d(sign * 1e3 * dx, sign * 1e3 * dy);
  });
}

// Point of symmetry, absolute plate frame (orbigon-11: xs, ys are relative to the principal point).
Eigen::Vector2d SymmetryPoint(DistortionModelId lens, const StellarCamera& v) {
  const double xs = lens == DistortionModelId::kSlama ? v[3] : 0.0;
  const double ys = lens == DistortionModelId::kSlama ? v[4] : 0.0;
  return {v[1] + xs, v[2] + ys};
}

// The radial component (um) of the radial part at distance d from the point of symmetry (along +x).
double RadialAt(DistortionModelId lens, const StellarCamera& radial_values, double d_mm) {
  const Eigen::Vector2d s = SymmetryPoint(lens, radial_values);
  return DistortionOf(lens, radial_values, s.x() + d_mm, s.y()).x();
}

// The largest tangential component (um) of the decentering part on the circle of radius d, and its direction.
double DecenteringAt(DistortionModelId lens, const StellarCamera& decentering_values, double d_mm,
                     double* direction_rad = nullptr) {
  const Eigen::Vector2d s = SymmetryPoint(lens, decentering_values);
  double best = -1.0, best_angle = 0.0;
  for (int k = 0; k < kCircleSamples; ++k) {
    const double a = M_PI * k / kCircleSamples;  // the tangential component is odd in a + pi
    const Eigen::Vector2d u(std::cos(a), std::sin(a));
    const Eigen::Vector2d e = DistortionOf(lens, decentering_values, s.x() + d_mm * u.x(), s.y() + d_mm * u.y());
    const double t = std::abs(-u.y() * e.x() + u.x() * e.y());
    if (t > best) best = t, best_angle = a;
  }
  if (direction_rad != nullptr) *direction_rad = best_angle;
  return best;
}

// k0 of the equal-area transformation: (2 / M^2) integral_0^M dr(d) dd, Simpson's rule.
double EqualAreaK0(DistortionModelId lens, const StellarCamera& radial_values, double max_mm) {
  const double h = max_mm / kIntegralSteps;
  double sum = 0.0;
  for (int i = 0; i <= kIntegralSteps; ++i) {
    const double w = i == 0 || i == kIntegralSteps ? 1.0 : i % 2 == 1 ? 4.0 : 2.0;
    sum += w * RadialAt(lens, radial_values, i * h);
  }
  return 2.0 / (max_mm * max_mm) * (sum * h / 3.0) * 1e-3;  // dr in um, d in mm
}

// Value and one sigma of f(camera values), the gradient by central differences.
std::pair<double, double> WithSigma(const StellarLensEstimate& e, const std::function<double(const StellarCamera&)>& f) {
  const double value = f(e.values);
  const int n = static_cast<int>(e.values.size());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    const double variance = e.covariance.rows() == n ? e.covariance(i, i) : 0.0;
    if (!(variance > 0.0)) continue;
    const double h = 1e-3 * std::sqrt(variance);
    StellarCamera plus = e.values, minus = e.values;
    plus[i] += h;
    minus[i] -= h;
    g[i] = (f(plus) - f(minus)) / (2.0 * h);
  }
  const double variance = e.covariance.rows() == n ? g.dot(e.covariance * g) : 0.0;
  return {value, std::sqrt(std::max(0.0, variance))};
}

// The covariance of the estimable parameters (non-zero diagonal of the information).
Eigen::MatrixXd CofactorOf(const Eigen::MatrixXd& information) {
  std::vector<int> rows;
  for (int i = 0; i < information.rows(); ++i) {
    if (information(i, i) > 0.0) rows.push_back(i);
  }
  return stellar_internal::InverseOverRows(information, rows);
}

}  // namespace

StellarLensEstimate PlateLensEstimate(const StellarPlateResult& plate, DistortionModelId lens) {
  StellarLensEstimate e{lens, plate.camera, {}};
  e.covariance = plate.m_o * plate.m_o * CofactorOf(plate.camera_information);
  return e;
}

StellarLensEstimate CombinationLensEstimate(const StellarCombination& combination, DistortionModelId lens) {
  return {lens, combination.camera, combination.m_0 * combination.m_0 * combination.cofactor};
}

const char* StellarLensPartName(StellarLensPart part) {
  switch (part) {
    case StellarLensPart::kTotal: return "total";
    case StellarLensPart::kRadial: return "radial symmetric";
    case StellarLensPart::kDecentering: return "decentering";
  }
  return "?";
}

Eigen::Vector2d StellarDistortion_um(const StellarLensEstimate& estimate, StellarLensPart part, double x_mm,
                                     double y_mm) {
  return DistortionOf(estimate.lens, PartValues(estimate, part), x_mm, y_mm);
}

StellarSymmetry StellarSymmetryOf(const StellarLensEstimate& estimate) {
  StellarSymmetry out;
  const Eigen::Vector2d s = SymmetryPoint(estimate.lens, estimate.values);
  out.x_mm = s.x();
  out.y_mm = s.y();
  // The direction is that of the decentering's leading term: searched on a circle of 10 mm.
  const double t = DecenteringAt(estimate.lens, PartValues(estimate, StellarLensPart::kDecentering), 10.0,
                                 &out.axis_rad);
  out.has_decentering = t > 0.0;
  return out;
}

StellarProfile ComputeStellarProfile(const StellarLensEstimate& estimate, double max_distance_mm, int samples) {
  if (samples < 2)
    throw Error("stellar distortion profile", fmt::format("needs at least 2 samples ({})", samples));
  std::vector<double> distances;
  for (int i = 0; i <= samples; ++i) distances.push_back(max_distance_mm * i / samples);
  return ComputeStellarProfile(estimate, max_distance_mm, distances);
}

StellarProfile ComputeStellarProfile(const StellarLensEstimate& estimate, double max_distance_mm,
                                     const std::vector<double>& distances_mm) {
  if (!(max_distance_mm > 0.0))
    throw Error("stellar distortion profile", fmt::format("needs a positive largest distance ({})", max_distance_mm));
  const DistortionModelId lens = estimate.lens;
  const auto radial_part = [&](StellarCamera v) {
    StellarLensEstimate e{lens, std::move(v), {}};
    return PartValues(e, StellarLensPart::kRadial);
  };
  const auto decentering_part = [&](StellarCamera v) {
    StellarLensEstimate e{lens, std::move(v), {}};
    return PartValues(e, StellarLensPart::kDecentering);
  };
  const auto k0 = [&](const StellarCamera& v) { return EqualAreaK0(lens, radial_part(v), max_distance_mm); };
  StellarProfile out;
  out.max_distance_mm = max_distance_mm;
  out.k0 = k0(estimate.values);
  std::tie(out.transformed_focal_length_mm, out.transformed_focal_length_sigma_mm) =
      WithSigma(estimate, [&](const StellarCamera& v) { return v[0] * (1.0 + k0(v)); });
  for (const double d : distances_mm) {
    StellarProfileRow row;
    row.d_mm = d;
    std::tie(row.radial_um, row.radial_sigma_um) =
        WithSigma(estimate, [&](const StellarCamera& v) { return RadialAt(lens, radial_part(v), d); });
    std::tie(row.transformed_um, row.transformed_sigma_um) = WithSigma(estimate, [&](const StellarCamera& v) {
      return RadialAt(lens, radial_part(v), d) - 1e3 * k0(v) * d;
    });
    std::tie(row.decentering_um, row.decentering_sigma_um) =
        WithSigma(estimate, [&](const StellarCamera& v) { return DecenteringAt(lens, decentering_part(v), d); });
    out.rows.push_back(row);
  }
  return out;
}

}  // namespace platemeter
