// CanonicalOptionsText (measure_run.h): the options that change measure's outputs
// as deterministic text, for the batch's resume fingerprint (docs/job.md).
#include <charconv>
#include <cstdio>
#include <sstream>

#include "platemeter/core/sha256.h"
#include "platemeter/core/version.h"
#include "platemeter/pipeline/measure_run.h"
#include "platemeter/core/number_text.h"

namespace platemeter::pipeline {
namespace {

// Shortest text that reads back as the same double: deterministic across runs and platforms.
// A double-quoted string with '"', '\\' and control bytes escaped (any bytes, unlike JSON's UTF-8 only).
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(c));
      out += hex;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::string CanonicalOptionsText(const MeasureRequest& request) {
  std::ostringstream out;
  auto line = [&out](const std::string& key, const std::string& value) { out << key << " = " << value << "\n"; };
  auto optional = [](const std::optional<double>& v) { return v ? ShortestText(*v) : std::string("none"); };
  auto boolean = [](bool b) { return std::string(b ? "true" : "false"); };
  const DetectRequest& d = request.detect;
  line("software", Quoted(std::string("platemeter ") + kVersion));
  line("camera", Quoted(d.camera));
  line("grid", Quoted(d.grid));
  line("pixel_size_um", optional(d.pixel_size_um));
  line("orientation", Quoted(d.orientation));
  line("allow_ambiguous_orientation", boolean(d.allow_ambiguous));
  line("stars.enabled", boolean(d.stars));
  line("stars.bright", boolean(d.stars_bright));
  line("stars.fwhm_px", ShortestText(d.star_fwhm_px));
  if (d.trails) {
    std::string dashes;
    for (int n : d.trails->leading_dashes) dashes += (dashes.empty() ? "" : ",") + std::to_string(n);
    line("trails.start_utc", Quoted(d.trails->start_utc));
    line("trails.leading_dashes", "[" + dashes + "]");
    line("trails.break_s", ShortestText(d.trails->break_s));
    line("trails.require_joined", boolean(d.trails->require_joined));
    line("trails.forced_dots", boolean(d.trails->forced_dots));
  } else {
    line("trails", "none");
  }
  if (d.passpoints) {
    const PasspointRequest& p = *d.passpoints;
    line("passpoints.list_file", Quoted(p.list_file));
    if (!p.list_file.empty()) {
      // The list's content changes the output, not just its name.
      std::string sha;
      try {
        sha = Sha256HexOfFile(p.list_file);
      } catch (const std::exception&) {
        sha = "unreadable";
      }
      line("passpoints.list_file_sha256", sha);
    }
    line("passpoints.shape", Quoted(p.shape));
    line("passpoints.diameter_um", ShortestText(p.diameter_um));
    line("passpoints.line_width_um", ShortestText(p.line_width_um));
    line("passpoints.polarity", Quoted(p.polarity));
  } else {
    line("passpoints", "none");
  }
  line("measure.temperature_degC", optional(request.temperature_degC));
  line("measure.emulsion_depth_um", optional(request.emulsion_depth_um));
  line("measure.refractive_index", ShortestText(request.refractive_index));
  line("measure.model", Quoted(request.model));
  line("measure.rejection_threshold", ShortestText(request.rejection_threshold));
  line("measure.tolerance_um", ShortestText(request.tolerance_um));
  line("measure.local_reseau", boolean(!request.no_local));
  line("measure.fiducial_orientation", boolean(request.fiducial_orientation));
  line("measure.fiducial_model", Quoted(request.fiducial_model));
  line("measure.min_cross_fraction", ShortestText(request.min_cross_fraction));
  line("measure.second_scan", Quoted(request.second_scan));
  line("measure.second_orientation", Quoted(request.second_orientation));
  return out.str();
}

}  // namespace platemeter::pipeline
