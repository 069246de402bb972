#include "platemeter/core/scan_orientation.h"

namespace platemeter {

std::array<int, 4> ScanOrientation::PixelAxesFromPlate() const {
  // Rotation by a multiple of 90 degrees in the plate frame (counter-clockwise, y up).
  const int quarter = ((rotation_deg / 90) % 4 + 4) % 4;
  static const int kCos[4] = {1, 0, -1, 0}, kSin[4] = {0, 1, 0, -1};
  const int c = kCos[quarter], s = kSin[quarter];
  const int mx = mirrored ? -1 : 1;
  // flip_y * [[c, -s], [s, c]] * diag(mx, 1)
  return {c * mx, -s, -s * mx, -c};
}

std::string ScanOrientation::Name() const { return std::to_string(rotation_deg) + (mirrored ? "m" : ""); }

std::vector<ScanOrientation> ScanOrientation::All() {
  std::vector<ScanOrientation> all;
  for (bool mirrored : {false, true})
    for (int rotation : {0, 90, 180, 270}) all.push_back({rotation, mirrored});
  return all;
}

bool ParseScanOrientation(const std::string& text, ScanOrientation* orientation) {
  for (const ScanOrientation& o : ScanOrientation::All()) {
    if (o.Name() == text) {
      *orientation = o;
      return true;
    }
  }
  return false;
}

}  // namespace platemeter
