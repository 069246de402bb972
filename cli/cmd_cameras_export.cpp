// platemeter cameras export: a camera definition as OpenCV YAML, MicMac XML or
// an Ames Stereo Pipeline .tsai for a scan's pixel grid (docs/camera-exports.md).
#include <iostream>
#include <memory>

#include "cmd_cameras_export.h"
#include "platemeter/calib/camera_export.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/core/atomic_file.h"

namespace platemeter::cli {
namespace {

struct ExportArguments {
  std::string camera;
  std::string format = "opencv";
  double pixel_size_um = 0.0;
  std::vector<int> image_size_px;
  std::string output;
};

void RunExport(const GlobalOptions& global, const ExportArguments& args) {
  CameraExportFormat format;
  if (!ParseCameraExportFormat(args.format, &format)) {
    throw Error("--format", "unknown format '" + args.format + "' (opencv, micmac, asp-tsai)");
  }
  CameraExportOptions options;
  options.pixel_size_um = args.pixel_size_um;
  options.image_width_px = args.image_size_px.at(0);
  options.image_height_px = args.image_size_px.at(1);
  const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
  CameraExportReport report;
  const std::string text = ExportCamera(registry.Camera(args.camera), format, options, &report);
  if (args.output.empty()) {
    std::cout << text;
  } else {
    WriteFileAtomically(args.output, text);
  }
  std::cerr << report.Summary() << '\n';
}

}  // namespace

void RegisterCamerasExport(CLI::App* cameras, GlobalOptions& global) {
  auto args = std::make_shared<ExportArguments>();
  auto* command = cameras->add_subcommand(
      "export", "a camera for other tools: OpenCV YAML, MicMac XML or ASP .tsai, fitted where the models differ "
                "(the fit's residual on stderr; docs/camera-exports.md)");
  command->add_option("NAME", args->camera, "camera name (see `platemeter cameras list`)")->required();
  command->add_option("--format", args->format, "opencv, micmac or asp-tsai")->capture_default_str();
  command->add_option("--pixel-um", args->pixel_size_um, "the scan's pixel size, um")->required()->check(CLI::PositiveNumber);
  command->add_option("--image-px", args->image_size_px, "the scan's width and height in pixels: W H")
      ->required()
      ->expected(2);
  command->add_option("-o,--output", args->output, "write here (atomically) instead of stdout");
  command->callback([&global, args] { RunExport(global, *args); });
}

}  // namespace platemeter::cli
