// platemeter detect SCAN (--camera NAME | --grid NAME) -o DIR: reseau crosses
// and fiducial marks with ids, positions, sigmas and statuses, into a
// measurement file and a JSON summary (the flow is detect_run.cpp's).
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "detect_run.h"
#include "platemeter/measure/atomic_file.h"

namespace platemeter::cli {

void RegisterDetectCommand(CLI::App& app, GlobalOptions& global) {
  auto request = std::make_shared<DetectRequest>();
  auto out_dir = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("detect", "find the reseau crosses and fiducials of a scan and measure them");
  cmd->add_option("SCAN", request->scan, "the scan")->required();
  auto* camera = cmd->add_option("--camera", request->camera, "camera definition (its grid and fiducials are searched)");
  auto* grid = cmd->add_option("--grid", request->grid, "master grid to search for (no fiducials)");
  camera->excludes(grid);
  cmd->add_option("--pixel-size-um", request->pixel_size_um, "scan pixel size in um (default: the TIFF resolution tags)");
  cmd->add_option("--orientation", request->orientation,
                  "known scan orientation: 0, 90, 180, 270, with m for mirrored (e.g. 90m)");
  cmd->add_flag("--allow-ambiguous-orientation", request->allow_ambiguous,
                "write results even when the orientation (hence the ids) cannot be decided");
  cmd->add_flag("--stars", request->stars, "also detect star images (kind star; docs/stars.md)");
  cmd->add_flag("--bright-stars", request->stars_bright, "stars are brighter than the background (default: dark, a negative)");
  cmd->add_option("--star-fwhm-px", request->star_fwhm_px, "expected FWHM of a star image in px (default 2.5)")
      ->check(CLI::Range(0.5, 100.0));
  // Duty-cycle trails (seed 001): giving the start time switches them on.
  auto trails = std::make_shared<TrailRequest>();
  cmd->add_option("--trails-start-utc", trails->start_utc,
                  "link star images into duty-cycle trails; ISO 8601 UTC of the plate's first shutter opening");
  cmd->add_option("--trail-dashes", trails->leading_dashes, "leading dashes per trail in exposure order (default 2,3,4,5)")
      ->delimiter(',');
  cmd->add_option("--trail-break-s", trails->break_s, "break between trails in s (default 480)");
  // Passpoints: giving the mark's diameter switches them on.
  auto passpoints = std::make_shared<PasspointRequest>();
  cmd->add_option("--passpoint-diameter-um", passpoints->diameter_um, "measure passpoints: outer diameter of the mark in um")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--passpoint-shape", passpoints->shape, "dot or ring (default dot)")->check(CLI::IsMember({"dot", "ring"}));
  cmd->add_option("--passpoint-line-width-um", passpoints->line_width_um, "ring line width in um");
  cmd->add_option("--passpoint-polarity", passpoints->polarity, "dark or bright (default dark)")
      ->check(CLI::IsMember({"dark", "bright"}));
  cmd->add_option("--passpoints", passpoints->list_file,
                  "approximate passpoint positions (CSV id,x_px,y_px; docs/passpoints.md); default: find and number them");
  cmd->add_option("-o,--output", *out_dir, "output folder")->required();
  cmd->callback([request, out_dir, trails, passpoints, cmd, &global] {
    if (cmd->count("--trails-start-utc")) request->trails = *trails;
    if (cmd->count("--passpoint-diameter-um")) request->passpoints = *passpoints;
    const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
    const DetectRun run = RunDetection(*request, registry);
    std::filesystem::create_directories(*out_dir);
    const std::string stem = std::filesystem::path(request->scan).stem().string();
    const std::string measurements = (std::filesystem::path(*out_dir) / (stem + ".measurements.csv")).string();
    const std::string summary = (std::filesystem::path(*out_dir) / (stem + ".detect.json")).string();
    WriteMeasurementFile(measurements, run.file);
    WriteFileAtomically(summary, run.summary.dump(2) + "\n");
    std::cout << run.messages << measurements << "\n" << summary << "\n";
  });
}

}  // namespace platemeter::cli
