// The `platemeter measure` flow as a function (measure_run.h): detect, correct,
// write the measurement file, the JSON report, the residual plot and the MicMac
// measures atomically, and say what was done. RunValidate is in validate_run.cpp,
// CanonicalOptionsText in measure_options_text.cpp.
#include "platemeter/pipeline/measure_run.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <new>
#include <sstream>

#include "measure_prepare.h"
#include "measure_report.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/error.h"
#include "platemeter/core/output_set.h"
#include "platemeter/measure/double_measurement.h"
#include "platemeter/measure/micmac_export.h"
#include "platemeter/measure/residual_plot.h"

namespace platemeter::pipeline {
namespace {

// An error that does not name the scan yet gets it as its subject, so a batch log line says which scan failed.
// The kind is kept: a failure of the machine (EnvironmentError, no memory, a file-system call) stays one, so
// that batch retries it on a rerun.
[[noreturn]] void RethrowNaming(const std::string& scan) {
  try {
    throw;
  } catch (const EnvironmentError& e) {
    if (std::string(e.what()).find(scan) != std::string::npos) throw;
    throw EnvironmentError(scan, e.what());
  } catch (const Error& e) {
    if (std::string(e.what()).find(scan) != std::string::npos) throw;
    throw Error(scan, e.what());
  } catch (const std::bad_alloc&) {
    throw EnvironmentError(scan, "out of memory");
  } catch (const std::filesystem::filesystem_error& e) {
    throw EnvironmentError(scan, OneLine(e.what()));
  } catch (const std::exception& e) {
    throw Error(scan, OneLine(e.what()));
  }
}

PreparedMeasurement Prepare(const MeasureRequest& request, const DefinitionRegistry& registry, std::string* messages) {
  try {
    return PrepareMeasurement(request, registry, true, messages);
  } catch (...) {
    RethrowNaming(request.detect.scan);
  }
}

std::string FractionText(double fraction) {
  std::ostringstream text;
  text << fraction;
  return text.str();
}

// A fit of a few crosses extrapolates over the plate without saying so: too few is a failed scan
// (checked on the measured crosses before the fit, and on the ones it kept after).
void CheckCrossCount(const PreparedMeasurement& p, int usable, double min_fraction, const std::string& scan) {
  if (!p.grid) return;
  const int grid = static_cast<int>(p.grid->points.size());
  const int needed = static_cast<int>(std::ceil(min_fraction * grid - 1e-9));
  if (usable >= needed) return;
  throw Error(scan, "only " + std::to_string(usable) + " of the " + std::to_string(grid) + " crosses of grid '" +
                        p.grid->name + "' usable for the reseau fit, " + std::to_string(needed) +
                        " needed (min_cross_fraction " + FractionText(min_fraction) +
                        "): wrong camera or pixel size, or most crosses hidden or damaged");
}

PlateCorrectionReport Correct(PreparedMeasurement* prepared, const MeasureRequest& request, const std::string& scan) {
  int measured = 0;
  for (const MeasuredPoint& point : prepared->file.points)
    measured += point.kind == PointKind::kReseau && point.status == PointStatus::kMeasured;
  CheckCrossCount(*prepared, measured, request.min_cross_fraction, scan);
  PlateCorrectionReport report;
  try {
    report = CorrectPrepared(prepared);
  } catch (...) {
    RethrowNaming(scan);
  }
  CheckCrossCount(*prepared, report.fit.used, request.min_cross_fraction, scan);
  return report;
}

nlohmann::json ReportJson(const MeasureRequest& request, const PreparedMeasurement& p, const PlateCorrectionReport& report) {
  nlohmann::json j;
  j["scan"] = request.detect.scan;
  j["camera"] = request.detect.camera;
  if (p.grid) j["grid"] = p.grid->name;
  j["corrections"] = nlohmann::json::array();
  for (const AppliedCorrection& c : p.file.header.corrections) {
    nlohmann::json params = nlohmann::json::object();
    for (const auto& [k, v] : c.parameters) params[k] = v;
    j["corrections"].push_back({{"name", c.name}, {"parameters", params}});
  }
  j["points_corrected"] = report.points_corrected;
  // Non-finite pixels of a float scan, masked by detection (docs/detect.md, "Masked pixels").
  j["masked_pixels"] = 0;
  for (const auto& [key, value] : p.file.header.extra) {
    if (key == "masked_pixels") j["masked_pixels"] = std::stol(value);
  }
  if (p.grid) j["reseau"] = ValidationJson(report, request.tolerance_um);
  if (report.fiducial) j["fiducial_orientation"] = FiducialJson(*report.fiducial);
  return j;
}

// The files of one measured scan (docs/measure.md), written as one set.
std::vector<std::string> MeasureSetMembers(const std::string& stem) {
  return {stem + ".measurements.csv", stem + ".measure.json", stem + ".residuals.png", stem + ".micmac.xml"};
}

MeasureSummary Run(const MeasureRequest& request, const DefinitionRegistry& registry) {
  CheckMeasureOptions(request);
  const std::string stem = PlateStem(request.detect.scan);
  // Created before any work: a folder that cannot take the outputs fails the run at once.
  OutputSet outputs(request.out_dir, MeasureSetMembers(stem));
  std::ostringstream console;
  std::string messages;
  PreparedMeasurement p = Prepare(request, registry, &messages);
  const PlateCorrectionReport report = Correct(&p, request, request.detect.scan);
  console << messages;
  nlohmann::json double_json;
  if (!request.second_scan.empty()) {
    MeasureRequest second = request;
    second.detect.scan = request.second_scan;
    second.detect.orientation = request.second_orientation;
    std::string second_messages;
    PreparedMeasurement q = Prepare(second, registry, &second_messages);
    const PlateCorrectionReport second_report = Correct(&q, request, request.second_scan);
    DoubleMeasurementReport d;
    try {
      d = MeanDoubleMeasurement(&p.file, q.file);
    } catch (...) {
      RethrowNaming(request.second_scan);
    }
    console << second_messages << "double measurement: " << d.paired << " points paired, rms discrepancy "
            << d.rms_discrepancy_mm * 1e3 << " um (" << d.rms_normalized << " of the sigmas)\n";
    double_json = DoubleMeasurementJson(request.second_scan, second_report, p.grid != nullptr, d, request.tolerance_um);
  }

  const std::string csv = stem + ".measurements.csv", json = stem + ".measure.json", png = stem + ".residuals.png",
                    xml = stem + ".micmac.xml";
  MeasureSummary summary;
  auto written = [&summary, &outputs](const std::string& name) {
    summary.written_files.push_back(std::filesystem::absolute(outputs.FinalPath(name)).lexically_normal().string());
    return summary.written_files.back();
  };
  outputs.Write(csv, [&](const std::string& path) { WriteMeasurementFile(path, p.file); });
  outputs.Write(xml, [&](const std::string& path) { WriteMicMacMeasures(path, p.file); });
  if (p.grid) {
    ResidualPlotOptions plot;
    plot.tolerance_um = request.tolerance_um;
    outputs.Write(png, [&](const std::string& path) { WriteResidualPlotPng(path, report.observations, report.fit, plot); });
  }
  nlohmann::json j = ReportJson(request, p, report);
  if (!double_json.is_null()) j["double_measurement"] = double_json;
  outputs.Write(json, [&](const std::string& path) { WriteFileAtomically(path, j.dump(2) + "\n"); });
  outputs.Commit();
  written(csv);
  written(xml);
  if (p.grid) summary.plot_png = written(png);
  summary.report_json = written(json);

  if (p.grid) {
    console << "reseau fit (" << ReseauFitModelName(report.fit.model) << "): " << report.fit.used << " crosses, "
            << report.fit.rejected << " rejected, rms " << report.fit.rms_mm * 1e3 << " um, sigma0 " << report.fit.sigma0
            << " (" << report.reseau_dof << " dof); local reseau correction ";
    if (request.no_local) {
      console << "off (--no-local-reseau)\n";
    } else {
      console << (report.local_reseau_applied ? "applied" : "not applied") << " (p = " << report.reseau_p_value
              << (report.local_reseau_applied ? ": film deformation)\n" : ": the residuals are measuring noise)\n");
    }
  }
  if (report.fiducial) {
    const ReseauFit& f = report.fiducial->fit;
    console << "fiducial orientation (" << ReseauFitModelName(f.model) << "): " << f.used << " fiducials, " << f.rejected
            << " rejected, rms " << f.rms_mm * 1e3 << " um, sigma0 " << f.sigma0 << "\n";
  }
  console << outputs.FinalPath(csv) << "\n" << outputs.FinalPath(json) << "\n";
  if (p.grid) console << outputs.FinalPath(png) << "\n";
  console << outputs.FinalPath(xml) << "\n";

  summary.plate_id = p.stem;
  for (const MeasuredPoint& point : p.file.points) {
    ++summary.counts_by_status[PointStatusName(point.status)];
    ++summary.counts_by_kind[PointKindName(point.kind)];
  }
  if (p.grid) {
    summary.reseau_rms_um = report.fit.rms_mm * 1e3;
    summary.scale_x = report.fit.scale_x.value;
    summary.scale_y = report.fit.scale_y.value;
  }
  summary.message = console.str();
  return summary;
}

}  // namespace

MeasureSummary RunMeasure(const MeasureRequest& request, const DefinitionRegistry& registry) {
  try {
    return Run(request, registry);
  } catch (...) {
    RethrowNaming(request.detect.scan);
  }
}

}  // namespace platemeter::pipeline
