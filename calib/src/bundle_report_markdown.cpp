// report.md of a bundle adjustment (bundle_report.h): seed 000 Tables 1-4 in
// form, then the adjustment's statistics, correlations, tests, rank report,
// frames and the worst observations.
#include <cmath>

#include <fmt/format.h>

#include "bundle_report_internal.h"
#include "platemeter/calib/bundle_report.h"

namespace platemeter {
namespace {

std::string Sigma(const std::optional<double>& s) { return s ? fmt::format("±{:.4g}", *s) : "--"; }

const char* UnitOf(const std::string& name) {
  if (name.ends_with("_mm")) return "mm";
  if (name.ends_with("_per_mm2")) return "mm^-2";
  if (name.ends_with("_per_mm4")) return "mm^-4";
  if (name.ends_with("_per_mm6")) return "mm^-6";
  if (name.ends_with("_per_mm")) return "mm^-1";
  return "-";
}

void ConstantsTable(const BundleCameraResult& camera, std::string* out) {
  *out += fmt::format("\n## Calibration constants, camera {} (seed 000 Table 1 form)\n\n", camera.name);
  *out += "| Parameter | Cal. value | Std. dev. | Units | Status |\n|---|---:|---:|---|---|\n";
  for (int i = 0; i < kBundleCameraParams; ++i) {
    *out += fmt::format("| {} | {:.6g} | {} | {} | {} |\n", kBundleCameraParamNames[i], camera.values[i],
                        Sigma(camera.sigmas[i]), UnitOf(kBundleCameraParamNames[i]), EstimateStatusName(camera.status[i]));
  }
}

void StatisticsSection(const BundleResult& result, std::string* out) {
  const AdjustmentResult& a = result.adjustment;
  *out += "\n## Adjustment\n\n| | |\n|---|---|\n";
  *out += fmt::format("| datum | {} |\n", result.datum_words);
  *out += fmt::format("| sigma0 (a posteriori) | {:.4f} |\n| degrees of freedom | {:.0f} |\n", a.sigma0, a.dof);
  *out += fmt::format("| observation rows / prior rows / unknowns | {} / {} / {} |\n", a.observation_rows,
                      a.prior_rows, a.unknowns);
  *out += fmt::format("| chi-square test (alpha {}) | {:.1f} in [{:.1f}, {:.1f}]: {} (p = {:.3g}) |\n",
                      result.options.adjustment.significance_level, a.chi_square.statistic, a.chi_square.lower,
                      a.chi_square.upper, a.chi_square.rejected ? "rejected" : "accepted", a.chi_square.p_value);
  *out += fmt::format("| rejected observations | {} |\n| converged, iterations | {}, {} |\n", a.rejected,
                      a.converged ? "yes" : "no", a.iterations);
  *out += fmt::format("| time: approximations, solve, covariance | {:.2f} s, {:.2f} s, {:.2f} s |\n",
                      result.initial_seconds, a.solve_seconds, a.covariance_seconds);
}

void CorrelationSection(const BundleResult& result, const BundleCameraResult& camera, std::string* out) {
  const AdjustmentResult& a = result.adjustment;
  std::vector<std::string> names;
  const std::vector<int> adjusted = AdjustedCameraParameters(camera, &names);
  if (adjusted.empty()) return;
  *out += fmt::format("\n## Correlations of the inner cone, camera {}\n\n|", camera.name);
  for (const std::string& n : names) *out += " " + n + " |";
  *out += " |\n|";
  for (size_t i = 0; i < names.size(); ++i) *out += "---:|";
  *out += "---|\n";
  const Eigen::MatrixXd r = a.Correlation(adjusted);
  for (int i = 0; i < r.rows(); ++i) {
    *out += "|";
    for (int k = 0; k < r.cols(); ++k) *out += fmt::format(" {:+.3f} |", r(i, k));
    *out += " " + names[i] + " |\n";
  }
  const auto high = a.HighCorrelations(adjusted, result.options.adjustment.correlation_threshold);
  if (!high.empty()) {
    *out += fmt::format("\nCorrelations at or above {}:\n\n", result.options.adjustment.correlation_threshold);
    for (const auto& [p, q, rho] : high) *out += fmt::format("- {} with {}: {:+.4f}\n", a.parameters[p].name, a.parameters[q].name, rho);
  }
  if (!camera.tests.empty()) {
    *out += fmt::format("\nSignificance of the distortion terms (alpha {}):\n\n| terms | statistic | critical | p | significant |\n|---|---:|---:|---:|---|\n",
                        result.options.adjustment.significance_level);
    for (const SignificanceTest& t : camera.tests) {
      *out += fmt::format("| {} | {:.3f} ({}) | {:.3f} | {:.3g} | {} |\n", t.what, t.statistic,
                          t.what.find(',') == std::string::npos ? "t" : "F", t.critical, t.p_value,
                          t.significant ? "yes" : "no");
    }
  }
}

void RankSection(const RankReport& rank, std::string* out) {
  *out += fmt::format("\n## Rank\n\n{} adjusted parameters in the reduced normal equations; structural rank {}, "
                      "numerical rank {}, datum defect {}, condition number {:.3g}.\n",
                      rank.num_parameters, rank.structural_rank, rank.numerical_rank, rank.datum_defect,
                      rank.condition_number);
  for (const std::string& u : rank.untouched) *out += "- untouched by any equation: " + u + "\n";
  for (const NullDirection& d : rank.directions) {
    *out += d.exact ? fmt::format("- **not determined**: {}\n", d.words)
                    : fmt::format("- poorly determined (relative eigenvalue {:.2g}): {}\n", d.relative_eigenvalue, d.words);
  }
  if (rank.points_undetermined > 0) *out += fmt::format("- {} points not determined by their rays\n", rank.points_undetermined);
}

void FramesSection(const BundleResult& result, std::string* out) {
  *out += "\n## Frames\n\n| frame | initial values | X m | Y m | Z m | phi deg | omega deg | kappa deg | obs | RMS x um | RMS y um |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  const double deg = 180.0 / M_PI;
  for (const BundleFrameResult& f : result.frames) {
    auto m = [&](double v, int i) { return fmt::format("{:.3f} {}", v, Sigma(f.sigmas[i])); };
    auto d = [&](double v, int i) {
      return fmt::format("{:.5f} {}", v * deg, f.sigmas[i] ? fmt::format("±{:.2g}", *f.sigmas[i] * deg) : "--");
    };
    *out += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2f} | {:.2f} |\n", f.id, f.initial_values,
                        m(f.position_m.x(), 0), m(f.position_m.y(), 1), m(f.position_m.z(), 2), d(f.angles.phi_rad, 3),
                        d(f.angles.omega_rad, 4), d(f.angles.kappa_rad, 5), f.observations, f.rms_x_um, f.rms_y_um);
  }
}

}  // namespace

std::string FormatBundleReportMarkdown(const BundleResult& result, const BundleReportOptions& options) {
  std::string out = "# " + options.title + "\n\n" + result.adjustment.summary + "\n";
  for (const BundleCameraResult& camera : result.cameras) {
    ConstantsTable(camera, &out);
    AppendProfileTables(result, camera, options, &out);
  }
  StatisticsSection(result, &out);
  for (const BundleCameraResult& camera : result.cameras) CorrelationSection(result, camera, &out);
  RankSection(result.adjustment.rank, &out);
  FramesSection(result, &out);
  out += "\n## Worst observations\n\n| frame | point | residual x um | residual y um | normalized | status | origin |\n"
         "|---|---|---:|---:|---:|---|---|\n";
  for (const ObservationResidual* r : WorstObservations(result, options.worst_observations)) {
    out += fmt::format("| {} | {} | {:.2f} | {:.2f} | {:.2f}, {:.2f} | {} | {} |\n", r->group, r->item,
                       1e3 * r->residual[0], 1e3 * r->residual[1], r->normalized[0], r->normalized[1],
                       r->status == ObservationStatus::kUsed ? "used" : "rejected: " + r->reason, r->origin);
  }
  if (!options.warnings.empty()) {
    out += "\n## Left out by the checks\n\n";
    for (const BundleWarning& w : options.warnings) out += "- " + w.item + ": " + w.reason + "\n";
  }
  return out;
}

}  // namespace platemeter
