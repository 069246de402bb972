// platemeter info SCAN: what the scan is, as platemeter reads it.
#include <iostream>
#include <optional>

#include "commands.h"
#include "platemeter/core/image.h"

namespace platemeter::cli {

void RegisterInfoCommand(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("info", "print a scan's size, sample type, tiling and pixel size");
  auto scan = std::make_shared<std::string>();
  cmd->add_option("SCAN", *scan, "the scan (TIFF, PNG, JPEG, FITS)")->required();
  cmd->callback([scan] {
    const Image image = Image::Open(*scan);
    const ImageInfo& info = image.info();
    std::cout << "file: " << info.path << '\n'
              << "format: " << info.format_name << '\n'
              << "size_px: " << info.width_px << " x " << info.height_px << '\n'
              << "channels: " << info.channels << (info.channels >= 3 ? " (read as luminance)" : "") << '\n'
              << "sample_type: " << SampleTypeName(info.sample_type) << '\n'
              << "layout: "
              << (info.tiled ? "tiled " + std::to_string(info.tile_width_px) + " x " +
                                   std::to_string(info.tile_height_px)
                             : std::string("strips"))
              << ", compression " << info.compression << '\n'
              << "pixel_size_um: ";
    if (info.pixel_size_x_um) {
      std::cout << *info.pixel_size_x_um << " (from resolution tags)\n";
    } else {
      std::cout << "unknown (give --pixel-size-um when measuring)\n";
    }
  });
}

}  // namespace platemeter::cli
