// Running the detectors into a measurement file (detect_run.h): the detect step
// of the pipeline, and what `platemeter detect` writes of it.
#include "platemeter/pipeline/detect_run.h"

#include "detect_stages.h"

#include <fmt/format.h>

#include <filesystem>
#include <optional>
#include <utility>

#include "platemeter/core/atomic_file.h"
#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/sha256.h"
#include "platemeter/core/version.h"
#include "platemeter/detect/fiducial_detector.h"
#include "platemeter/detect/reseau_detector.h"

namespace platemeter::pipeline {
namespace {

// What the two detectors found, for the outputs.
struct Detections {
  std::optional<ReseauDetection> reseau;
  std::optional<FiducialDetection> fiducials;
  ScanOrientation orientation;
  int polarity = -1;
  long masked_px = 0;  // masked pixels of the scan (core/image.h), counted by the detector that read it all
};

// Counted once, by whichever detector read the whole scan: the reseau's overview, else the fiducial search's.
long MaskedPixels(const Detections& d) {
  if (d.reseau) return d.reseau->masked_px;
  return d.fiducials ? d.fiducials->masked_px : 0;
}

MeasurementFile ToMeasurementFile(const Detections& detections, const std::string& scan, const std::string& camera,
                                  double pixel_size_um) {
  MeasurementFile file;
  file.header.plate_id = std::filesystem::path(scan).stem().string();
  file.header.scan_file = std::filesystem::absolute(scan).string();
  file.header.scan_sha256 = Sha256HexOfFile(scan);
  file.header.camera = camera;
  file.header.pixel_size_um = pixel_size_um;
  file.header.software_version = std::string("platemeter ") + kVersion;
  file.header.extra.push_back({"orientation", detections.orientation.Name()});
  if (detections.reseau) file.header.extra.push_back({"polarity", detections.polarity < 0 ? "dark" : "bright"});
  if (detections.masked_px > 0) file.header.extra.push_back({"masked_pixels", std::to_string(detections.masked_px)});
  std::vector<DetectedPoint> points;
  if (detections.reseau) points = detections.reseau->points;
  if (detections.fiducials) points.insert(points.end(), detections.fiducials->points.begin(), detections.fiducials->points.end());
  for (const DetectedPoint& p : points) {
    MeasuredPoint row;
    row.id = p.id;
    row.kind = p.kind;
    row.status = p.status;
    if (p.status != PointStatus::kMissing) {
      row.x_px = p.position_px.x_px;
      row.y_px = p.position_px.y_px;
      if (p.sigma_x_px > 0.0 && p.sigma_y_px > 0.0) {  // a rejected point may have a place but no sigma
        row.sigma_x_px = p.sigma_x_px;
        row.sigma_y_px = p.sigma_y_px;
      }
    }
    if (!p.reason.empty()) row.flags.push_back(std::string(PointStatusName(p.status)) + ":" + p.reason);
    file.points.push_back(row);
  }
  return file;
}

nlohmann::json SummaryJson(const Detections& detections, const std::string& scan, const std::string& grid) {
  nlohmann::json j;
  j["scan"] = scan;
  j["orientation"] = detections.orientation.Name();
  j["masked_pixels"] = detections.masked_px;
  if (detections.reseau) {
    const ReseauDetection& d = *detections.reseau;
    nlohmann::json r;
    r["grid"] = grid;
    r["found"] = d.found;
    r["orientation"] = d.orientation.Name();
    r["orientation_ambiguous"] = d.orientation_ambiguous;
    r["orientation_evidence"] = d.orientation_evidence;
    r["polarity"] = d.polarity < 0 ? "dark" : "bright";
    r["counts"] = {{"measured", d.measured}, {"rejected", d.rejected}, {"missing", d.missing},
                   {"candidates", d.candidates}};
    r["overview_factor"] = d.overview_factor;
    r["plate_to_pixel"] = {{"a", {d.plate_to_pixel.a[0], d.plate_to_pixel.a[1], d.plate_to_pixel.a[2], d.plate_to_pixel.a[3]}},
                           {"t_px", {d.plate_to_pixel.t[0], d.plate_to_pixel.t[1]}}};
    r["timings_s"] = {{"overview", d.seconds_overview}, {"candidates", d.seconds_candidates},
                      {"assignment", d.seconds_assignment}, {"refinement", d.seconds_refinement}};
    r["summary"] = d.summary;
    j["reseau"] = r;
  }
  if (detections.fiducials) {
    const FiducialDetection& f = *detections.fiducials;
    nlohmann::json r;
    r["found"] = f.found;
    r["used_reseau_prior"] = f.used_prior;
    r["orientation"] = f.orientation.Name();
    r["orientation_ambiguous"] = f.orientation_ambiguous;
    r["orientation_evidence"] = f.orientation_evidence;
    r["counts"] = {{"measured", f.measured}, {"rejected", f.rejected}, {"missing", f.missing}};
    r["summary"] = f.summary;
    j["fiducials"] = r;
  }
  return j;
}

}  // namespace

DetectRun RunDetection(const DetectRequest& request, const DefinitionRegistry& registry) {
  if (request.camera.empty() && request.grid.empty()) throw Error("detect", "give --camera NAME or --grid NAME");
  const CameraDefinition* camera = request.camera.empty() ? nullptr : &registry.Camera(request.camera);
  const std::string grid_name = camera ? camera->grid : request.grid;
  const bool has_fiducials = camera && (!camera->fiducial_set.empty() || camera->format_corners_as_fiducials);
  if (grid_name.empty() && !has_fiducials) {
    throw Error("camera '" + request.camera + "'", "has neither a reseau grid nor fiducials to detect");
  }
  const Image image = Image::Open(request.scan);
  const double pixel_size_um = ResolvePixelSizeUm(image.info(), request.pixel_size_um);
  std::optional<ScanOrientation> orientation;
  if (!request.orientation.empty()) {
    ScanOrientation parsed;
    if (!ParseScanOrientation(request.orientation, &parsed)) {
      throw Error("--orientation", "'" + request.orientation + "' is not one of " + kScanOrientationNames);
    }
    orientation = parsed;
  }
  auto check_orientation = [&](bool ambiguous, const std::string& evidence) {
    if (ambiguous && !request.allow_ambiguous) {
      throw Error(request.scan, "cannot tell the scan's orientation (" + evidence + "); give --orientation");
    }
  };

  Detections detections;
  if (!grid_name.empty()) {
    ReseauDetectorOptions options;
    options.pixel_size_um = pixel_size_um;
    options.orientation = orientation;
    detections.reseau = DetectReseau(image, registry.Grid(grid_name), options);
    if (!detections.reseau->found) throw Error(request.scan, detections.reseau->summary);
    check_orientation(detections.reseau->orientation_ambiguous, detections.reseau->orientation_evidence);
    detections.orientation = detections.reseau->orientation;
    detections.polarity = detections.reseau->polarity;
  }
  if (has_fiducials) {
    // With a reseau the fiducials are predicted from it; without one they are searched for.
    FiducialDetectorOptions options;
    options.pixel_size_um = pixel_size_um;
    options.orientation = orientation;
    const FiducialSet* set = camera->fiducial_set.empty() ? nullptr : &registry.Fiducials(camera->fiducial_set);
    const PlateToPixel* prior = detections.reseau ? &detections.reseau->plate_to_pixel : nullptr;
    detections.fiducials = DetectFiducialMarks(image, *camera, set, prior, options);
    if (!prior) {
      if (!detections.fiducials->found) throw Error(request.scan, detections.fiducials->summary);
      check_orientation(detections.fiducials->orientation_ambiguous, detections.fiducials->orientation_evidence);
      detections.orientation = detections.fiducials->orientation;
    }
  }
  detections.masked_px = MaskedPixels(detections);
  const DetectContext context{.request = request,
                              .registry = registry,
                              .image = image,
                              .pixel_size_um = pixel_size_um,
                              .camera = camera,
                              .grid = grid_name.empty() ? nullptr : &registry.Grid(grid_name),
                              .reseau = detections.reseau ? &*detections.reseau : nullptr,
                              .fiducials = detections.fiducials ? &*detections.fiducials : nullptr,
                              .orientation = detections.orientation};
  DetectRun run;
  run.file = ToMeasurementFile(detections, request.scan, request.camera, pixel_size_um);
  std::vector<std::pair<std::string, StageOutput>> stages;  // (each appends its rows to the file's)
  if (request.stars || request.trails) stages.emplace_back("stars", RunStarStage(context, &run.file.points));
  if (request.passpoints) stages.emplace_back("passpoints", RunPasspointStage(context, &run.file.points));
  run.summary = SummaryJson(detections, request.scan, grid_name);
  run.grid_name = grid_name;
  if (detections.masked_px > 0) {
    run.messages += fmt::format("scan: {} pixels masked (NaN, infinite or |value| > {:g}: no value, not used)\n",
                                detections.masked_px, kMaxPixelMagnitudeDn);
  }
  if (detections.reseau) run.messages += "reseau: " + detections.reseau->summary + "\n";
  if (detections.fiducials) run.messages += "fiducials: " + detections.fiducials->summary + "\n";
  for (auto& [key, stage] : stages) {
    run.summary[key] = std::move(stage.summary);
    run.messages += key + ": " + stage.message + "\n";
  }
  return run;
}

std::vector<std::string> DetectSetMembers(const std::string& scan) {
  const std::string stem = std::filesystem::path(scan).stem().string();
  return {stem + ".measurements.csv", stem + ".detect.json"};
}

DetectFiles WriteDetectRun(const DetectRun& run, const std::string& scan, OutputSet* outputs) {
  const std::vector<std::string> names = DetectSetMembers(scan);
  outputs->Write(names[0], [&](const std::string& path) { WriteMeasurementFile(path, run.file); });
  outputs->Write(names[1], [&](const std::string& path) { WriteFileAtomically(path, run.summary.dump(2) + "\n"); });
  outputs->Commit();
  return {outputs->FinalPath(names[0]), outputs->FinalPath(names[1])};
}

}  // namespace platemeter::pipeline
