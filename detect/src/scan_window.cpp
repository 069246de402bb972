// A window of the scan read as fit pixels (scan_window.h).
#include "scan_window.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace platemeter::detect_internal {

bool WindowAbout(const ScanPixels& scan, const PixelPoint& centre, double half_px, PixelRect* rect) {
  const long x0 = static_cast<long>(std::floor(centre.x_px - half_px));
  const long y0 = static_cast<long>(std::floor(centre.y_px - half_px));
  const long x1 = static_cast<long>(std::ceil(centre.x_px + half_px));
  const long y1 = static_cast<long>(std::ceil(centre.y_px + half_px));
  if (x0 < 0 || y0 < 0 || x1 >= scan.width_px || y1 >= scan.height_px) return false;
  *rect = PixelRect{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  return true;
}

bool ReadContrast(const ScanPixels& scan, const PixelRect& rect, std::vector<star_internal::FitPixel>* pixels,
                  std::vector<PixelPoint>* clipped) {
  std::vector<float> values(static_cast<size_t>(rect.width_px * rect.height_px));
  scan.read(rect, values.data());
  const double sign = scan.dark ? -1.0 : 1.0;
  pixels->clear();
  if (clipped) clipped->clear();
  pixels->reserve(values.size());
  for (long y = 0; y < rect.height_px; ++y)
    for (long x = 0; x < rect.width_px; ++x) {
      const float v = values[static_cast<size_t>(y * rect.width_px + x)];
      if (std::isnan(v)) continue;  // masked: no value in the scan, simply not used
      const double x_px = static_cast<double>(rect.x0_px + x), y_px = static_cast<double>(rect.y0_px + y);
      if (v <= scan.low_dn || v >= scan.high_dn) {
        if (!clipped) return false;
        clipped->push_back({x_px, y_px});
        continue;
      }
      pixels->push_back({static_cast<float>(x_px), static_cast<float>(y_px), static_cast<float>(sign * v)});
    }
  return true;
}

double ToSweep_px(const PixelPoint& p, const PixelPoint& centre, double angle_rad, double length_px) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad), h = 0.5 * length_px;
  const double dx = p.x_px - centre.x_px, dy = p.y_px - centre.y_px;
  const double along = std::clamp(dx * c + dy * s, -h, h);
  return std::hypot(dx - along * c, dy - along * s);
}

bool ClearOfClipped(const std::vector<PixelPoint>& clipped, const PixelPoint& centre, double angle_rad,
                    double length_px, double clear_px) {
  return std::none_of(clipped.begin(), clipped.end(), [&](const PixelPoint& q) {
    return ToSweep_px(q, centre, angle_rad, length_px) <= clear_px;
  });
}

star_internal::FittedSegment ModelOf(const DetectedStar& d) {
  star_internal::FittedSegment m;
  m.x_px = d.point.position_px.x_px, m.y_px = d.point.position_px.y_px;
  m.angle_rad = d.angle_deg * std::numbers::pi / 180.0;
  m.length_px = d.length_px;
  m.flux_dn = d.flux_dn;
  m.sigma_px = d.fwhm_px / star_internal::kFwhmPerSigma;
  return m;
}

}  // namespace platemeter::detect_internal
