// The bundle's report (bundle_report.h) as a document: seed 000 Tables 1-4 in
// form, then the adjustment's statistics, correlations, tests, rank report,
// frames and the worst observations; rendered as report.md here and as
// report.html by the report library (the same cells, formatted once).
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

void ConstantsTable(const BundleCameraResult& camera, TextDocument* doc) {
  doc->Heading(2, fmt::format("Calibration constants, camera {} (seed 000 Table 1 form)", camera.name));
  TextTable& table = doc->Table({"Parameter", "Cal. value", "Std. dev.", "Units", "Status"}, "lrrll");
  for (int i = 0; i < kBundleCameraParams; ++i) {
    table.rows.push_back({kBundleCameraParamNames[i], fmt::format("{:.6g}", camera.values[i]), Sigma(camera.sigmas[i]),
                          UnitOf(kBundleCameraParamNames[i]), EstimateStatusName(camera.status[i])});
  }
}

void StatisticsSection(const BundleResult& result, TextDocument* doc) {
  const AdjustmentResult& a = result.adjustment;
  doc->Heading(2, "Adjustment");
  TextTable& t = doc->Table({"", ""}, "ll");
  t.rows.push_back({"datum", result.datum_words});
  t.rows.push_back({"sigma0 (a posteriori)", fmt::format("{:.4f}", a.sigma0)});
  t.rows.push_back({"degrees of freedom", fmt::format("{:.0f}", a.dof)});
  t.rows.push_back({"observation rows / prior rows / unknowns",
                    fmt::format("{} / {} / {}", a.observation_rows, a.prior_rows, a.unknowns)});
  t.rows.push_back({fmt::format("chi-square test (alpha {})", result.options.adjustment.significance_level),
                    fmt::format("{:.1f} in [{:.1f}, {:.1f}]: {} (p = {:.3g})", a.chi_square.statistic, a.chi_square.lower,
                                a.chi_square.upper, a.chi_square.rejected ? "rejected" : "accepted", a.chi_square.p_value)});
  t.rows.push_back({"rejected observations", fmt::format("{}", a.rejected)});
  t.rows.push_back({"converged, iterations", fmt::format("{}, {}", a.converged ? "yes" : "no", a.iterations)});
  t.rows.push_back({"time: approximations, solve, covariance",
                    fmt::format("{:.2f} s, {:.2f} s, {:.2f} s", result.initial_seconds, a.solve_seconds,
                                a.covariance_seconds)});
}

void TestsTable(const BundleResult& result, const BundleCameraResult& camera, TextDocument* doc) {
  if (camera.tests.empty()) return;
  doc->Paragraph(fmt::format("Significance of the distortion terms (alpha {}):",
                             result.options.adjustment.significance_level));
  TextTable& t = doc->Table({"terms", "statistic", "critical", "p", "significant"}, "lrrrl");
  for (const SignificanceTest& test : camera.tests) {
    t.rows.push_back({test.what,
                      fmt::format("{:.3f} ({})", test.statistic, test.what.find(',') == std::string::npos ? "t" : "F"),
                      fmt::format("{:.3f}", test.critical), fmt::format("{:.3g}", test.p_value),
                      test.significant ? "yes" : "no"});
  }
}

void CorrelationSection(const BundleResult& result, const BundleCameraResult& camera, TextDocument* doc) {
  const AdjustmentResult& a = result.adjustment;
  std::vector<std::string> names;
  const std::vector<int> adjusted = AdjustedCameraParameters(camera, &names);
  if (adjusted.empty()) return;
  doc->Heading(2, fmt::format("Correlations of the inner cone, camera {}", camera.name));
  std::vector<std::string> header = names;
  header.push_back("");
  TextTable& t = doc->Table(header, std::string(names.size(), 'r') + "l");
  const Eigen::MatrixXd r = a.Correlation(adjusted);
  for (int i = 0; i < r.rows(); ++i) {
    std::vector<std::string>& row = t.rows.emplace_back();
    for (int k = 0; k < r.cols(); ++k) row.push_back(fmt::format("{:+.3f}", r(i, k)));
    row.push_back(names[i]);
  }
  const auto high = a.HighCorrelations(adjusted, result.options.adjustment.correlation_threshold);
  if (!high.empty()) {
    doc->Paragraph(fmt::format("Correlations at or above {}:", result.options.adjustment.correlation_threshold));
    std::vector<std::string> items;
    for (const auto& [p, q, rho] : high) {
      items.push_back(fmt::format("{} with {}: {:+.4f}", a.parameters[p].name, a.parameters[q].name, rho));
    }
    doc->List(items);
  }
  TestsTable(result, camera, doc);
}

void RankSection(const RankReport& rank, TextDocument* doc) {
  doc->Heading(2, "Rank");
  doc->Paragraph(fmt::format("{} adjusted parameters in the reduced normal equations; structural rank {}, "
                             "numerical rank {}, datum defect {}, condition number {:.3g}.",
                             rank.num_parameters, rank.structural_rank, rank.numerical_rank, rank.datum_defect,
                             rank.condition_number));
  std::vector<std::string> items;
  for (const std::string& u : rank.untouched) items.push_back("untouched by any equation: " + u);
  for (const NullDirection& d : rank.directions) {
    items.push_back(d.exact ? fmt::format("**not determined**: {}", d.words)
                            : fmt::format("poorly determined (relative eigenvalue {:.2g}): {}", d.relative_eigenvalue, d.words));
  }
  if (rank.points_undetermined > 0) items.push_back(fmt::format("{} points not determined by their rays", rank.points_undetermined));
  if (!items.empty()) doc->List(items);
}

void FramesSection(const BundleResult& result, TextDocument* doc) {
  doc->Heading(2, "Frames");
  TextTable& t = doc->Table({"frame", "initial values", "X m", "Y m", "Z m", "phi deg", "omega deg", "kappa deg", "obs",
                             "RMS x um", "RMS y um"},
                            "llrrrrrrrrr");
  const double deg = 180.0 / M_PI;
  for (const BundleFrameResult& f : result.frames) {
    auto m = [&](double v, int i) { return fmt::format("{:.3f} {}", v, Sigma(f.sigmas[i])); };
    auto d = [&](double v, int i) {
      return fmt::format("{:.5f} {}", v * deg, f.sigmas[i] ? fmt::format("±{:.2g}", *f.sigmas[i] * deg) : "--");
    };
    t.rows.push_back({f.id, f.initial_values, m(f.position_m.x(), 0), m(f.position_m.y(), 1), m(f.position_m.z(), 2),
                      d(f.angles.phi_rad, 3), d(f.angles.omega_rad, 4), d(f.angles.kappa_rad, 5),
                      fmt::format("{}", f.observations), fmt::format("{:.2f}", f.rms_x_um),
                      fmt::format("{:.2f}", f.rms_y_um)});
  }
}

void WorstSection(const BundleResult& result, const BundleReportOptions& options, TextDocument* doc) {
  doc->Heading(2, "Worst observations");
  TextTable& t = doc->Table({"frame", "point", "residual x um", "residual y um", "normalized", "status", "origin"},
                            "llrrrll");
  for (const ObservationResidual* r : WorstObservations(result, options.worst_observations)) {
    t.rows.push_back({r->group, r->item, fmt::format("{:.2f}", 1e3 * r->residual[0]),
                      fmt::format("{:.2f}", 1e3 * r->residual[1]),
                      fmt::format("{:.2f}, {:.2f}", r->normalized[0], r->normalized[1]),
                      r->status == ObservationStatus::kUsed ? "used" : "rejected: " + r->reason, r->origin});
  }
}

}  // namespace

TextDocument BundleReportDocument(const BundleResult& result, const BundleReportOptions& options) {
  TextDocument doc;
  doc.Heading(1, options.title);
  doc.Paragraph(result.adjustment.summary);
  for (const BundleCameraResult& camera : result.cameras) {
    ConstantsTable(camera, &doc);
    AppendProfileTables(result, camera, options, &doc);
  }
  StatisticsSection(result, &doc);
  for (const BundleCameraResult& camera : result.cameras) CorrelationSection(result, camera, &doc);
  RankSection(result.adjustment.rank, &doc);
  FramesSection(result, &doc);
  WorstSection(result, options, &doc);
  if (!options.warnings.empty()) {
    doc.Heading(2, "Left out by the checks");
    std::vector<std::string> items;
    for (const BundleWarning& w : options.warnings) items.push_back(w.item + ": " + w.reason);
    doc.List(items);
  }
  return doc;
}

std::string FormatBundleReportMarkdown(const BundleResult& result, const BundleReportOptions& options) {
  return ToMarkdown(BundleReportDocument(result, options));
}

}  // namespace platemeter
