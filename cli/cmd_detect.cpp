// platemeter detect SCAN (--camera NAME | --grid NAME) -o DIR: reseau crosses
// with ids, positions, sigmas and statuses, into a measurement file and a JSON
// summary.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.h"
#include "platemeter/core/error.h"
#include "platemeter/core/image.h"
#include "platemeter/core/version.h"
#include "platemeter/detect/reseau_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/atomic_file.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/measure/sha256.h"

namespace platemeter::cli {
namespace {

struct DetectArguments {
  std::string scan;
  std::string camera;
  std::string grid;
  std::optional<double> pixel_size_um;
  std::string orientation;
  std::string out_dir;
  bool allow_ambiguous = false;
};

MeasurementFile ToMeasurementFile(const ReseauDetection& detection, const std::string& scan, const std::string& camera,
                                  double pixel_size_um) {
  MeasurementFile file;
  file.header.plate_id = std::filesystem::path(scan).stem().string();
  file.header.scan_file = std::filesystem::absolute(scan).string();
  file.header.scan_sha256 = Sha256HexOfFile(scan);
  file.header.camera = camera;
  file.header.pixel_size_um = pixel_size_um;
  file.header.software_version = std::string("platemeter ") + kVersion;
  file.header.extra.push_back({"orientation", detection.orientation.Name()});
  file.header.extra.push_back({"polarity", detection.polarity < 0 ? "dark" : "bright"});
  for (const DetectedPoint& p : detection.points) {
    MeasuredPoint row;
    row.id = p.id;
    row.kind = p.kind;
    row.status = p.status;
    if (p.status != PointStatus::kMissing) {
      row.x_px = p.position_px.x_px;
      row.y_px = p.position_px.y_px;
      row.sigma_x_px = p.sigma_x_px;
      row.sigma_y_px = p.sigma_y_px;
    }
    if (!p.reason.empty()) row.flags.push_back(std::string(PointStatusName(p.status)) + ":" + p.reason);
    file.points.push_back(row);
  }
  return file;
}

nlohmann::json SummaryJson(const ReseauDetection& d, const std::string& scan, const std::string& grid) {
  nlohmann::json j;
  j["scan"] = scan;
  j["grid"] = grid;
  j["found"] = d.found;
  j["orientation"] = d.orientation.Name();
  j["orientation_ambiguous"] = d.orientation_ambiguous;
  j["orientation_evidence"] = d.orientation_evidence;
  j["polarity"] = d.polarity < 0 ? "dark" : "bright";
  j["counts"] = {{"measured", d.measured}, {"rejected", d.rejected}, {"missing", d.missing},
                 {"candidates", d.candidates}};
  j["overview_factor"] = d.overview_factor;
  j["plate_to_pixel"] = {{"a", {d.plate_to_pixel.a[0], d.plate_to_pixel.a[1], d.plate_to_pixel.a[2], d.plate_to_pixel.a[3]}},
                         {"t_px", {d.plate_to_pixel.t[0], d.plate_to_pixel.t[1]}}};
  j["timings_s"] = {{"overview", d.seconds_overview}, {"candidates", d.seconds_candidates},
                    {"assignment", d.seconds_assignment}, {"refinement", d.seconds_refinement}};
  j["summary"] = d.summary;
  return j;
}

}  // namespace

void RegisterDetectCommand(CLI::App& app, GlobalOptions& global) {
  auto args = std::make_shared<DetectArguments>();
  auto* cmd = app.add_subcommand("detect", "find the reseau crosses of a scan and measure them");
  cmd->add_option("SCAN", args->scan, "the scan")->required();
  auto* camera = cmd->add_option("--camera", args->camera, "camera definition (its grid is searched)");
  auto* grid = cmd->add_option("--grid", args->grid, "master grid to search for");
  camera->excludes(grid);
  cmd->add_option("--pixel-size-um", args->pixel_size_um, "scan pixel size in um (default: the TIFF resolution tags)");
  cmd->add_option("--orientation", args->orientation,
                  "known scan orientation: 0, 90, 180, 270, with m for mirrored (e.g. 90m)");
  cmd->add_flag("--allow-ambiguous-orientation", args->allow_ambiguous,
                "write results even when the orientation (hence the ids) cannot be decided");
  cmd->add_option("-o,--output", args->out_dir, "output folder")->required();
  cmd->callback([args, &global] {
    if (args->camera.empty() && args->grid.empty()) throw Error("detect", "give --camera NAME or --grid NAME");
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    std::string grid_name = args->grid;
    if (!args->camera.empty()) {
      grid_name = registry.Camera(args->camera).grid;
      if (grid_name.empty()) throw Error("camera '" + args->camera + "'", "has no reseau grid to detect");
    }
    const MasterGrid& grid = registry.Grid(grid_name);
    const Image image = Image::Open(args->scan);
    ReseauDetectorOptions options;
    options.pixel_size_um = ResolvePixelSizeUm(image.info(), args->pixel_size_um);
    if (!args->orientation.empty()) {
      ScanOrientation orientation;
      if (!ParseScanOrientation(args->orientation, &orientation)) {
        throw Error("--orientation", "'" + args->orientation + "' is not one of 0 90 180 270 0m 90m 180m 270m");
      }
      options.orientation = orientation;
    }
    const ReseauDetection detection = DetectReseau(image, grid, options);
    if (!detection.found) throw Error(args->scan, detection.summary);
    if (detection.orientation_ambiguous && !args->allow_ambiguous) {
      throw Error(args->scan, "cannot tell the scan's orientation (" + detection.orientation_evidence +
                                  "); give --orientation");
    }
    std::filesystem::create_directories(args->out_dir);
    const std::string stem = std::filesystem::path(args->scan).stem().string();
    const std::string measurements = (std::filesystem::path(args->out_dir) / (stem + ".measurements.csv")).string();
    const std::string summary = (std::filesystem::path(args->out_dir) / (stem + ".detect.json")).string();
    WriteMeasurementFile(measurements,
                         ToMeasurementFile(detection, args->scan, args->camera.empty() ? "" : args->camera,
                                           options.pixel_size_um));
    WriteFileAtomically(summary, SummaryJson(detection, args->scan, grid_name).dump(2) + "\n");
    std::cout << detection.summary << "\n" << measurements << "\n" << summary << "\n";
  });
}

}  // namespace platemeter::cli
