// The precision simulation's report (precision_simulation.h): text and JSON.
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "output_files.h"
#include "platemeter/calib/precision_simulation.h"
#include "platemeter/core/error.h"
#include "json_optional.h"

namespace platemeter {
namespace {

using nlohmann::ordered_json;

std::string BalanceWords(const PrecisionPlan& plan) {
  switch (plan.balance) {
    case RadialBalance::kAsGiven: return "as given (seed 000's tables: k0' = 0 for a Gaussian lens, so c' = c)";
    case RadialBalance::kZeroAtRadius: return fmt::format("balanced to zero at r = {:g} mm, every correlation propagated", plan.balance_radius_mm);
    case RadialBalance::kEqualLobePeaks: return "balanced to equal lobe peaks over the format, every correlation propagated";
    case RadialBalance::kEqualLobeAreas: return "balanced to equal lobe areas over the format, every correlation propagated";
  }
  return "?";
}

// The headline rows: label, unit, predicted, reference.
struct Headline {
  std::string key;
  std::string label;
  std::optional<double> predicted;
  std::optional<double> reference;
};

std::vector<Headline> Headlines(const PrecisionSimulationResult& r) {
  const PrecisionReference& ref = r.plan.reference;
  const bool c_free = r.camera[0].sigma.has_value();
  return {
      {"xp", "xp", r.xp_um, ref.xp_um},
      {"yp", "yp", r.yp_um, ref.yp_um},
      {"c", "c (Gaussian principal distance)", r.c_um, std::nullopt},
      {"c_prime", "c' (calibrated focal length)",
       c_free ? std::optional<double>(r.calibrated_focal_length_mm.sigma * 1e3) : std::nullopt, ref.c_prime_um},
      {"radial_corner", fmt::format("delta_r' at the corner (r = {:.1f} mm)", r.corner_radius_mm),
       r.radial_corner_sigma_um, ref.radial_corner_um},
      {"decentering_corner", "P(r) at the corner", r.decentering_corner_sigma_um, ref.decentering_corner_um},
  };
}

std::string Number(const std::optional<double>& v, int width, const char* format = "{:.1f}") {
  const std::string text = v ? fmt::format(fmt::runtime(format), *v) : std::string("-");
  return fmt::format("{:>{}}", text, width);
}

std::string RollList(const std::vector<double>& rolls) {
  std::vector<std::string> parts;
  for (double r : rolls) parts.push_back(fmt::format("{:.0f}", r));
  return fmt::format("{}", fmt::join(parts, " "));
}


}  // namespace

std::string FormatPrecisionText(const PrecisionSimulationResult& r) {
  const PrecisionPlan& plan = r.plan;
  std::string out;
  out += fmt::format("Precision simulation{}\n", plan.title.empty() ? "" : ": " + plan.title);
  if (!plan.source.empty()) out += fmt::format("plan: {}\n", plan.source);
  out += fmt::format("geometry: {}\n", r.geometry);
  out += fmt::format("rolls about the optical axis (deg, exposure order): {} ({}, {:+g} deg per exposure)\n",
                     RollList(r.frame_roll_deg), KappaSequenceName(plan.kappa_sequence), plan.kappa_increment_deg);
  std::vector<std::string> free;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (plan.free[i]) free.emplace_back(kBundleCameraParamNames[i]);
  }
  out += fmt::format("adjustment: free {}; datum: {}\n", fmt::join(free, ", "), r.datum_words);
  out += fmt::format("error budget: {:g} um per image coordinate; {} passpoints, {} image points (x and y each)\n\n",
                     plan.image_sigma_um, r.points, r.observations);

  const bool reference = !plan.reference.source.empty() || plan.reference.xp_um || plan.reference.yp_um ||
                         plan.reference.c_prime_um || plan.reference.radial_corner_um ||
                         plan.reference.decentering_corner_um;
  out += "A-priori standard deviations (sigma0 = 1), um\n";
  const std::string ref_title = plan.reference.source.empty() ? "reference" : plan.reference.source;
  if (reference) {
    out += fmt::format("  {:<42} {:>10}  {:>10}  {:>6}   ({})\n", "", "predicted", "reference", "ratio", ref_title);
  } else {
    out += fmt::format("  {:<42} {:>10}\n", "", "predicted");
  }
  for (const Headline& h : Headlines(r)) {
    out += fmt::format("  {:<42} {}", h.label, Number(h.predicted, 10));
    if (reference) {
      out += fmt::format("  {}", Number(h.reference, 10, "{:g}"));
      std::optional<double> ratio;
      if (h.predicted && h.reference && *h.reference > 0.0) ratio = *h.predicted / *h.reference;
      out += fmt::format("  {}", Number(ratio, 6, "{:.2f}"));
    }
    out += "\n";
  }
  out += fmt::format("  c' and delta_r': {}.\n", BalanceWords(plan));
  out += "  P(r) = |(p1, p2)| r^2 (eq. 15); where p1 = p2 = 0 its sigma is the largest over directions.\n\n";

  out += "Camera parameters (true value, a-priori sigma with sigma0 = 1)\n";
  for (const PrecisionParameter& p : r.camera) {
    out += fmt::format("  {:<12} {:>14.8g}  {:>12}  {}\n", p.name, p.value,
                       p.sigma ? fmt::format("{:.4g}", *p.sigma) : std::string("-"), EstimateStatusName(p.status));
  }
  out += "\n";

  out += fmt::format("Distortion profiles ({})\n", BalanceWords(plan));
  out += fmt::format("  {:>8} {:>12} {:>10} {:>10} {:>10}\n", "r_mm", "delta_r'_um", "sigma_um", "P_um", "sigma_um");
  for (const DistortionProfileRow& row : r.profile.rows) {
    out += fmt::format("  {:>8.1f} {:>12.2f} {:>10.2f} {:>10.2f} {:>10.2f}\n", row.r_mm, row.radial_um,
                       row.radial_sigma_um, row.decentering_um, row.decentering_sigma_um);
  }
  out += fmt::format("  c' = {:.6f} +- {:.4f} mm\n\n", r.calibrated_focal_length_mm.value,
                     r.calibrated_focal_length_mm.sigma);

  out += "Adjustment\n";
  out += fmt::format("  observation rows {}, prior rows {}, unknowns {}, degrees of freedom (sigma0) {:g}\n",
                     r.observation_rows, r.prior_rows, r.unknowns, r.dof);
  out += fmt::format("  rank: {} parameters in the reduced system, numerical rank {}, datum defect {}, condition {:.3g}\n",
                     r.rank.num_parameters, r.rank.numerical_rank, r.rank.datum_defect, r.rank.condition_number);
  for (const NullDirection& d : r.rank.directions) {
    out += fmt::format("  {} direction{}: {}\n", d.exact ? "null" : "weak",
                       d.exact ? std::string() : fmt::format(" (relative eigenvalue {:.2g})", d.relative_eigenvalue),
                       d.words);
  }
  if (!r.rank.untouched.empty()) out += fmt::format("  untouched: {}\n", fmt::join(r.rank.untouched, ", "));
  if (r.high_correlations.empty()) {
    out += fmt::format("  no correlation of the inner cone reaches |rho| = {:g}\n", plan.correlation_threshold);
  } else {
    for (const auto& [a, b, rho] : r.high_correlations) out += fmt::format("  correlation {} / {}: {:+.3f}\n", a, b, rho);
  }
  out += fmt::format("\n{}\n", r.summary);
  return out;
}

std::string FormatPrecisionJson(const PrecisionSimulationResult& r) {
  const PrecisionPlan& plan = r.plan;
  ordered_json j;
  j["software"] = "platemeter";
  j["kind"] = "precision-simulation";
  j["title"] = plan.title;
  j["plan"] = plan.source;
  j["geometry"] = r.geometry;
  j["frames"] = r.frames;
  j["passpoints"] = r.points;
  j["image_points"] = r.observations;
  j["image_sigma_um"] = plan.image_sigma_um;
  j["kappa_sequence"] = KappaSequenceName(plan.kappa_sequence);
  j["frame_roll_deg"] = r.frame_roll_deg;
  std::vector<std::string> free;
  for (int i = 0; i < kBundleCameraParams; ++i) {
    if (plan.free[i]) free.emplace_back(kBundleCameraParamNames[i]);
  }
  j["free"] = free;
  j["datum"] = r.datum_words;
  j["balance"] = RadialBalanceName(plan.balance);
  if (plan.balance == RadialBalance::kZeroAtRadius) j["balance_radius_mm"] = plan.balance_radius_mm;
  j["corner_radius_mm"] = r.corner_radius_mm;
  ordered_json sigmas;
  for (const Headline& h : Headlines(r)) sigmas[h.key + "_um"] = calib_internal::OptionalJson(h.predicted);
  j["sigma_apriori"] = sigmas;
  if (!plan.reference.source.empty() || plan.reference.xp_um || plan.reference.c_prime_um) {
    ordered_json ref;
    ref["source"] = plan.reference.source;
    for (const Headline& h : Headlines(r)) {
      if (h.reference) ref[h.key + "_um"] = *h.reference;
    }
    j["reference"] = ref;
  }
  ordered_json camera = ordered_json::array();
  for (const PrecisionParameter& p : r.camera) {
    camera.push_back({{"name", p.name}, {"value", p.value}, {"status", EstimateStatusName(p.status)},
                      {"sigma_apriori", calib_internal::OptionalJson(p.sigma)}});
  }
  j["camera"] = camera;
  j["calibrated_focal_length_mm"] = {{"value", r.calibrated_focal_length_mm.value},
                                     {"sigma_apriori", r.calibrated_focal_length_mm.sigma}};
  ordered_json rows = ordered_json::array();
  for (const DistortionProfileRow& row : r.profile.rows) {
    rows.push_back({{"r_mm", row.r_mm},
                    {"radial_um", row.radial_um},
                    {"radial_sigma_um", row.radial_sigma_um},
                    {"decentering_um", row.decentering_um},
                    {"decentering_sigma_um", row.decentering_sigma_um}});
  }
  j["profile"] = rows;
  j["observation_rows"] = r.observation_rows;
  j["prior_rows"] = r.prior_rows;
  j["unknowns"] = r.unknowns;
  j["dof"] = r.dof;
  ordered_json rank;
  rank["num_parameters"] = r.rank.num_parameters;
  rank["structural_rank"] = r.rank.structural_rank;
  rank["numerical_rank"] = r.rank.numerical_rank;
  rank["datum_defect"] = r.rank.datum_defect;
  rank["condition_number"] = r.rank.condition_number;
  rank["untouched"] = r.rank.untouched;
  ordered_json directions = ordered_json::array();
  for (const NullDirection& d : r.rank.directions) {
    directions.push_back({{"exact", d.exact}, {"relative_eigenvalue", d.relative_eigenvalue}, {"words", d.words}});
  }
  rank["directions"] = directions;
  j["rank"] = rank;
  ordered_json correlation;
  correlation["parameters"] = r.correlation_names;
  ordered_json matrix = ordered_json::array();
  for (int i = 0; i < r.correlation.rows(); ++i) {
    std::vector<double> row(r.correlation.cols());
    for (int k = 0; k < r.correlation.cols(); ++k) row[k] = std::round(r.correlation(i, k) * 1e6) / 1e6;
    matrix.push_back(row);
  }
  correlation["matrix"] = matrix;
  ordered_json high = ordered_json::array();
  for (const auto& [a, b, rho] : r.high_correlations) high.push_back({{"a", a}, {"b", b}, {"rho", rho}});
  correlation["high"] = high;
  j["correlation"] = correlation;
  j["summary"] = r.summary;
  return j.dump(2) + "\n";
}

std::vector<std::string> WritePrecisionOutputs(const std::string& dir, const PrecisionSimulationResult& result) {
  return WriteOutputFiles(dir, {{"precision.json", FormatPrecisionJson(result)}, {"precision.txt", FormatPrecisionText(result)}});
}

}  // namespace platemeter
