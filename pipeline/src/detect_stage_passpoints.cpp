// The passpoint stage of RunDetection (detect_stages.h): marked passpoints
// (kind passpoint) from an approximate list or found and numbered P1, P2, ...
// (detect/passpoint_detector.h, docs/passpoints.md). Crosses and fiducials
// found by the earlier stages are masked: they are never passpoints.
#include <cmath>
#include <numbers>

#include "detect_stages.h"
#include "platemeter/core/error.h"
#include "platemeter/detect/passpoint_detector.h"

namespace platemeter::pipeline {
namespace {


// Two segments through (or from) a point along the directions angle and angle + 90 deg.
void AddArms(PixelPoint c, double angle_rad, double behind_px, double ahead_px, double radius_px, bool both_handed,
             std::vector<PasspointMask>* mask) {
  std::vector<double> angles{angle_rad, angle_rad + 0.5 * std::numbers::pi};
  if (both_handed) angles.push_back(angle_rad - 0.5 * std::numbers::pi);  // a corner's second arm: either side of the first
  for (double a : angles) {
    const double ux = std::cos(a), uy = std::sin(a);
    mask->push_back({{c.x_px - behind_px * ux, c.y_px - behind_px * uy},
                     {c.x_px + ahead_px * ux, c.y_px + ahead_px * uy},
                     radius_px});
  }
}

std::vector<PasspointMask> MaskOf(const DetectContext& context, double passpoint_radius_px) {
  std::vector<PasspointMask> mask;
  const double px_per_um = 1.0 / context.pixel_size_um;
  const double margin = passpoint_radius_px + 2.0;
  if (context.reseau && context.grid) {
    // Crosses: both arms, tip to tip, along the reseau's plate axes on the scan (arm_length_um: tip to tip,
    // or a dot's or ring's diameter).
    const PlateToPixel& m = context.reseau->plate_to_pixel;
    const double angle = std::atan2(m.a[2], m.a[0]);
    const double half_arm = 0.5 * context.grid->mark.arm_length_um * px_per_um;
    const double radius = 0.5 * context.grid->mark.line_width_um * px_per_um + margin;
    const bool cross = context.grid->mark.type == MarkType::kCross;
    for (const DetectedPoint& p : context.reseau->points) {
      if (p.status == PointStatus::kMissing) continue;
      if (cross) AddArms(p.position_px, angle, half_arm, half_arm, radius, false, &mask);
      else mask.push_back({p.position_px, p.position_px, half_arm + margin});  // a dot or ring reseau: its disk
    }
  }
  if (context.fiducials) {
    const FiducialDetection& f = *context.fiducials;
    for (size_t i = 0; i < f.points.size(); ++i) {
      const DetectedPoint& p = f.points[i];
      if (p.status == PointStatus::kMissing) continue;
      const MarkFitResult& fit = f.fits[i];
      if (!fit.converged) {
        mask.push_back({p.position_px, p.position_px, 2.0 * passpoint_radius_px + margin});
        continue;
      }
      const double radius = 0.5 * std::max(fit.line_width_px, fit.line_width_2_px) + margin;
      switch (fit.type) {
        case MarkType::kCorner:
          AddArms(fit.centre_px, fit.rotation_rad, 0.0, fit.size_px, radius, true, &mask);
          break;
        case MarkType::kCross:
          AddArms(fit.centre_px, fit.rotation_rad, 0.5 * fit.size_px, 0.5 * fit.size_px, radius, false, &mask);
          break;
        default:  // dot, ring
          mask.push_back({fit.centre_px, fit.centre_px, 0.5 * fit.size_px + margin});
          break;
      }
    }
  }
  return mask;
}

}  // namespace

StageOutput RunPasspointStage(const DetectContext& context, std::vector<MeasuredPoint>* rows) {
  const PasspointRequest& request = *context.request.passpoints;
  if (!(request.diameter_um > 0.0)) throw Error("--passpoint-diameter-um", "must be > 0");
  if (request.shape != "dot" && request.shape != "ring")
    throw Error("--passpoint-shape", "'" + request.shape + "' is not dot or ring");
  if (request.polarity != "dark" && request.polarity != "bright")
    throw Error("--passpoint-polarity", "'" + request.polarity + "' is not dark or bright");
  const bool ring = request.shape == "ring";
  if (ring && !(request.line_width_um > 0.0 && request.line_width_um < 0.5 * request.diameter_um))
    throw Error("--passpoint-line-width-um", "a ring needs its line width, > 0 and below half the diameter");
  PasspointDetectorOptions options;
  options.shape = ring ? MarkType::kRing : MarkType::kDot;
  options.diameter_px = request.diameter_um / context.pixel_size_um;
  options.line_width_px = ring ? request.line_width_um / context.pixel_size_um : 0.0;
  options.dark = request.polarity == "dark";
  if (!(options.diameter_px >= 3.0))
    throw Error("--passpoint-diameter-um", "the mark is under 3 px across at " + std::to_string(context.pixel_size_um) +
                                               " um per pixel: too small to measure");
  options.mask = MaskOf(context, 0.5 * options.diameter_px);
  std::vector<ApproximatePasspoint> list;
  if (!request.list_file.empty()) list = ReadPasspointList(request.list_file);
  const PasspointDetection found =
      DetectPasspoints(context.image, options, request.list_file.empty() ? nullptr : &list);

  StageOutput out;
  for (const PasspointPoint& p : found.points) {
    MeasuredPoint row;
    row.id = p.point.id;
    row.kind = PointKind::kPasspoint;
    row.status = p.point.status;
    // A missing passpoint has no position: the listed one is the user's, not a measurement.
    if (p.point.status != PointStatus::kMissing) {
      row.x_px = p.point.position_px.x_px;
      row.y_px = p.point.position_px.y_px;
      row.sigma_x_px = p.point.sigma_x_px;
      row.sigma_y_px = p.point.sigma_y_px;
    }
    if (!p.point.reason.empty()) row.flags.push_back(std::string(PointStatusName(p.point.status)) + ":" + p.point.reason);
    row.flags.insert(row.flags.end(), p.flags.begin(), p.flags.end());
    rows->push_back(std::move(row));
  }
  out.summary = {{"mode", found.from_list ? "list" : "automatic"},
                 {"list_file", request.list_file},
                 {"shape", request.shape},
                 {"diameter_um", request.diameter_um},
                 {"line_width_um", ring ? request.line_width_um : 0.0},
                 {"polarity", request.polarity},
                 {"counts",
                  {{"measured", found.measured},
                   {"rejected", found.rejected},
                   {"missing", found.missing},
                   {"candidates", found.candidates},
                   {"not_passpoints", found.not_passpoints},
                   {"masked", found.masked}}},
                 {"tiles", found.tiles},
                 {"overview_factor", found.overview_factor},
                 {"summary", found.summary}};
  out.message = found.summary;
  return out;
}

}  // namespace platemeter::pipeline
