#pragma once
// The scan orientation: how a plate lies on its scan (0/90/180/270 degrees, mirrored
// or not, written "0", "90", ..., "0m", "90m", ...). Shared by the detectors, the
// comparator corrections and the job files.
#include <array>
#include <string>
#include <vector>

namespace platemeter {

// How plate axes (x right, y up) lie on the scan: rotated counter-clockwise as
// seen on the scan by rotation_deg, after mirroring x if mirrored (emulsion-down scans).
struct ScanOrientation {
  int rotation_deg = 0;  // 0, 90, 180, 270
  bool mirrored = false;
  std::string Name() const;  // "0", "90", "180", "270", "0m", ...
  static std::vector<ScanOrientation> All();
  // Plate axes onto pixel axes (row-major 2x2 of 0/+-1): mirror x, rotate by the
  // orientation in the plate frame, then flip y because pixel rows run down.
  std::array<int, 4> PixelAxesFromPlate() const;
};
bool ParseScanOrientation(const std::string& text, ScanOrientation* orientation);
// The names ParseScanOrientation accepts, for messages.
inline constexpr char kScanOrientationNames[] = "0 90 180 270 0m 90m 180m 270m";

}  // namespace platemeter
