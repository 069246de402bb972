// calibration.json of a bundle adjustment (bundle_report.h; docs/calibration-output.md).
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bundle_report_internal.h"
#include "report_json.h"
#include "platemeter/calib/bundle_report.h"
#include "json_optional.h"

namespace platemeter {
namespace {

using nlohmann::ordered_json;


ordered_json TestJson(const SignificanceTest& t) {
  return {{"terms", t.what},          {"statistic", t.statistic}, {"critical", t.critical},
          {"p_value", t.p_value},     {"significant", t.significant},
          {"kind", t.what.find(',') == std::string::npos ? "t" : "F"}};
}

ordered_json CameraJson(const BundleResult& result, size_t c) {
  const BundleCameraResult& camera = result.cameras[c];
  const AdjustmentResult& a = result.adjustment;
  ordered_json j;
  j["name"] = camera.name;
  j["model"] = "brown-affine";
  j["format_mm"] = {camera.format_width_mm, camera.format_height_mm};
  ordered_json parameters = ordered_json::object();
  for (int i = 0; i < kBundleCameraParams; ++i) {
    parameters[kBundleCameraParamNames[i]] = {{"value", camera.values[i]},
                                              {"sigma", calib_internal::OptionalJson(camera.sigmas[i])},
                                              {"status", EstimateStatusName(camera.status[i])}};
  }
  j["parameters"] = parameters;
  std::vector<std::string> names;
  const std::vector<int> adjusted = AdjustedCameraParameters(camera, &names);
  const Eigen::MatrixXd r = a.Correlation(adjusted);
  j["correlation"] = {{"parameters", names}, {"matrix", ordered_json::array()}};
  for (int i = 0; i < r.rows(); ++i) {
    std::vector<double> row(r.cols());
    for (int k = 0; k < r.cols(); ++k) row[k] = std::round(r(i, k) * 1e6) / 1e6;
    j["correlation"]["matrix"].push_back(row);
  }
  const Eigen::MatrixXd cov = a.Covariance(adjusted, true), unscaled = a.Covariance(adjusted, false);
  j["covariance"] = {{"parameters", names}, {"scaled_by_sigma0_squared", ordered_json::array()},
                     {"unscaled", ordered_json::array()}};
  for (int i = 0; i < cov.rows(); ++i) {
    std::vector<double> row(cov.cols()), row_u(cov.cols());
    for (int k = 0; k < cov.cols(); ++k) {
      row[k] = cov(i, k);
      row_u[k] = unscaled(i, k);
    }
    j["covariance"]["scaled_by_sigma0_squared"].push_back(row);
    j["covariance"]["unscaled"].push_back(row_u);
  }
  j["high_correlations"] = ordered_json::array();
  for (const auto& [p, q, rho] : a.HighCorrelations(adjusted, result.options.adjustment.correlation_threshold)) {
    j["high_correlations"].push_back({{"a", a.parameters[p].name}, {"b", a.parameters[q].name}, {"rho", rho}});
  }
  j["significance_tests"] = ordered_json::array();
  for (const SignificanceTest& t : camera.tests) j["significance_tests"].push_back(TestJson(t));
  return j;
}

}  // namespace

std::string FormatCalibrationJson(const BundleResult& result, const BundleReportOptions& options) {
  const AdjustmentResult& a = result.adjustment;
  ordered_json j;
  j["kind"] = "bundle-adjustment";
  j["title"] = options.title;
  j["software"] = options.software;
  j["summary"] = a.summary;
  j["converged"] = a.converged;
  j["iterations"] = a.iterations;
  j["datum"] = {{"kind", DatumKindName(result.datum)}, {"words", result.datum_words}};
  j["sigma0"] = a.sigma0;
  j["degrees_of_freedom"] = a.dof;
  j["observation_rows"] = a.observation_rows;
  j["prior_rows"] = a.prior_rows;
  j["unknowns"] = a.unknowns;
  j["rejected_observations"] = a.rejected;
  j["chi_square_test"] = {{"statistic", a.chi_square.statistic}, {"dof", a.chi_square.dof},
                          {"alpha", result.options.adjustment.significance_level},       {"lower", a.chi_square.lower},
                          {"upper", a.chi_square.upper},          {"p_value", a.chi_square.p_value},
                          {"rejected", a.chi_square.rejected}};
  j["cameras"] = ordered_json::array();
  for (size_t c = 0; c < result.cameras.size(); ++c) j["cameras"].push_back(CameraJson(result, c));
  j["rank"] = RankReportJson(a.rank);
  j["frames"] = ordered_json::array();
  for (const BundleFrameResult& f : result.frames) {
    ordered_json e;
    e["id"] = f.id;
    e["camera"] = f.camera;
    e["initial_values"] = f.initial_values;
    const double v[6] = {f.position_m.x(), f.position_m.y(), f.position_m.z(), f.angles.phi_rad, f.angles.omega_rad,
                         f.angles.kappa_rad};
    for (int i = 0; i < 6; ++i) e[kBundleFrameParamNames[i]] = {{"value", v[i]}, {"sigma", calib_internal::OptionalJson(f.sigmas[i])}};
    std::vector<int> indices;
    for (const char* name : kBundleFrameParamNames) indices.push_back(a.Find("frame " + f.id, name));
    const Eigen::MatrixXd cov = a.Covariance(indices, true);
    e["covariance_scaled_by_sigma0_squared"] = ordered_json::array();
    for (int r = 0; r < 6; ++r) e["covariance_scaled_by_sigma0_squared"].push_back(std::vector<double>(cov.row(r).begin(), cov.row(r).end()));
    e["observations"] = f.observations;
    e["rms_x_um"] = f.rms_x_um;
    e["rms_y_um"] = f.rms_y_um;
    j["frames"].push_back(e);
  }
  j["points"] = ordered_json::array();
  for (const BundlePointResult& p : result.points) {
    ordered_json e{{"id", p.id}, {"control", p.control}, {"rays", p.rays},
                   {"x_m", p.position_m.x()}, {"y_m", p.position_m.y()}, {"z_m", p.position_m.z()}};
    e["sigma_m"] = p.sigma_m ? ordered_json({p.sigma_m->x(), p.sigma_m->y(), p.sigma_m->z()}) : ordered_json(nullptr);
    e["rms_um"] = p.rms_um;
    j["points"].push_back(e);
  }
  j["worst_observations"] = ordered_json::array();
  for (const ObservationResidual* r : WorstObservations(result, options.worst_observations)) {
    j["worst_observations"].push_back({{"frame", r->group}, {"point_id", r->item}, {"origin", r->origin},
                                       {"status", r->status == ObservationStatus::kUsed ? "used" : "rejected"},
                                       {"residual_um", {1e3 * r->residual[0], 1e3 * r->residual[1]}},
                                       {"normalized", r->normalized}, {"reason", r->reason}});
  }
  j["warnings"] = ordered_json::array();
  for (const BundleWarning& w : options.warnings) j["warnings"].push_back({{"item", w.item}, {"reason", w.reason}});
  j["timing_s"] = {{"approximations", result.initial_seconds}, {"solve", a.solve_seconds},
                   {"covariance", a.covariance_seconds}};
  return j.dump(2) + "\n";
}

}  // namespace platemeter
