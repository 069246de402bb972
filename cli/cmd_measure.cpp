// platemeter measure SCAN --camera NAME ... -o DIR: detect, then the
// comparator corrections (measure/plate_corrections.h) into a measurement file
// with plate millimetres and a JSON report; platemeter validate SCAN ...: the
// reseau check alone (docs/measure.md).
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.h"
#include "detect_run.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/atomic_file.h"
#include "platemeter/measure/double_measurement.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/micmac_export.h"
#include "platemeter/measure/residual_plot.h"
#include "platemeter/measure/fiducial_orientation.h"
#include "platemeter/measure/plate_corrections.h"

namespace platemeter::cli {
namespace {

constexpr double kRadToArcsec = 206264.80624709636;

struct MeasureArguments {
  DetectRequest detect;
  std::optional<double> temperature_degC;
  std::optional<double> emulsion_depth_um;
  double refractive_index = 1.65;
  std::string model = "scales";
  double rejection_threshold = 4.0;
  double tolerance_um = 5.0;
  bool no_local = false;
  bool fiducial_orientation = false;  // reseau cameras: the fiducial step on top of the reseau
  std::string fiducial_model = "affine";
  std::string second_scan;          // measure: the plate scanned again, rotated 180 deg
  std::string second_orientation;   // its known orientation
  std::string out_dir;
};

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

// The reseau validation: per-cross residuals, RMS, the decomposed linear part
// with sigmas, the scale discrepancy and its reading as an emulsion depth, flags.
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
  j["tolerance_um"] = tolerance_um;
  j["flags"] = {{"rms_out_of_tolerance", f.rms_mm * 1e3 > tolerance_um},
                {"crosses_out_of_tolerance", out_of_tolerance},
                {"crosses_rejected", f.rejected}};
  return j;
}

void AddOptions(CLI::App* cmd, MeasureArguments* args) {
  cmd->add_option("SCAN", args->detect.scan, "the scan, or detect's <scan>.measurements.csv")->required();
  cmd->add_option("--camera", args->detect.camera, "camera definition")->required();
  cmd->add_option("--pixel-size-um", args->detect.pixel_size_um, "scan pixel size in um (default: the TIFF tags / the file header)");
  cmd->add_option("--orientation", args->detect.orientation, "known scan orientation: 0, 90, 180, 270, with m for mirrored");
  cmd->add_flag("--allow-ambiguous-orientation", args->detect.allow_ambiguous, "accept an undecided orientation");
  cmd->add_option("--temperature-degC", args->temperature_degC, "measuring temperature (thermal scaling to the grid's calibration temperature)");
  cmd->add_option("--refractive-index", args->refractive_index, "emulsion refractive index (1.65)");
  cmd->add_option("--model", args->model, "reseau fit model: similarity, affine, scales, projective (scales)");
  cmd->add_option("--rejection-threshold", args->rejection_threshold, "normalized residual above which a cross is rejected (4)");
  cmd->add_option("--tolerance-um", args->tolerance_um, "residual tolerance for the out-of-tolerance flags (5 um)");
  cmd->add_option("-o,--output", args->out_dir, "output folder")->required();
  cmd->add_option("--fiducial-model", args->fiducial_model, "fiducial interior orientation model: similarity, affine (affine)");
}

// The fiducial interior orientation: fit, per-fiducial residuals and leave-one-out discrepancies.
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

struct Prepared {
  MeasurementFile file;
  PlateCorrectionOptions options;
  const MasterGrid* grid = nullptr;
  std::string stem;
};

Prepared Prepare(const MeasureArguments& args, const DefinitionRegistry& registry, bool local) {
  Prepared p;
  const CameraDefinition& camera = registry.Camera(args.detect.camera);
  if (camera.grid.empty() && (!local || (camera.fiducial_set.empty() && !camera.format_corners_as_fiducials))) {
    throw Error("camera '" + camera.name + "'", local ? "has neither a reseau grid nor fiducials to correct with"
                                                      : "has no reseau grid to validate");
  }
  if (!camera.grid.empty()) p.grid = &registry.Grid(camera.grid);
  const std::filesystem::path scan(args.detect.scan);
  if (scan.extension() == ".csv") {
    p.file = ReadMeasurementFile(args.detect.scan);
    p.stem = scan.stem().stem().string();
  } else {
    DetectRun run = RunDetection(args.detect, registry);
    std::cout << run.messages;
    p.file = std::move(run.file);
    p.stem = scan.stem().string();
  }
  PlateCorrectionOptions& o = p.options;
  o.pixel_size_um = args.detect.pixel_size_um;
  if (!args.detect.orientation.empty()) o.orientation = args.detect.orientation;
  o.temperature_degC = args.temperature_degC;
  o.calibration_temperature_degC = camera.calibration_temperature_degC.value_or(
      p.grid ? p.grid->calibration_temperature_degC.value_or(20.0) : 20.0);
  o.expansion_per_degC = camera.glass_expansion_per_degC;
  o.emulsion.depth_um = args.emulsion_depth_um.value_or(0.0);
  o.emulsion.refractive_index = args.refractive_index;
  o.emulsion.principal_distance_mm = camera.lens && camera.lens->principal_distance_mm > 0
                                         ? camera.lens->principal_distance_mm
                                         : camera.nominal_principal_distance_mm;
  if (!ParseReseauFitModel(args.model, &o.fit.model)) {
    throw Error("--model", "'" + args.model + "' is not one of similarity, affine, scales, projective");
  }
  o.fit.rejection_threshold = args.rejection_threshold;
  o.local_reseau = local && !args.no_local;
  o.fiducial_orientation = args.fiducial_orientation;
  o.fiducials = CalibratedFiducials(camera, camera.fiducial_set.empty() ? nullptr : &registry.Fiducials(camera.fiducial_set));
  o.fiducial_source = camera.fiducial_set;
  if (camera.format_corners_as_fiducials) o.fiducial_source += (o.fiducial_source.empty() ? "" : "+") + std::string("format_corners");
  if (!ParseReseauFitModel(args.fiducial_model, &o.fiducial.model) ||
      (o.fiducial.model != ReseauFitModel::kSimilarity && o.fiducial.model != ReseauFitModel::kAffine)) {
    throw Error("--fiducial-model", "'" + args.fiducial_model + "' is not one of similarity, affine");
  }
  return p;
}

}  // namespace

void RegisterMeasureCommand(CLI::App& app, GlobalOptions& global) {
  auto args = std::make_shared<MeasureArguments>();
  auto* cmd = app.add_subcommand("measure", "detect, correct (thermal, emulsion depth, reseau fit, local reseau) and write plate mm");
  AddOptions(cmd, args.get());
  cmd->add_option("--emulsion-depth-um", args->emulsion_depth_um, "depth of the image centroid in the emulsion (0: no correction)");
  cmd->add_flag("--no-local-reseau", args->no_local, "skip the bilinear local reseau correction");
  cmd->add_flag("--fiducial-orientation", args->fiducial_orientation,
                "reseau cameras: also fit the fiducials and map every point into their frame (fiducial-only cameras always)");
  cmd->add_option("--second-scan", args->second_scan, "the plate scanned a second time (rotated 180 deg): both corrected, then meaned");
  cmd->add_option("--second-orientation", args->second_orientation, "the second scan's known orientation (e.g. 180)");
  cmd->callback([args, &global] {
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    Prepared p = Prepare(*args, registry, true);
    auto correct = [](Prepared& x) {
      return x.grid ? CorrectPlate(&x.file, *x.grid, x.options) : CorrectFiducialPlate(&x.file, x.options);
    };
    const PlateCorrectionReport report = correct(p);
    std::optional<PlateCorrectionReport> second_report;
    std::optional<DoubleMeasurementReport> double_report;
    if (!args->second_scan.empty()) {
      MeasureArguments second = *args;
      second.detect.scan = args->second_scan;
      second.detect.orientation = args->second_orientation;
      Prepared q = Prepare(second, registry, true);
      second_report = correct(q);
      double_report = MeanDoubleMeasurement(&p.file, q.file);
      std::cout << "double measurement: " << double_report->paired << " points paired, rms discrepancy "
                << double_report->rms_discrepancy_mm * 1e3 << " um (" << double_report->rms_normalized
                << " of the sigmas)\n";
    }
    std::filesystem::create_directories(args->out_dir);
    const std::filesystem::path dir(args->out_dir);
    const std::string csv = (dir / (p.stem + ".measurements.csv")).string();
    const std::string json = (dir / (p.stem + ".measure.json")).string();
    const std::string png = (dir / (p.stem + ".residuals.png")).string();
    const std::string xml = (dir / (p.stem + ".micmac.xml")).string();
    WriteMeasurementFile(csv, p.file);
    WriteMicMacMeasures(xml, p.file);
    if (p.grid) {
      ResidualPlotOptions plot;
      plot.tolerance_um = args->tolerance_um;
      WriteResidualPlotPng(png, report.observations, report.fit, plot);
    }
    nlohmann::json j;
    j["scan"] = args->detect.scan;
    j["camera"] = args->detect.camera;
    if (p.grid) j["grid"] = p.grid->name;
    j["corrections"] = nlohmann::json::array();
    for (const AppliedCorrection& c : p.file.header.corrections) {
      nlohmann::json params = nlohmann::json::object();
      for (const auto& [k, v] : c.parameters) params[k] = v;
      j["corrections"].push_back({{"name", c.name}, {"parameters", params}});
    }
    j["points_corrected"] = report.points_corrected;
    if (p.grid) j["reseau"] = ValidationJson(report, args->tolerance_um);
    if (report.fiducial) j["fiducial_orientation"] = FiducialJson(*report.fiducial);
    if (double_report) {
      nlohmann::json d;
      d["second_scan"] = args->second_scan;
      if (p.grid) d["second_reseau"] = ValidationJson(*second_report, args->tolerance_um);
      if (second_report->fiducial) d["second_fiducial_orientation"] = FiducialJson(*second_report->fiducial);
      d["paired"] = double_report->paired;
      d["first_only"] = double_report->only_first;
      d["second_only"] = double_report->only_second;
      d["rms_discrepancy_um"] = double_report->rms_discrepancy_mm * 1e3;
      d["rms_normalized"] = double_report->rms_normalized;
      nlohmann::json rows = nlohmann::json::array();
      for (const PointDiscrepancy& x : double_report->discrepancies) {
        rows.push_back({{"id", x.id}, {"kind", PointKindName(x.kind)}, {"dx_um", x.dx_mm * 1e3}, {"dy_um", x.dy_mm * 1e3},
                        {"normalized_x", x.normalized_x}, {"normalized_y", x.normalized_y}});
      }
      d["discrepancies"] = rows;
      j["double_measurement"] = d;
    }
    WriteFileAtomically(json, j.dump(2) + "\n");
    if (p.grid) {
      std::cout << "reseau fit (" << ReseauFitModelName(report.fit.model) << "): " << report.fit.used << " crosses, "
                << report.fit.rejected << " rejected, rms " << report.fit.rms_mm * 1e3 << " um\n";
    }
    if (report.fiducial) {
      const ReseauFit& f = report.fiducial->fit;
      std::cout << "fiducial orientation (" << ReseauFitModelName(f.model) << "): " << f.used << " fiducials, "
                << f.rejected << " rejected, rms " << f.rms_mm * 1e3 << " um, sigma0 " << f.sigma0 << "\n";
    }
    std::cout << csv << "\n" << json << "\n";
    if (p.grid) std::cout << png << "\n";
    std::cout << xml << "\n";
  });

  auto vargs = std::make_shared<MeasureArguments>();
  auto* val = app.add_subcommand("validate", "the reseau check alone: residuals, scales, non-orthogonality, emulsion-depth reading");
  AddOptions(val, vargs.get());
  val->add_option("--emulsion-depth-um", vargs->emulsion_depth_um, "correct this depth first (default none: the discrepancy reads as a depth)");
  val->callback([vargs, &global] {
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    Prepared p = Prepare(*vargs, registry, false);
    const PlateCorrectionReport report = CorrectPlate(&p.file, *p.grid, p.options);
    std::filesystem::create_directories(vargs->out_dir);
    const std::string json = (std::filesystem::path(vargs->out_dir) / (p.stem + ".validate.json")).string();
    const nlohmann::json j = ValidationJson(report, vargs->tolerance_um);
    WriteFileAtomically(json, j.dump(2) + "\n");
    const std::string png = (std::filesystem::path(vargs->out_dir) / (p.stem + ".residuals.png")).string();
    ResidualPlotOptions plot;
    plot.tolerance_um = vargs->tolerance_um;
    WriteResidualPlotPng(png, report.observations, report.fit, plot);
    const ReseauFit& f = report.fit;
    std::cout << "reseau fit (" << ReseauFitModelName(f.model) << "): " << f.used << " crosses, " << f.rejected
              << " rejected, rms " << f.rms_mm * 1e3 << " um\n"
              << "scale x " << f.scale_x.value << " +- " << f.scale_x.sigma << ", y " << f.scale_y.value << " +- "
              << f.scale_y.sigma << ", non-orthogonality " << f.non_orthogonality_rad.value * kRadToArcsec << " +- "
              << f.non_orthogonality_rad.sigma * kRadToArcsec << " arcsec\n"
              << "scale discrepancy " << (f.mean_scale.value - 1.0) * 1e6 << " +- " << f.mean_scale.sigma * 1e6
              << " ppm, as emulsion depth " << report.emulsion_depth_reading_um.value << " +- "
              << report.emulsion_depth_reading_um.sigma << " um\n"
              << json << "\n" << png << "\n";
  });
}

}  // namespace platemeter::cli
