// The star stage of RunDetection (detect_stages.h): star images (kind star).
#include <sstream>

#include "detect_stages.h"
#include "platemeter/detect/star_detector.h"

namespace platemeter::cli {

StageOutput RunStarStage(const DetectContext& context) {
  const DetectRequest& request = context.request;
  StarDetectorOptions options;
  options.dark = !request.stars_bright;
  options.psf_fwhm_px = request.star_fwhm_px;
  if (context.reseau) {
    // Crosses are not stars: mask every cross found, out to half its arm.
    for (const DetectedPoint& p : context.reseau->points)
      if (p.status != PointStatus::kMissing) options.mask_px.push_back(p.position_px);
    options.mask_radius_px = 0.5 * context.grid->mark.arm_length_um / context.pixel_size_um + 3.0;
  }
  const std::vector<DetectedStar> stars = DetectStars(context.image, options);
  StageOutput out;
  int measured = 0, rejected = 0;
  for (const DetectedStar& star : stars) {
    measured += star.point.status == PointStatus::kMeasured;
    rejected += star.point.status == PointStatus::kRejected;
    MeasuredPoint row;
    row.id = star.point.id;
    row.kind = PointKind::kStar;
    row.status = star.point.status;
    row.x_px = star.point.position_px.x_px;
    row.y_px = star.point.position_px.y_px;
    row.sigma_x_px = star.point.sigma_x_px;
    row.sigma_y_px = star.point.sigma_y_px;
    std::stringstream names(StarFlagNames(star.flags));
    for (std::string name; std::getline(names, name, ',');)
      if (!name.empty()) row.flags.push_back(name);
    if (!star.point.reason.empty()) row.flags.push_back(std::string(PointStatusName(star.point.status)) + ":" + star.point.reason);
    out.rows.push_back(row);
  }
  out.summary = {{"measured", measured}, {"rejected", rejected}};
  out.message = std::to_string(stars.size()) + " images";
  return out;
}

}  // namespace platemeter::cli
