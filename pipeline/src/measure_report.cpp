// The JSON pieces of the measure and validate reports (measure_report.h).
#include "measure_report.h"

#include <cmath>
#include <vector>

namespace platemeter::pipeline {
namespace {

nlohmann::json Vs(const ValueSigma& v) { return {{"value", v.value}, {"sigma", v.sigma}}; }

// What every fit report starts with: model, counts (under `counted`), sigma0, RMS, parameters with sigmas.
nlohmann::json FitJson(const ReseauFit& f, const char* counted) {
  nlohmann::json j;
  j["model"] = ReseauFitModelName(f.model);
  j[counted] = {{"used", f.used}, {"rejected", f.rejected}};
  j["sigma0"] = f.sigma0;
  j["rms_um"] = f.rms_mm * 1e3;
  nlohmann::json params = nlohmann::json::object();
  const std::vector<std::string> names = f.ParameterNames();
  for (size_t k = 0; k < names.size(); ++k) {
    params[names[k]] = {{"value", f.parameters[k]}, {"sigma", std::sqrt(f.covariance[9 * k])}};
  }
  j["parameters"] = params;
  return j;
}

}  // namespace

nlohmann::json ValidationJson(const PlateCorrectionReport& r, double tolerance_um) {
  const ReseauFit& f = r.fit;
  nlohmann::json j = FitJson(f, "crosses");
  j["scale_x"] = Vs(f.scale_x);
  j["scale_y"] = Vs(f.scale_y);
  j["mean_scale"] = Vs(f.mean_scale);
  j["non_orthogonality_arcsec"] = Vs({f.non_orthogonality_rad.value * kRadToArcsec, f.non_orthogonality_rad.sigma * kRadToArcsec});
  j["rotation_deg"] = Vs({f.rotation_rad.value * 180.0 / M_PI, f.rotation_rad.sigma * 180.0 / M_PI});
  j["scale_discrepancy_ppm"] = Vs({(f.mean_scale.value - 1.0) * 1e6, f.mean_scale.sigma * 1e6});
  j["emulsion_depth_reading_um"] = Vs(r.emulsion_depth_reading_um);
  j["emulsion_depth_reading_note"] =
      r.emulsion.enabled ? "the emulsion-depth correction was applied: the reading is what remains"
                         : "the scale discrepancy read as an emulsion depth (exact radial model fitted over the used crosses)";
  nlohmann::json rows = nlohmann::json::array();
  int out_of_tolerance = 0;
  for (size_t i = 0; i < r.observations.size(); ++i) {
    const double rx = f.residual_x_mm[i] * 1e3, ry = f.residual_y_mm[i] * 1e3;
    const bool out = std::hypot(rx, ry) > tolerance_um;
    out_of_tolerance += out && !f.is_rejected[i];
    rows.push_back({{"id", r.observations[i].id},
                    {"grid_x_mm", r.observations[i].grid_x_mm},
                    {"grid_y_mm", r.observations[i].grid_y_mm},
                    {"residual_x_um", rx},
                    {"residual_y_um", ry},
                    {"rejected", static_cast<bool>(f.is_rejected[i])},
                    {"out_of_tolerance", out}});
  }
  j["residuals"] = rows;
  j["local_reseau"] = {{"applied", r.local_reseau_applied},
                       {"chi2", r.reseau_chi2},
                       {"degrees_of_freedom", r.reseau_dof},
                       {"p_value", r.reseau_p_value},
                       {"note", "applied when the residuals' chi-square rejects pure measuring noise at p < 0.01"}};
  j["tolerance_um"] = tolerance_um;
  j["flags"] = {{"rms_out_of_tolerance", f.rms_mm * 1e3 > tolerance_um},
                {"crosses_out_of_tolerance", out_of_tolerance},
                {"crosses_rejected", f.rejected}};
  return j;
}

nlohmann::json FiducialJson(const FiducialOrientation& o) {
  const ReseauFit& f = o.fit;
  nlohmann::json j = FitJson(f, "fiducials");
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i = 0; i < o.observations.size(); ++i) {
    rows.push_back({{"id", o.observations[i].id},
                    {"camera_x_mm", o.observations[i].grid_x_mm},
                    {"camera_y_mm", o.observations[i].grid_y_mm},
                    {"residual_x_um", f.residual_x_mm[i] * 1e3},
                    {"residual_y_um", f.residual_y_mm[i] * 1e3},
                    {"leave_one_out_sigmas", o.leave_one_out[i]},
                    {"rejected", static_cast<bool>(f.is_rejected[i])}});
  }
  j["residuals"] = rows;
  return j;
}

nlohmann::json DoubleMeasurementJson(const std::string& second_scan, const PlateCorrectionReport& second,
                                     bool with_reseau, const DoubleMeasurementReport& report, double tolerance_um) {
  nlohmann::json d;
  d["second_scan"] = second_scan;
  if (with_reseau) d["second_reseau"] = ValidationJson(second, tolerance_um);
  if (second.fiducial) d["second_fiducial_orientation"] = FiducialJson(*second.fiducial);
  d["paired"] = report.paired;
  d["first_only"] = report.only_first;
  d["second_only"] = report.only_second;
  d["rms_discrepancy_um"] = report.rms_discrepancy_mm * 1e3;
  d["rms_normalized"] = report.rms_normalized;
  nlohmann::json rows = nlohmann::json::array();
  for (const PointDiscrepancy& x : report.discrepancies) {
    rows.push_back({{"id", x.id}, {"kind", PointKindName(x.kind)}, {"dx_um", x.dx_mm * 1e3}, {"dy_um", x.dy_mm * 1e3},
                    {"normalized_x", x.normalized_x}, {"normalized_y", x.normalized_y}});
  }
  d["discrepancies"] = rows;
  return d;
}

}  // namespace platemeter::pipeline
