// JSON pieces shared by the adjustments' reports (report_json.h).
#include "report_json.h"

namespace platemeter {

using nlohmann::ordered_json;

ordered_json RankReportJson(const RankReport& rank) {
  ordered_json j;
  j["parameters"] = rank.num_parameters;
  j["structural_rank"] = rank.structural_rank;
  j["numerical_rank"] = rank.numerical_rank;
  j["datum_defect"] = rank.datum_defect;
  j["condition_number"] = rank.condition_number;
  j["untouched"] = rank.untouched;
  j["points_undetermined"] = rank.points_undetermined;
  j["directions"] = ordered_json::array();
  for (const NullDirection& d : rank.directions) {
    ordered_json e;
    e["kind"] = d.exact ? "null" : "weak";
    e["relative_eigenvalue"] = d.relative_eigenvalue;
    e["words"] = d.words;
    e["shares"] = ordered_json::object();
    for (const auto& [name, share] : d.shares) {
      if (share >= 0.01) e["shares"][name] = share;
    }
    j["directions"].push_back(e);
  }
  return j;
}

ordered_json StatisticsJson(const AdjustmentResult& a) {
  ordered_json j;
  j["sigma0"] = a.sigma0;
  j["degrees_of_freedom"] = a.dof;
  j["observation_rows"] = a.observation_rows;
  j["prior_rows"] = a.prior_rows;
  j["unknowns"] = a.unknowns;
  j["iterations"] = a.iterations;
  j["converged"] = a.converged;
  j["rejected_observations"] = a.rejected;
  j["chi_square"] = {{"statistic", a.chi_square.statistic}, {"dof", a.chi_square.dof},
                     {"lower", a.chi_square.lower},         {"upper", a.chi_square.upper},
                     {"p_value", a.chi_square.p_value},     {"rejected", a.chi_square.rejected}};
  return j;
}

}  // namespace platemeter
