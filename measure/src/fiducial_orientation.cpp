// The fiducial interior orientation (fiducial_orientation.h).
#include "platemeter/measure/fiducial_orientation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

using Matrix2x8 = Eigen::Matrix<double, 2, 8>;

Eigen::Matrix2d AsMatrix(const Covariance2& c) {
  Eigen::Matrix2d m;
  m << c.xx, c.xy, c.xy, c.yy;
  return m;
}

Covariance2 AsCovariance(const Eigen::Matrix2d& m) { return {m(0, 0), 0.5 * (m(0, 1) + m(1, 0)), m(1, 1)}; }

Eigen::Matrix<double, 8, 8> ParameterCovariance(const ReseauFit& fit) {
  return Eigen::Map<const Eigen::Matrix<double, 8, 8, Eigen::RowMajor>>(fit.covariance);
}

double Step(double p) { return 1e-7 * std::max(1.0, std::abs(p)); }

// dF(g)/dp (measured mm per parameter) by central differences; zero columns
// for the model's unused parameters.
Matrix2x8 ForwardByParameters(const ReseauFit& fit, double gx, double gy) {
  Matrix2x8 a = Matrix2x8::Zero();
  for (int k = 0; k < fit.parameter_count; ++k) {
    ReseauFit plus = fit, minus = fit;
    const double h = Step(fit.parameters[k]);
    plus.parameters[k] += h;
    minus.parameters[k] -= h;
    double xp, yp, xm, ym;
    plus.Forward(gx, gy, &xp, &yp);
    minus.Forward(gx, gy, &xm, &ym);
    a(0, k) = (xp - xm) / (2 * h);
    a(1, k) = (yp - ym) / (2 * h);
  }
  return a;
}

// dF^-1(m)/dp (camera mm per parameter) by central differences.
Matrix2x8 InverseByParameters(const ReseauFit& fit, double mx, double my) {
  Matrix2x8 a = Matrix2x8::Zero();
  for (int k = 0; k < fit.parameter_count; ++k) {
    ReseauFit plus = fit, minus = fit;
    const double h = Step(fit.parameters[k]);
    plus.parameters[k] += h;
    minus.parameters[k] -= h;
    const PlanePoint gp = plus.ToGrid({mx, my, {}}), gm = minus.ToGrid({mx, my, {}});
    a(0, k) = (gp.x - gm.x) / (2 * h);
    a(1, k) = (gp.y - gm.y) / (2 * h);
  }
  return a;
}

int FiducialParameterCount(ReseauFitModel model) { return model == ReseauFitModel::kSimilarity ? 4 : 6; }

// The variance factor FitReseau applied to the parameter covariance.
double VarianceFactor(const ReseauFit& fit) { return std::max(1.0, fit.sigma0 * fit.sigma0); }

Covariance2 Floored(const Covariance2& c, double min_sigma_mm) {
  const double v = min_sigma_mm * min_sigma_mm;
  return {std::max(c.xx, v), c.xy, std::max(c.yy, v)};
}

ReseauFit FitSubset(const std::vector<ReseauObservation>& observations, const std::vector<bool>& excluded,
                    const FiducialOrientationOptions& options) {
  std::vector<ReseauObservation> used;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (!excluded[i]) used.push_back(observations[i]);
  }
  ReseauFitOptions fit;
  fit.model = options.model;
  fit.max_rejected = 0;  // the rejection is the leave-one-out loop here
  fit.min_sigma_mm = options.min_sigma_mm;
  fit.scale_by_variance_factor = true;
  return FitReseau(used, fit);
}

// Observation i against a fit that did not use it: Mahalanobis norm of
// measured - F(g_i) with covariance f C_i + A C_p A^T.
double Discrepancy(const ReseauFit& fit, const ReseauObservation& o, double min_sigma_mm) {
  double px, py;
  fit.Forward(o.grid_x_mm, o.grid_y_mm, &px, &py);
  const Eigen::Vector2d d(o.measured.x - px, o.measured.y - py);
  const Matrix2x8 a = ForwardByParameters(fit, o.grid_x_mm, o.grid_y_mm);
  const Eigen::Matrix2d s =
      VarianceFactor(fit) * AsMatrix(Floored(o.measured.cov, min_sigma_mm)) + a * ParameterCovariance(fit) * a.transpose();
  return std::sqrt(d.dot(s.ldlt().solve(d)));
}

}  // namespace

std::vector<CalibratedFiducial> CalibratedFiducials(const CameraDefinition& camera, const FiducialSet* set) {
  std::vector<CalibratedFiducial> out;
  if (set) {
    for (const FiducialMark& m : set->marks) out.push_back({m.id, m.x_mm, m.y_mm});
  }
  if (camera.format_corners_as_fiducials) {
    const double w = camera.format_width_mm / 2, h = camera.format_height_mm / 2;
    out.push_back({"UL", -w, h});
    out.push_back({"UR", w, h});
    out.push_back({"LL", -w, -h});
    out.push_back({"LR", w, -h});
  }
  return out;
}

bool FiducialOrientationOptions::Check(std::string* why) const {
  if (model != ReseauFitModel::kSimilarity && model != ReseauFitModel::kAffine) {
    if (why) *why = std::string("fiducial orientation model must be similarity or affine, not ") + ReseauFitModelName(model);
    return false;
  }
  if (!(rejection_threshold > 1.0) || max_rejected < 0 || !(min_sigma_mm > 0.0)) {
    if (why) *why = "fiducial orientation needs rejection_threshold > 1, max_rejected >= 0, min_sigma_mm > 0";
    return false;
  }
  return true;
}

PlanePoint FiducialOrientation::ToCamera(const PlanePoint& measured) const {
  PlanePoint g = fit.ToGrid(measured);
  const Matrix2x8 jp = InverseByParameters(fit, measured.x, measured.y);
  g.cov = g.cov + AsCovariance(jp * ParameterCovariance(fit) * jp.transpose());
  return g;
}

PlanePoint FiducialOrientation::FiducialToCamera(size_t i) const {
  const ReseauObservation& o = observations.at(i);
  if (fit.is_rejected.at(i)) return ToCamera(o.measured);
  // The residual's covariance f C_i - A C_p A^T (kept positive: a floor of
  // 1 % of f C_i's diagonal against rounding with exactly determined points).
  const Matrix2x8 a = ForwardByParameters(fit, o.grid_x_mm, o.grid_y_mm);
  const Eigen::Matrix2d c = VarianceFactor(fit) * AsMatrix(o.measured.cov);
  Eigen::Matrix2d r = c - a * ParameterCovariance(fit) * a.transpose();
  r(0, 0) = std::max(r(0, 0), 0.01 * c(0, 0));
  r(1, 1) = std::max(r(1, 1), 0.01 * c(1, 1));
  return fit.ToGrid({o.measured.x, o.measured.y, AsCovariance(r)});
}

AppliedCorrection FiducialOrientation::Record(const std::string& source) const {
  AppliedCorrection c{"fiducial_orientation", {{"model", ReseauFitModelName(fit.model)}, {"fiducials", source}}};
  const std::vector<std::string> names = fit.ParameterNames();
  for (size_t k = 0; k < names.size(); ++k) {
    c.parameters.push_back({names[k], fmt::format("{}", fit.parameters[k])});
    c.parameters.push_back({"sigma_" + names[k], fmt::format("{}", std::sqrt(fit.covariance[9 * k]))});
  }
  c.parameters.push_back({"sigma0", fmt::format("{}", fit.sigma0)});
  c.parameters.push_back({"rms_mm", fmt::format("{}", fit.rms_mm)});
  c.parameters.push_back({"fiducials_used", std::to_string(fit.used)});
  c.parameters.push_back({"fiducials_rejected", std::to_string(fit.rejected)});
  std::string rejected;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (fit.is_rejected[i]) rejected += (rejected.empty() ? "" : ";") + observations[i].id;
  }
  if (!rejected.empty()) c.parameters.push_back({"rejected_ids", rejected});
  return c;
}

FiducialOrientation FitFiducialOrientation(const std::vector<ReseauObservation>& observations,
                                           const FiducialOrientationOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("fiducial orientation", why);
  const int n = FiducialParameterCount(options.model);
  const int count = static_cast<int>(observations.size());
  if (2 * count <= n) {
    throw Error("fiducial orientation", fmt::format("the {} model needs more than {} measured fiducials, {} usable",
                                                    ReseauFitModelName(options.model), n / 2, count));
  }
  // Robust: the fiducial the others predict worst (leave-one-out, so a bad
  // fiducial cannot hide by pulling the fit) is dropped while its
  // discrepancy exceeds the threshold and the rest stays redundant.
  std::vector<bool> rejected(observations.size(), false);
  auto used_count = [&] { return static_cast<int>(std::count(rejected.begin(), rejected.end(), false)); };
  auto leave_one_out = [&](size_t i) {
    std::vector<bool> excluded = rejected;
    excluded[i] = true;
    return Discrepancy(FitSubset(observations, excluded, options), observations[i], options.min_sigma_mm);
  };
  while (count - used_count() < options.max_rejected && 2 * (used_count() - 1) > n) {
    int worst = -1;
    double worst_value = 0.0;
    for (size_t i = 0; i < observations.size(); ++i) {
      if (rejected[i]) continue;
      const double v = leave_one_out(i);
      if (v > worst_value) {
        worst_value = v;
        worst = static_cast<int>(i);
      }
    }
    if (worst < 0 || worst_value <= options.rejection_threshold) break;
    rejected[worst] = true;
  }

  FiducialOrientation out;
  out.observations = observations;
  out.fit = FitSubset(observations, rejected, options);
  out.fit.is_rejected = rejected;
  out.fit.used = used_count();
  out.fit.rejected = count - out.fit.used;
  out.fit.residual_x_mm.clear();
  out.fit.residual_y_mm.clear();
  const bool redundant = 2 * (out.fit.used - 1) > n;
  for (size_t i = 0; i < observations.size(); ++i) {
    const PlanePoint g = out.fit.ToGrid(observations[i].measured);
    out.fit.residual_x_mm.push_back(observations[i].grid_x_mm - g.x);
    out.fit.residual_y_mm.push_back(observations[i].grid_y_mm - g.y);
    if (rejected[i]) {
      out.leave_one_out.push_back(Discrepancy(out.fit, observations[i], options.min_sigma_mm));
    } else {
      out.leave_one_out.push_back(redundant ? leave_one_out(i) : 0.0);
    }
  }
  return out;
}

FiducialOrientation ApplyFiducialOrientation(MeasurementFile* file, std::vector<PlanePoint>* positions,
                                             const std::vector<bool>& has_position,
                                             const std::vector<CalibratedFiducial>& calibrated,
                                             const FiducialOrientationOptions& options) {
  std::map<std::string, const CalibratedFiducial*> table;
  for (const CalibratedFiducial& c : calibrated) table[c.id] = &c;
  std::vector<ReseauObservation> observations;
  std::vector<size_t> rows;
  for (size_t k = 0; k < file->points.size(); ++k) {
    const MeasuredPoint& p = file->points[k];
    if (p.kind != PointKind::kFiducial || !has_position[k]) continue;
    const auto it = table.find(p.id);
    if (it == table.end()) continue;
    observations.push_back({p.id, it->second->x_mm, it->second->y_mm, (*positions)[k]});
    rows.push_back(k);
  }
  FiducialOrientation o = FitFiducialOrientation(observations, options);
  std::map<size_t, size_t> observation_of_row;
  for (size_t i = 0; i < rows.size(); ++i) observation_of_row[rows[i]] = i;
  for (size_t k = 0; k < file->points.size(); ++k) {
    if (!has_position[k]) continue;
    const auto it = observation_of_row.find(k);
    if (it == observation_of_row.end()) {
      if (file->points[k].kind == PointKind::kFiducial) file->points[k].flags.push_back("fiducial_orientation:not_in_table");
      (*positions)[k] = o.ToCamera((*positions)[k]);
      continue;
    }
    if (o.fit.is_rejected[it->second]) file->points[k].flags.push_back("fiducial_orientation:rejected");
    (*positions)[k] = o.FiducialToCamera(it->second);
  }
  return o;
}

}  // namespace platemeter
