// The comparator corrections end to end (plate_corrections.h).
#include "platemeter/measure/plate_corrections.h"

#include "platemeter/core/scan_orientation.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <boost/math/distributions/chi_squared.hpp>
#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/measure/local_reseau.h"
#include "platemeter/core/number_text.h"

namespace platemeter {
namespace {


bool Usable(const MeasuredPoint& p) {
  return p.status == PointStatus::kMeasured && p.x_px && p.y_px && p.sigma_x_px && p.sigma_y_px;
}

PlanePoint PlanePointFromPixels(const MeasuredPoint& p) {
  return {*p.x_px, *p.y_px, {*p.sigma_x_px * *p.sigma_x_px, 0.0, *p.sigma_y_px * *p.sigma_y_px}};
}

}  // namespace

bool PlateCorrectionOptions::Check(std::string* why) const {
  if (!fit.Check(why)) return false;
  if (!fiducial.Check(why)) return false;
  if (!(local_reseau_significance > 0.0 && local_reseau_significance < 1.0)) {
    if (why) *why = "local_reseau_significance must lie in (0, 1)";
    return false;
  }
  if (temperature_degC) {
    ThermalCorrection t{true, *temperature_degC, calibration_temperature_degC, expansion_per_degC};
    if (!t.Check(why)) return false;
  }
  EmulsionDepthCorrection e;
  e.model = emulsion;
  return e.Check(why);
}

namespace {

// The comparator and thermal steps from the options and the file header.
void SetUpEarlySteps(MeasurementFile* file, const PlateCorrectionOptions& options, const std::string& subject,
                     PlateCorrectionReport* report) {
  std::string why;
  if (!options.Check(&why)) throw Error(subject, why);
  report->comparator.pixel_size_um = options.pixel_size_um.value_or(file->header.pixel_size_um.value_or(0.0));
  std::string orientation = "0";
  for (const auto& [key, value] : file->header.extra) {
    if (key == "orientation") orientation = value;
  }
  if (options.orientation) orientation = *options.orientation;
  ScanOrientation scan_orientation;
  if (!ParseScanOrientation(orientation, &scan_orientation)) {
    throw Error(subject, "unknown scan orientation '" + orientation + "'");
  }
  report->comparator.orientation_deg = scan_orientation.rotation_deg;
  report->comparator.mirrored = scan_orientation.mirrored;
  if (!report->comparator.Check(&why)) throw Error(subject, why + " (give the pixel size)");

  report->thermal.enabled = options.temperature_degC.has_value();
  report->thermal.temperature_degC = options.temperature_degC.value_or(options.calibration_temperature_degC);
  report->thermal.calibration_temperature_degC = options.calibration_temperature_degC;
  report->thermal.expansion_per_degC = options.expansion_per_degC;
}

// The local correction's test (PlateCorrectionOptions::local_reseau): the
// used crosses' chi-square v'Pv = sigma0^2 (2 n - u) against chi-square(2 n - u).
// Where it does not reject, the residuals are measuring noise: interpolating
// them adds the corner crosses' errors to every point of a cell as one shared
// error (10 rendered Orbigon glass plates: the stellar camera's spread up to
// 2.2x its sigma with it, within sampling of 1 without; docs/measure.md).
void TestFilmDeformation(const PlateCorrectionOptions& options, PlateCorrectionReport* report) {
  const ReseauFit& fit = report->fit;
  report->reseau_dof = 2 * fit.used - fit.parameter_count;
  report->reseau_chi2 = fit.sigma0 * fit.sigma0 * std::max(report->reseau_dof, 0);
  if (report->reseau_dof <= 0) {
    report->reseau_p_value = 1.0;  // no redundancy: nothing tells deformation from noise
  } else {
    const boost::math::chi_squared distribution(report->reseau_dof);
    report->reseau_p_value = boost::math::cdf(boost::math::complement(distribution, report->reseau_chi2));
  }
  report->local_reseau_applied =
      options.local_reseau && report->reseau_p_value < options.local_reseau_significance;
}

void WriteMm(const PlanePoint& q, MeasuredPoint* p) {
  p->x_mm = q.x;
  p->y_mm = q.y;
  p->sigma_x_mm = std::sqrt(q.cov.xx);
  p->sigma_y_mm = std::sqrt(q.cov.yy);
}

}  // namespace

PlateCorrectionReport CorrectPlate(MeasurementFile* file, const MasterGrid& grid, const PlateCorrectionOptions& options) {
  const std::string subject = file->header.plate_id.empty() ? "measurement file" : file->header.plate_id;
  PlateCorrectionReport report;
  SetUpEarlySteps(file, options, subject, &report);

  auto early = [&](const MeasuredPoint& p) { return report.thermal.Apply(report.comparator.Apply(PlanePointFromPixels(p))); };

  // The crosses after comparator + thermal; a preliminary similarity fit
  // places the principal point in the comparator frame for the radial model.
  std::vector<ReseauObservation> observations;
  std::vector<size_t> observation_row;
  for (size_t k = 0; k < file->points.size(); ++k) {
    const MeasuredPoint& p = file->points[k];
    if (p.kind != PointKind::kReseau || !Usable(p)) continue;
    const GridPoint* g = grid.Find(p.id);
    if (!g) continue;
    observations.push_back({p.id, g->x_mm, g->y_mm, early(p)});
    observation_row.push_back(k);
  }
  report.emulsion.enabled = options.emulsion.depth_um > 0.0;
  report.emulsion.model = options.emulsion;
  if (report.emulsion.enabled) {
    ReseauFitOptions similarity = options.fit;
    similarity.model = ReseauFitModel::kSimilarity;
    const ReseauFit pre = FitReseau(observations, similarity);
    pre.Forward(options.principal_point_x_mm, options.principal_point_y_mm, &report.emulsion.centre_x_mm,
                &report.emulsion.centre_y_mm);
    for (ReseauObservation& o : observations) o.measured = report.emulsion.Apply(o.measured);
  }

  report.fit = FitReseau(observations, options.fit);
  report.observations = observations;
  const double n = options.emulsion.refractive_index, c = options.emulsion.principal_distance_mm;
  // Read through the exact model fitted over the used crosses (as a scale-only
  // fit about the principal point would see it), not the small-angle scale.
  std::vector<double> radii_mm;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (report.fit.is_rejected[i]) continue;
    radii_mm.push_back(std::hypot(observations[i].grid_x_mm - options.principal_point_x_mm,
                                  observations[i].grid_y_mm - options.principal_point_y_mm));
  }
  EmulsionDepthModel unit{1.0, n, c};
  const double per_um = unit.FittedScale(radii_mm) - 1.0;
  report.emulsion_depth_reading_um = {(report.fit.mean_scale.value - 1.0) / per_um, report.fit.mean_scale.sigma / per_um};

  // Residuals of the used crosses, for the local correction.
  std::map<std::string, PlanePoint> residuals;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (report.fit.is_rejected[i]) continue;
    const PlanePoint g = report.fit.ToGrid(observations[i].measured);
    residuals[observations[i].id] = {report.fit.residual_x_mm[i], report.fit.residual_y_mm[i], g.cov};
  }
  const LocalReseauCorrection local(grid, residuals);
  TestFilmDeformation(options, &report);

  std::map<size_t, size_t> observation_of_row;
  for (size_t i = 0; i < observation_row.size(); ++i) observation_of_row[observation_row[i]] = i;
  std::vector<PlanePoint> positions(file->points.size());
  std::vector<bool> has_position(file->points.size(), false);
  for (size_t k = 0; k < file->points.size(); ++k) {
    MeasuredPoint& p = file->points[k];
    if (!Usable(p)) continue;
    PlanePoint q = report.emulsion.Apply(early(p));
    q = report.fit.ToGrid(q);
    if (p.kind == PointKind::kReseau) {
      // A cross keeps its globally fitted position (its residual is the report).
      const auto it = observation_of_row.find(k);
      if (it != observation_of_row.end() && report.fit.is_rejected[it->second]) p.flags.push_back("reseau_fit:rejected");
      if (it == observation_of_row.end()) p.flags.push_back("reseau_fit:not_in_grid");
    } else if (report.local_reseau_applied) {
      q = local.Apply(q, &p.flags);
    }
    positions[k] = q;
    has_position[k] = true;
    ++report.points_corrected;
  }

  // Optionally the fiducial interior orientation on top (reseau cameras).
  if (options.fiducial_orientation) {
    try {
      report.fiducial = ApplyFiducialOrientation(file, &positions, has_position, options.fiducials, options.fiducial);
    } catch (const Error& e) {
      throw Error(subject, e.what());
    }
  }
  for (size_t k = 0; k < file->points.size(); ++k) {
    if (has_position[k]) WriteMm(positions[k], &file->points[k]);
  }

  // The header, in application order.
  auto& corrections = file->header.corrections;
  corrections.push_back(report.comparator.Record());
  if (report.thermal.enabled) corrections.push_back(report.thermal.Record());
  if (report.emulsion.enabled) corrections.push_back(report.emulsion.Record());
  AppliedCorrection fit{"reseau_fit", {{"model", ReseauFitModelName(report.fit.model)}, {"grid", grid.name}}};
  const std::vector<std::string> names = report.fit.ParameterNames();
  for (size_t k = 0; k < names.size(); ++k) {
    fit.parameters.push_back({names[k], ShortestText(report.fit.parameters[k])});
    fit.parameters.push_back({"sigma_" + names[k], ShortestText(std::sqrt(report.fit.covariance[9 * k]))});
  }
  fit.parameters.push_back({"sigma0", ShortestText(report.fit.sigma0)});
  fit.parameters.push_back({"rms_mm", ShortestText(report.fit.rms_mm)});
  fit.parameters.push_back({"crosses_used", std::to_string(report.fit.used)});
  fit.parameters.push_back({"crosses_rejected", std::to_string(report.fit.rejected)});
  corrections.push_back(fit);
  if (options.local_reseau) {
    corrections.push_back({"local_reseau",
                           {{"interpolation", "bilinear"},
                            {"applied", report.local_reseau_applied ? "yes" : "no"},
                            {"reseau_chi2", ShortestText(report.reseau_chi2)},
                            {"reseau_dof", std::to_string(report.reseau_dof)},
                            {"p_value", ShortestText(report.reseau_p_value)}}});
  }
  if (report.fiducial) corrections.push_back(report.fiducial->Record(options.fiducial_source));
  return report;
}

PlateCorrectionReport CorrectFiducialPlate(MeasurementFile* file, const PlateCorrectionOptions& options) {
  const std::string subject = file->header.plate_id.empty() ? "measurement file" : file->header.plate_id;
  PlateCorrectionReport report;
  SetUpEarlySteps(file, options, subject, &report);
  std::vector<PlanePoint> positions(file->points.size());
  std::vector<bool> has_position(file->points.size(), false);
  for (size_t k = 0; k < file->points.size(); ++k) {
    const MeasuredPoint& p = file->points[k];
    if (!Usable(p)) continue;
    positions[k] = report.thermal.Apply(report.comparator.Apply(PlanePointFromPixels(p)));
    has_position[k] = true;
  }
  try {
    // Emulsion depth about the principal point, placed in the comparator
    // frame by a preliminary similarity fit of the fiducials (on a scratch copy).
    report.emulsion.enabled = options.emulsion.depth_um > 0.0;
    report.emulsion.model = options.emulsion;
    if (report.emulsion.enabled) {
      MeasurementFile scratch = *file;
      std::vector<PlanePoint> scratch_positions = positions;
      FiducialOrientationOptions similarity = options.fiducial;
      similarity.model = ReseauFitModel::kSimilarity;
      const FiducialOrientation pre =
          ApplyFiducialOrientation(&scratch, &scratch_positions, has_position, options.fiducials, similarity);
      pre.fit.Forward(options.principal_point_x_mm, options.principal_point_y_mm, &report.emulsion.centre_x_mm,
                      &report.emulsion.centre_y_mm);
      for (size_t k = 0; k < positions.size(); ++k) {
        if (has_position[k]) positions[k] = report.emulsion.Apply(positions[k]);
      }
    }
    report.fiducial = ApplyFiducialOrientation(file, &positions, has_position, options.fiducials, options.fiducial);
  } catch (const Error& e) {
    throw Error(subject, e.what());
  }
  for (size_t k = 0; k < file->points.size(); ++k) {
    if (!has_position[k]) continue;
    WriteMm(positions[k], &file->points[k]);
    ++report.points_corrected;
  }
  auto& corrections = file->header.corrections;
  corrections.push_back(report.comparator.Record());
  if (report.thermal.enabled) corrections.push_back(report.thermal.Record());
  if (report.emulsion.enabled) corrections.push_back(report.emulsion.Record());
  corrections.push_back(report.fiducial->Record(options.fiducial_source));
  return report;
}

}  // namespace platemeter
