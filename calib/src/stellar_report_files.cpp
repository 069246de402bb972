// calibration.json, the CSV files and the writing of
// a stellar calibration job's outputs (stellar_report.h).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "platemeter/calib/stellar_report.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/definition_io.h"
#include "output_files.h"
#include "report_json.h"

namespace platemeter {
namespace {

using nlohmann::ordered_json;

// The plate frame with the lens model's names; an orbigon-11 camera in seed 001's printed frame too.
ordered_json CameraJson(DistortionModelId lens, const StellarCamera& values, const StellarCamera& sigmas) {
  ordered_json j;
  ordered_json plate = ordered_json::object();
  const std::vector<std::string> names = StellarCameraParamNames(lens);
  for (size_t i = 0; i < names.size(); ++i) plate[names[i]] = {{"value", values[i]}, {"sigma", sigmas[i]}};
  j["plate_frame"] = plate;
  if (lens == DistortionModelId::kSlama) {
    const PrintedCamera p = ToPrinted(values, sigmas);
    ordered_json printed = ordered_json::object();
    for (int i = 0; i < kStellarCameraParams; ++i) printed[kPrintedCameraNames[i]] = {{"value", p.value[i]}, {"sigma", p.sigma[i]}};
    j["seed001_printed_frame"] = printed;
  }
  return j;
}

ordered_json PlateJson(DistortionModelId lens, const StellarPlateResult& s, const std::optional<IdentificationResult>& id) {
  ordered_json j;
  j["id"] = s.plate_id;
  j["group"] = s.group;
  j["catalog_stars"] = s.catalog_stars;
  j["unknown_stars"] = s.unknown_stars;
  j["images"] = s.images;
  j["rejected_images"] = s.rejected_images;
  j["camera"] = CameraJson(lens, s.camera, s.camera_sigma);
  j["deformation"] = {{"cx_mm", s.cx_mm}, {"cx_sigma_mm", s.cx_sigma_mm}, {"cy_mm", s.cy_mm},
                      {"cy_sigma_mm", s.cy_sigma_mm}, {"epsilon_rad", s.epsilon_rad},
                      {"epsilon_sigma_rad", s.epsilon_sigma_rad}};
  j["orientation_sets"] = ordered_json::array();
  for (const OrientationSetResult& o : s.orientation_sets) {
    j["orientation_sets"].push_back({{"index", o.index}, {"start_s", o.start_s}, {"end_s", o.end_s},
                                     {"images", o.images}, {"axis_azimuth_deg", o.axis_azimuth_deg},
                                     {"axis_altitude_deg", o.axis_altitude_deg}, {"roll_deg", o.roll_deg},
                                     {"sigma_arcsec", o.sigma_arcsec}});
  }
  j["largest_motion_arcsec"] = s.largest_motion_arcsec;
  j["m_o"] = s.m_o;
  j["m_p_um"] = s.m_p_um;
  j["statistics"] = StatisticsJson(s.adjustment);
  j["rank"] = RankReportJson(s.adjustment.rank);
  if (id) {
    j["identification"] = {{"identified", id->catalog_id.size()}, {"unknown", id->unknown.size()},
                           {"ambiguous", id->ambiguous.size()}, {"hypotheses", id->hypotheses_tried},
                           {"false_alarm_probability", id->false_alarm_probability}, {"rms_arcsec", id->rms_arcsec}};
  }
  return j;
}

ordered_json CombinationJson(DistortionModelId lens, const StellarCombination& c) {
  ordered_json j;
  j["name"] = c.name;
  j["plates"] = c.plate_ids;
  j["camera"] = CameraJson(lens, c.camera, c.camera_sigma);
  j["m_0"] = c.m_0;
  j["degrees_of_freedom"] = c.dof;
  j["m_p_um"] = c.m_p_um;
  j["m_p_after_um"] = c.m_p_after_um;
  j["relinearizations"] = c.relinearizations;
  j["pope_one_step_offset_sigma"] = c.one_step_offset_sigma;
  const int n = static_cast<int>(c.camera.size());
  std::vector<std::vector<double>> correlation(n, std::vector<double>(n, 0.0));
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const double d = std::sqrt(c.cofactor(a, a) * c.cofactor(b, b));
      correlation[a][b] = d > 0 ? c.cofactor(a, b) / d : 0.0;
    }
  }
  j["correlation"] = correlation;
  j["consistency"] = ordered_json::array();
  for (const PlateConsistency& t : c.consistency) {
    j["consistency"].push_back({{"plate", t.plate_id}, {"F", t.f_statistic}, {"k", t.k}, {"p_value", t.p_value},
                                {"rejected", t.rejected}});
  }
  return j;
}

ordered_json InterlockJson(DistortionModelId lens, const StellarInterlockResult& r) {
  ordered_json j;
  j["exposures"] = r.exposures;
  j["cameras"] = ordered_json::array();
  for (const InterlockCameraResult& c : r.cameras) {
    j["cameras"].push_back({{"name", c.name}, {"plates", c.plates}, {"stars", c.stars}, {"images", c.images},
                            {"rejected_images", c.rejected_images}, {"rms_residual_um", c.rms_residual_um},
                            {"camera", CameraJson(lens, c.camera, c.camera_sigma)}});
  }
  j["interlocks"] = ordered_json::array();
  for (const CameraInterlockResult& i : r.interlocks) {
    std::vector<std::vector<double>> matrix(3), covariance(3), elements(9);
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        matrix[a].push_back(i.matrix(a, b));
        covariance[a].push_back(i.angles.covariance_rad2(a, b));
      }
    }
    for (int a = 0; a < 9; ++a) {
      for (int b = 0; b < 9; ++b) elements[a].push_back(i.element_covariance(a, b));
    }
    j["interlocks"].push_back(
        {{"from", i.from}, {"to", i.to}, {"matrix", matrix},
         {"convention", "to_from_from = R3(kappa) R2(phi) R1(omega), seed 004 Table A.6"},
         {"omega_rad", i.angles.angles.omega_rad}, {"phi_rad", i.angles.angles.phi_rad},
         {"kappa_rad", i.angles.angles.kappa_rad}, {"omega_sigma_arcsec", i.angles.omega_sigma_arcsec},
         {"phi_sigma_arcsec", i.angles.phi_sigma_arcsec}, {"kappa_sigma_arcsec", i.angles.kappa_sigma_arcsec},
         {"angle_covariance_rad2", covariance}, {"element_covariance", elements}, {"summary", i.angles.summary}});
  }
  j["statistics"] = StatisticsJson(r.adjustment);
  j["rank"] = RankReportJson(r.adjustment.rank);
  return j;
}

}  // namespace

std::string FormatStellarJson(const StellarJob& job, const StellarJobResult& result) {
  ordered_json j;
  j["title"] = job.title;
  j["adjustment"] = "stellar calibration (seed 001), docs/stellar.md";
  j["cameras"] = ordered_json::array();
  for (const CameraDefinition& c : job.cameras) j["cameras"].push_back(c.name);
  const DistortionModelId lens = job.options.lens_model;
  j["lens_model"] = DistortionModelName(lens);
  j["frames"] = lens == DistortionModelId::kSlama
                    ? "plate_frame: x right, y up, xs/ys from the principal point, Phi_T rad; seed001_printed_frame: "
                      "left-handed (y down), um, xs/ys from the reseau centre, Phi_T deg"
                    : "plate_frame: x right, y up, the lens model's parameters (distortion_models.h) about the "
                      "principal point";
  j["catalog"] = {{"path", job.catalog_path}, {"magnitude_limit", job.magnitude_limit},
                  {"sigma_arcsec", job.catalog_sigma_arcsec}, {"stars", result.catalog.size()}};
  j["plates"] = ordered_json::array();
  for (size_t i = 0; i < result.singles.size(); ++i) {
    ordered_json plate = PlateJson(lens, result.singles[i], result.identification[i]);
    plate["camera_name"] = job.cameras[job.plates[i].camera].name;
    plate["exposure"] = job.plates[i].exposure;
    j["plates"].push_back(std::move(plate));
  }
  j["combinations"] = ordered_json::array();
  for (size_t k = 0; k < result.combinations.size(); ++k) {
    ordered_json c = CombinationJson(lens, result.combinations[k]);
    c["camera_name"] = job.cameras[result.combination_camera[k]].name;
    j["combinations"].push_back(std::move(c));
  }
  if (result.interlock) j["interlock"] = InterlockJson(lens, *result.interlock);
  return j.dump(2) + "\n";
}

std::string FormatStellarResidualsCsv(const StellarJobResult& result) {
  std::string out = "plate,image,star,status,vx_um,vy_um,normalized_x,normalized_y,origin,reason\n";
  for (const StellarPlateResult& s : result.singles) {
    for (const ObservationResidual& r : s.adjustment.residuals) {
      const size_t space = r.item.find(' ');
      const std::string image = r.item.substr(0, space);
      std::string star = space == std::string::npos ? "" : r.item.substr(space + 1);
      if (star.size() >= 2 && star.front() == '(') star = star.substr(1, star.size() - 2);
      out += fmt::format("{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{},{}\n", s.plate_id, image, star,
                         r.status == ObservationStatus::kUsed ? "used" : "rejected", 1e3 * r.residual[0],
                         1e3 * r.residual[1], r.normalized[0], r.normalized[1], r.origin, r.reason);
    }
  }
  return out;
}

std::string FormatIdentificationCsv(const StellarJobResult& result) {
  std::string out = "plate,star_key,catalog_key,status\n";
  for (size_t i = 0; i < result.identification.size(); ++i) {
    if (!result.identification[i]) continue;
    const IdentificationResult& r = *result.identification[i];
    const std::string& plate = result.singles[i].plate_id;
    for (const auto& [key, id] : r.catalog_id) out += fmt::format("{},{},{},identified\n", plate, key, id);
    for (const std::string& key : r.unknown) {
      const bool ambiguous = std::find(r.ambiguous.begin(), r.ambiguous.end(), key) != r.ambiguous.end();
      out += fmt::format("{},{},,{}\n", plate, key, ambiguous ? "ambiguous" : "unknown");
    }
  }
  return out;
}

std::vector<std::string> WriteStellarOutputs(const std::string& dir, const StellarJob& job,
                                             const StellarJobResult& result,
                                             const std::vector<std::pair<std::string, std::string>>& extra_files) {
  // Every text is formatted before the first file is written: a failure leaves no partial set.
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back("calibration.json", FormatStellarJson(job, result));
  files.emplace_back("report.md", FormatStellarMarkdown(job, result));
  files.emplace_back("residuals.csv", FormatStellarResidualsCsv(result));
  files.emplace_back("identification.csv", FormatIdentificationCsv(result));
  for (size_t k = 0; k < job.cameras.size(); ++k) {
    files.emplace_back("camera-" + job.cameras[k].name + "-stellar.toml",
                       "# " + job.title + "\n# Format: docs/definitions.md\n\n" +
                           ToToml(StellarCameraDefinition(job, result, static_cast<int>(k))));
  }
  files.insert(files.end(), extra_files.begin(), extra_files.end());
  return WriteOutputFiles(dir, files);
}

}  // namespace platemeter
