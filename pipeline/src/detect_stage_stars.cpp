// The star stage of RunDetection (detect_stages.h): star images (kind star)
// and, when the plate's duty-cycle program is given, its trails (kinds
// trail_dot and trail_dash, with star, trail, dot and mid-exposure time).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "detect_stages.h"
#include "platemeter/core/error.h"
#include "platemeter/core/utc_time.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/detect/trail_forced.h"
#include "platemeter/detect/trail_linker.h"

namespace platemeter::pipeline {
namespace {

constexpr double kSiderealRate_rad_per_s = 7.2921150e-5;

// The fastest a star image can move on the plate, px/s: f w / cos^2(theta) at
// the format's corner (a star on the celestial equator, gnomonic projection).
double MaxTrailRate_px_per_s(const DetectContext& context) {
  if (!context.camera || context.camera->nominal_principal_distance_mm <= 0) {
    throw Error(context.request.scan, "trails need a camera definition with its principal distance (--camera)");
  }
  const double f_mm = context.camera->nominal_principal_distance_mm;
  const double half_diagonal_mm = 0.5 * std::hypot(context.camera->format_width_mm, context.camera->format_height_mm);
  const double sec2 = 1.0 + (half_diagonal_mm / f_mm) * (half_diagonal_mm / f_mm);
  return f_mm * kSiderealRate_rad_per_s * sec2 * 1e3 / context.pixel_size_um;
}

// The camera's format (centred on its reseau's origin) through the reseau's plate-to-pixel similarity:
// nothing is exposed outside it (a trail entering the format has lost its first dashes there). Empty
// without a placed reseau or a format size.
std::vector<PixelPoint> ExposedOutline_px(const DetectContext& context) {
  if (!context.camera || !context.reseau || !context.reseau->found || context.camera->format_width_mm <= 0 ||
      context.camera->format_height_mm <= 0)
    return {};
  const double w = 0.5 * context.camera->format_width_mm, h = 0.5 * context.camera->format_height_mm;
  const PlateToPixel& m = context.reseau->plate_to_pixel;
  return {m.Apply(-w, -h), m.Apply(w, -h), m.Apply(w, h), m.Apply(-w, h)};
}

DutyCycleScheduleOptions TrailSchedule(const TrailRequest& trails) {
  DutyCycleScheduleOptions schedule;
  schedule.start_s = 0.0;  // times count from the plate's first opening
  schedule.leading_dashes = trails.leading_dashes;
  schedule.break_s = trails.break_s;
  std::string why;
  if (!schedule.Check(&why)) throw Error("trail program", why);
  return schedule;
}

MeasuredPoint StarRow(const DetectedStar& star) {
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
  return row;
}

// A tagged trail image. Its position and sigmas are the image's own measurement (the detector's
// segment or PSF fit: independent of its neighbours; docs/detect.md, "Duty-cycle trails"), with the
// decoder's tags. The trail's fitted track at the image's mid-exposure (smooth along the trail, its
// errors correlated from dot to dot, its sigma the track's formal one) is only a flag, track_x_px/
// track_y_px with track_sigma_*_px, for the images the track was fitted to (track_fit, and bad ones).
// An image off its track (bad) is rejected; one found along the plate's flow beyond the track's images
// (flow_check) or measured at the track's prediction (forced_fit) has no track of its own here.
MeasuredPoint TrailRow(const DetectedStar& star, const TrailImage& t, const TrailLinkResult& linked,
                       const UtcInstant& start_utc) {
  MeasuredPoint row = StarRow(star);
  const bool dot = t.kind == ExposureKind::kDot;
  row.kind = dot ? PointKind::kTrailDot : PointKind::kTrailDash;
  row.star_id = "S" + std::to_string(t.star + 1);
  row.trail = "T" + std::to_string(t.trail);
  row.dot = dot ? t.dot_index : t.dash_index;
  row.id = row.star_id + "-" + row.trail + (dot ? "-D" : "-L") + std::to_string(*row.dot);
  row.mid_time_utc = FormatUtcIso8601(start_utc.PlusSeconds(t.mid_s), 3);
  char value[64];
  std::snprintf(value, sizeof value, t.flow_checked ? "flow_residual_px=%.4f" : "track_residual_px=%.4f",
                t.residual_px);
  row.flags.push_back(value);
  // (the evidence its trail was decoded by: a run of leading dashes is the strongest, a lone trail's the weakest)
  row.flags.push_back(std::string("trail_step=") + TrailStepName(linked.chains[t.chain].decoded_by));
  if (!t.flow_checked && !t.forced) {
    std::snprintf(value, sizeof value, "track_x_px=%.4f", t.refined_px.x_px);
    row.flags.push_back(value);
    std::snprintf(value, sizeof value, "track_y_px=%.4f", t.refined_px.y_px);
    row.flags.push_back(value);
    std::snprintf(value, sizeof value, "track_sigma_x_px=%.5f", t.sigma_refined_x_px);
    row.flags.push_back(value);
    std::snprintf(value, sizeof value, "track_sigma_y_px=%.5f", t.sigma_refined_y_px);
    row.flags.push_back(value);
  }
  if (t.bad) {
    row.status = PointStatus::kRejected;
    row.flags.push_back("rejected:bad_fit");
    return row;
  }
  row.flags.push_back(t.flow_checked ? "flow_check" : t.forced ? "forced_fit" : "track_fit");
  return row;
}

// The plate's star widths (detect/star_width_model.h) as FWHM: the model, and its values over the scan.
nlohmann::json WidthModelJson(const StarWidthModel& model, double start_fwhm_px) {
  nlohmann::json j = {{"start_fwhm_px", start_fwhm_px}, {"degree", model.degree}, {"stars_used", model.stars_used}};
  if (model.degree < 0) return j;
  j["fwhm_px_at_centre"] = kFwhmPerSigma * model.SigmaAt(model.centre_x_px, model.centre_y_px);
  j["fwhm_px_min"] = kFwhmPerSigma * model.min_sigma_px;
  j["fwhm_px_max"] = kFwhmPerSigma * model.max_sigma_px;
  j["scatter_fwhm_px"] = kFwhmPerSigma * model.scatter_px;
  j["profile_misfit"] = model.profile_misfit;
  j["sigma_px_coefficients"] = model.coefficients;  // 1, u, v, u^2, uv, v^2; u, v = -1..1 over the scan
  return j;
}

}  // namespace

StageOutput RunStarStage(const DetectContext& context, std::vector<MeasuredPoint>* rows) {
  const DetectRequest& request = context.request;
  StarDetectorOptions options;
  options.dark = !request.stars_bright;
  options.psf_fwhm_px = request.star_fwhm_px;
  if (context.reseau) {
    // Crosses are not stars: mask every cross found, out to half its arm, along its arms (the grid's axes
    // in the scan): star images between the arms are measured, the arms' pixels left out of their fits.
    for (const DetectedPoint& p : context.reseau->points)
      if (p.status != PointStatus::kMissing) options.mask.points_px.push_back(p.position_px);
    options.mask.radius_px = 0.5 * context.grid->mark.arm_length_um / context.pixel_size_um + 3.0;
    const double* a = context.reseau->plate_to_pixel.a;
    const double x_scale = std::hypot(a[0], a[2]), y_scale = std::hypot(a[1], a[3]);
    if (context.grid->mark.type == MarkType::kCross && x_scale > 0 && y_scale > 0) {
      options.mask.arm_axes_px[0] = {a[0] / x_scale, a[2] / x_scale};
      options.mask.arm_axes_px[1] = {a[1] / y_scale, a[3] / y_scale};
      // Half the line plus 3 sigma of a scan's blur (~0.5 px); an arm's own pieces peak within it.
      options.mask.arm_half_width_px = 0.5 * context.grid->mark.line_width_um / context.pixel_size_um + 1.5;
      options.mask.arm_reach_px = options.mask.arm_half_width_px;
    }
  }
  std::optional<UtcInstant> start_utc;
  DutyCycleScheduleOptions schedule;
  TrailOptions trail_options;
  if (request.trails) {
    try {
      start_utc = ParseUtcIso8601(request.trails->start_utc);
    } catch (const Error& e) {
      throw Error("--trails-start-utc", "'" + request.trails->start_utc + "' is not an ISO 8601 UTC time");
    }
    schedule = TrailSchedule(*request.trails);
    // Trail mode (docs/trails.md): a 20 s dash is a star image swept along the arc, not a line defect;
    // a dot is one image, never a pair.
    const double rate_px_per_s = MaxTrailRate_px_per_s(context);
    options.max_dash_length_px = 20.0 * rate_px_per_s;
    options.pair_chi2_gain = 1e12;
    trail_options.max_dash_spacing_px = 1.5 * options.max_dash_length_px;
    trail_options.psf_fwhm_px = options.psf_fwhm_px;
    trail_options.image_min_px = {0.0, 0.0};
    trail_options.image_max_px = {context.image.info().width_px - 1.0, context.image.info().height_px - 1.0};
    trail_options.exposed_outline_px = ExposedOutline_px(context);
    trail_options.require_joined = request.trails->require_joined;
    trail_options.blind = options.mask;
  }
  StarDetectionStats stats;
  const std::vector<DetectedStar> stars = DetectStars(context.image, options, &stats);

  StageOutput out;
  int measured = 0, rejected = 0;
  for (const DetectedStar& star : stars) {
    measured += star.point.status == PointStatus::kMeasured;
    rejected += star.point.status == PointStatus::kRejected;
  }
  out.summary = {{"measured", measured}, {"rejected", rejected}};
  if (!request.trails) {
    out.summary["width_model"] = WidthModelJson(stats.width_model, options.psf_fwhm_px);
    out.summary["noise_peaks_dropped"] = stats.noise_peaks;  // docs/stars.md step 4
    out.summary["noise_peak_level_sigma"] = stats.noise_peak_level_sigma;
    rows->reserve(rows->size() + stars.size());
    for (const DetectedStar& star : stars) rows->push_back(StarRow(star));
    out.message = std::to_string(stars.size()) + " images";
    return out;
  }

  // The scan's pixels, read in windows: the lone trails' runs and the decoded trails' undetected dots.
  ScanPixels scan;
  scan.read = [&image = context.image](const PixelRect& rect, float* values_dn) { image.ReadWindowInto(rect, values_dn); };
  scan.width_px = context.image.info().width_px, scan.height_px = context.image.info().height_px;
  scan.dark = options.dark;
  scan.low_dn = options.floor_dn;
  scan.high_dn = options.saturation_dn.value_or(context.image.info().full_scale_dn);
  const TrailLinkResult linked = LinkTrails(stars, schedule, trail_options, &scan);
  // The decoded trails' undetected dots, measured where their tracks put them.
  ForcedDotOptions forced_options;
  forced_options.enabled = request.trails->forced_dots;
  ForcedDotStats forced_stats;
  const std::vector<ForcedDot> forced =
      MeasureMissingDots(scan, stars, linked, schedule, trail_options, forced_options, &forced_stats);
  context.image.ReleaseCachedTiles();  // the trails' windows are all read: the cache's tiles go before the rows grow
  std::vector<bool> replaced(stars.size(), false);  // detections re-measured as a trail's dot
  for (const ForcedDot& f : forced)
    if (f.replaces >= 0) replaced[f.replaces] = true;
  rows->reserve(rows->size() + stars.size() - std::count(replaced.begin(), replaced.end(), true) + forced.size());
  std::map<std::string, long> unassigned;
  for (size_t i = 0; i < stars.size(); ++i) {
    if (replaced[i]) continue;
    const TrailImage& t = linked.images[i];
    MeasuredPoint row = StarRow(stars[i]);
    if (!t.assigned) {
      const std::string why = TrailReasonName(t.reason);
      if (t.reason != TrailReason::kNotStar) row.flags.push_back("trail:" + why);
      unassigned[why]++;
      rows->push_back(std::move(row));
      continue;
    }
    rows->push_back(TrailRow(stars[i], t, linked, *start_utc));
  }
  for (const ForcedDot& f : forced) rows->push_back(TrailRow(f.image, f.tag, linked, *start_utc));
  nlohmann::json reasons = nlohmann::json::object();
  for (const auto& [reason, n] : unassigned) reasons[reason] = n;
  long decoded = 0;
  nlohmann::json by_step = nlohmann::json::object();
  for (const TrailChain& c : linked.chains)
    if (c.trail > 0) {
      const char* step = TrailStepName(c.decoded_by);
      ++decoded, by_step[step] = by_step.value(step, 0L) + 1;
    }
  out.summary["trails"] = {{"decoded_trails", decoded},
                           {"refused_runs", static_cast<long>(linked.chains.size()) - decoded},
                           {"refused_readings", linked.refused_readings},
                           {"decoded_trails_by_step", by_step},
                           {"stars", linked.stars.size()},
                           {"assigned_dots", linked.assigned_dots},
                           {"assigned_dashes", linked.assigned_dashes},
                           {"bad_images", linked.bad_images},
                           {"forced_dots",
                            {{"tried", forced_stats.tried},
                             {"measured", forced_stats.measured},
                             {"outside", forced_stats.outside},
                             {"crowded", forced_stats.crowded},
                             {"clipped", forced_stats.clipped},
                             {"failed", forced_stats.failed},
                             {"faint", forced_stats.faint},
                             {"off_place", forced_stats.off_place},
                             {"off_flux", forced_stats.off_flux}}},
                           {"unassigned_by_reason", reasons},
                           {"summary", linked.Summary()}};
  out.message = std::to_string(stars.size()) + " images; trails: " + linked.Summary() + "; " +
                std::to_string(forced.size()) + " undetected dots measured at their tracks' predictions";
  return out;
}

}  // namespace platemeter::pipeline
