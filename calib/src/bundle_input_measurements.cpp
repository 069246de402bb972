// Observations from measurement files (bundle_input_io.h): one frame per file.
#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "platemeter/calib/bundle_input_io.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

// The line of each data row of a measurement file that ParseMeasurementFile
// accepted: after the title, '#' lines and blank lines form the header, then
// one column line, then one non-blank line per point (no comments).
std::vector<int> DataRowLines(const std::string& text) {
  std::vector<int> lines;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  bool title = false, columns = false;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!title) {
      title = true;
      continue;
    }
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (!columns) {
      if (line[0] == '#') continue;
      columns = true;
      continue;
    }
    lines.push_back(number);
  }
  return lines;
}

std::string KindList(const std::vector<PointKind>& kinds) {
  std::string list;
  for (PointKind kind : kinds) list += std::string(list.empty() ? "" : ", ") + PointKindName(kind);
  return list;
}

}  // namespace

std::vector<ImageObservation> ObservationsFromMeasurementFile(const MeasurementFile& file, const std::string& origin,
                                                              const MeasurementObservationOptions& options,
                                                              std::vector<BundleWarning>* warnings,
                                                              const std::string* text) {
  const std::string frame = options.frame_id.empty() ? file.header.plate_id : options.frame_id;
  if (frame.empty()) {
    throw Error(origin, "the header's plate_id is empty: give the frame's id (the [[frame]]'s id)");
  }
  if (options.kinds.empty()) throw Error(origin, "no point kinds selected");
  std::vector<int> lines;
  if (text != nullptr) lines = DataRowLines(*text);
  if (text != nullptr && lines.size() != file.points.size()) lines.clear();  // not this file's text

  std::vector<ImageObservation> observations;
  std::map<std::string, size_t> seen;  // point id -> index in the file
  int incomplete = 0;
  std::string first_incomplete;
  for (size_t i = 0; i < file.points.size(); ++i) {
    const MeasuredPoint& p = file.points[i];
    if (std::find(options.kinds.begin(), options.kinds.end(), p.kind) == options.kinds.end()) continue;
    if (p.status != PointStatus::kMeasured) continue;
    const std::string where = lines.empty() ? origin : origin + ":" + std::to_string(lines[i]);
    const std::string line_prefix = lines.empty() ? std::string() : "line " + std::to_string(lines[i]) + ": ";
    if (!p.x_mm || !p.y_mm || !p.sigma_x_mm || !p.sigma_y_mm) {
      if (incomplete++ == 0) first_incomplete = p.id;
      continue;
    }
    if (!(*p.sigma_x_mm > 0.0) || !(*p.sigma_y_mm > 0.0)) {
      throw Error(origin, line_prefix + std::string(PointKindName(p.kind)) + " '" + p.id +
                              "': sigma_x_mm and sigma_y_mm must be positive for an image observation");
    }
    const auto [it, inserted] = seen.emplace(p.id, i);
    if (!inserted) {
      throw Error(origin, line_prefix + "id '" + p.id + "' is both a " + PointKindName(file.points[it->second].kind) +
                              " and a " + PointKindName(p.kind) + ": the selected kinds (" +
                              KindList(options.kinds) + ") must not share ids");
    }
    ImageObservation o;
    o.frame = frame;
    o.point_id = p.id;
    o.x_mm = *p.x_mm;
    o.y_mm = *p.y_mm;
    o.sigma_x_mm = *p.sigma_x_mm;
    o.sigma_y_mm = *p.sigma_y_mm;
    o.origin = where;
    observations.push_back(std::move(o));
  }
  if (incomplete > 0 && warnings != nullptr) {
    warnings->push_back({"frame " + frame,
                         std::to_string(incomplete) + " measured point(s) of the selected kinds (" +
                             KindList(options.kinds) + ") in " + origin +
                             " have no plate coordinates or sigmas (x_mm, y_mm, sigma_x_mm, sigma_y_mm), e.g. '" +
                             first_incomplete + "': left out (run measure to get plate coordinates)"});
  }
  return observations;
}

std::vector<ImageObservation> ReadObservationsFromMeasurementFile(const std::string& path,
                                                                  const MeasurementObservationOptions& options,
                                                                  std::vector<BundleWarning>* warnings) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the measurement file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path, "read error");
  const std::string text = buffer.str();
  const MeasurementFile file = ParseMeasurementFile(text, path);
  return ObservationsFromMeasurementFile(file, path, options, warnings, &text);
}

}  // namespace platemeter
