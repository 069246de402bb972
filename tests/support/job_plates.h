#pragma once
// What the job-file and measure tests of tests/pipeline and tests/cli share: the documented
// example job (docs/job.md) and the simulator's Orbigon plate, as detect's measurement file
// made from its truth (fast) or rendered as a scan (for what needs the detector).
#include <optional>
#include <string>

#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter::testing {

// The ```toml block of docs/job.md.
inline std::string JobDocsExample() {
  const std::string doc = ReadTextFile(std::string(PLATEMETER_SOURCE_DIR) + "/docs/job.md");
  const size_t begin = doc.find("```toml\n");
  const size_t end = doc.find("```", begin + 8);
  if (begin == std::string::npos || end == std::string::npos) return "";
  return doc.substr(begin + 8, end - begin - 8);
}

// The simulator's Orbigon plate (121 crosses; seed 001's 22 degC and 21 um emulsion) at 40 um pixels.
inline sim::SimulatedPlate OrbigonJobPlate() {
  const std::string spec =
      "name = \"orbigon\"\ncamera = \"orbigon\"\nseed = 5\n[output]\npixel_size_um = 40.0\nmargin_mm = 1.0\n"
      "[thermal]\ntemperature_degC = 22.0\n[emulsion]\ndepth_um = 21.0\n"
      "[noise]\nblur_sigma_um = 8.0\nsensor_sigma_dn = 100.0\n";
  const DefinitionRegistry registry;
  return sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec, "spec"), registry);
}

// Detect's measurement file made from OrbigonJobPlate's truth (no render, no detection: fast), written
// into dir; `measured` crosses measured at 0.05 px, the others missing.
inline std::string OrbigonTruthMeasurementFile(const TempDir& dir, int measured = 121) {
  const sim::SimulatedPlate plate = OrbigonJobPlate();
  MeasurementFile file;
  file.header.plate_id = "orbigon";
  file.header.camera = "orbigon";
  file.header.pixel_size_um = 40.0;
  for (MeasuredPoint p : plate.truth) {
    if (p.kind != PointKind::kReseau) continue;
    const bool keep = measured-- > 0;
    p.status = keep ? PointStatus::kMeasured : PointStatus::kMissing;
    p.sigma_x_px = p.sigma_y_px = keep ? std::optional<double>(0.05) : std::nullopt;
    if (!keep) p.x_px = p.y_px = std::nullopt;
    p.x_mm = p.y_mm = p.sigma_x_mm = p.sigma_y_mm = std::nullopt;
    p.crb_x_px = p.crb_y_px = p.crb_xy_corr = std::nullopt;
    p.flags.clear();
    file.points.push_back(p);
  }
  const std::string path = dir.file("orbigon.measurements.csv");
  WriteMeasurementFile(path, file);
  return path;
}

// OrbigonJobPlate rendered, once per test program (its folder is removed at exit).
inline const std::string& OrbigonJobScan() {
  static const TempDir dir;
  static const std::string scan = sim::WriteSimulatedPlate(OrbigonJobPlate(), dir.path().string()).image_path;
  return scan;
}

}  // namespace platemeter::testing
