// Writing a simulated plate: the scan band by band, the truth file and the chain file.
#include <chrono>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <vector>

#include "platemeter/core/error.h"
#include "platemeter/core/version.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/sha256.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/render_crb.h"
#include "platemeter/samples/simulate.h"

namespace platemeter::sim {

void ComputeCramerRaoBounds(SimulatedPlate* plate) {
  const std::vector<MarkCramerRao> bounds = CramerRaoBounds(plate->scene);
  for (size_t i = 0; i < plate->truth.size(); ++i) {
    const int mark = plate->truth_mark[i];
    if (mark < 0) continue;
    const MarkCramerRao& crb = bounds[static_cast<size_t>(mark)];
    if (!crb.valid || !std::isfinite(crb.sigma_x_px) || !std::isfinite(crb.sigma_y_px)) continue;
    plate->truth[i].crb_x_px = crb.sigma_x_px;
    plate->truth[i].crb_y_px = crb.sigma_y_px;
    plate->truth[i].crb_xy_corr = std::clamp(crb.correlation_xy, -1.0, 1.0);
  }
}

std::string ChainFileJson(const SimulatedPlate& plate) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["format"] = "platemeter simulation chain";
  j["format_version"] = 1;
  j["software_version"] = std::string("platemeter ") + kVersion;
  j["name"] = plate.name;
  j["spec"] = plate.spec_origin;
  j["camera"] = plate.camera;
  j["seed"] = plate.seed;
  j["full_size"] = plate.full_size;
  j["image"] = {{"file", plate.name + ".tif"},
                {"width_px", plate.scene.width_px},
                {"height_px", plate.scene.height_px},
                {"pixel_size_um", plate.pixel_size_um},
                {"bits", plate.image.sample_type == SampleType::kUint8 ? 8 : 16}};
  j["pixel_convention"] = "x = column, y = row down, centre of the top-left pixel at (0, 0)";
  j["plate_frame"] = "master-grid / camera millimetres, x right, y up, before every step of the chain";
  j["chain"] = ordered_json::parse(plate.chain.ToJson());
  if (!plate.star_field_json.empty()) j["star_field"] = ordered_json::parse(plate.star_field_json);
  const SceneBackground& bg = plate.scene.background;
  const SceneNoise& noise = plate.scene.noise;
  j["background"] = {{"level_dn", bg.level_dn},
                     {"terrain_amplitude_dn", bg.terrain_amplitude_dn},
                     {"terrain_scale_px", bg.terrain_scale_px},
                     {"vignetting_fraction", bg.vignetting_fraction},
                     {"optical_centre_px", {bg.optical_centre_px.x_px, bg.optical_centre_px.y_px}},
                     {"vignetting_radius_px", bg.vignetting_radius_px}};
  j["noise"] = {{"scanner_blur_sigma_px", noise.scanner_blur_sigma_px},
                {"sensor_sigma_dn", noise.sensor_sigma_dn},
                {"grain_sigma_dn", noise.grain_sigma_dn},
                {"quantize", noise.quantize},
                {"saturation_dn", noise.saturation_dn},
                {"seed", noise.seed}};
  auto marks = [&plate](const std::vector<int>& indices) {
    ordered_json list = ordered_json::array();
    for (int i : indices) {
      const SceneMark& m = plate.scene.marks[static_cast<size_t>(i)];
      list.push_back({{"id", m.id},
                      {"x_px", m.centre_px.x_px},
                      {"y_px", m.centre_px.y_px},
                      {"size_um", m.size_um},
                      {"line_width_um", m.line_width_um},
                      {"amplitude_dn", m.amplitude_dn}});
    }
    return list;
  };
  ordered_json damaged = ordered_json::array(), absent = ordered_json::array();
  for (const MeasuredPoint& t : plate.truth) {
    for (const std::string& flag : t.flags) {
      if (flag == "damaged") damaged.push_back(t.id);
      if (flag == "absent") absent.push_back(t.id);
    }
  }
  j["defects"] = {{"missing_crosses", absent},
                  {"damaged_crosses", damaged},
                  {"false_marks", marks(plate.false_marks)},
                  {"dust", marks(plate.dust)},
                  {"scratches", marks(plate.scratches)}};
  return j.dump(2) + "\n";
}

namespace {

// The scan band by band; each band is written (converted, compressed: one
// thread) while the next one renders, from two buffers.
void RenderScan(const SimulatedPlate& plate, const std::string& image_path, const RenderProgress& progress) {
  const SceneRenderer renderer(plate.scene);
  ImageWriter writer(image_path, plate.image);
  const long height = plate.scene.height_px, width = plate.scene.width_px;
  const long band = plate.image.tile_size_px > 0 ? writer.band_height_px() : std::min<long>(64, height);
  std::vector<float> buffers[2];
  for (auto& buffer : buffers) buffer.resize(static_cast<size_t>(band * width));
  std::future<void> writing;  // destroyed (joined) before the writer
  long rows_written = 0;
  auto wait_for_write = [&] {
    if (!writing.valid()) return;
    writing.get();  // rethrows a write error
    if (progress) progress(rows_written, height);
  };
  int next = 0;
  for (long y0 = 0; y0 < height; y0 += band, next ^= 1) {
    const long rows = std::min(band, height - y0);
    renderer.RenderBand(y0, rows, buffers[next].data());
    wait_for_write();
    writing = std::async(std::launch::async, [&writer, &buffers, next, y0, rows] {
      writer.WriteBand(y0, rows, buffers[next].data());
    });
    rows_written = y0 + rows;
  }
  wait_for_write();
  writer.Finish();
}

}  // namespace

SimulateOutputs WriteSimulatedPlate(SimulatedPlate plate, const std::string& out_dir, const RenderProgress& progress) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) throw Error(out_dir, "cannot create the output folder");
  SimulateOutputs out;
  out.image_path = (fs::path(out_dir) / (plate.name + ".tif")).string();
  out.truth_path = (fs::path(out_dir) / (plate.name + ".truth.csv")).string();
  out.chain_path = (fs::path(out_dir) / (plate.name + ".chain.json")).string();

  ComputeCramerRaoBounds(&plate);
  const std::string chain_json = ChainFileJson(plate);

  RenderScan(plate, out.image_path, progress);

  MeasurementFile truth;
  truth.truth_columns = true;
  truth.header.plate_id = plate.name;
  truth.header.scan_file = plate.name + ".tif";
  truth.header.scan_sha256 = Sha256HexOfFile(out.image_path);
  truth.header.camera = plate.camera;
  truth.header.pixel_size_um = plate.pixel_size_um;
  truth.header.software_version = std::string("platemeter ") + kVersion;
  truth.header.extra = {{"truth_of", "platemeter simulate " + plate.spec_origin},
                        {"seed", std::to_string(plate.seed)},
                        {"full_size", plate.full_size ? "true" : "false"},
                        {"chain_file", plate.name + ".chain.json"},
                        {"plate_frame", "x_mm,y_mm are master-grid/camera positions before the chain"}};
  truth.points = plate.truth;
  WriteMeasurementFile(out.truth_path, truth);
  WriteFileAtomically(out.chain_path, chain_json);
  return out;
}

}  // namespace platemeter::sim
