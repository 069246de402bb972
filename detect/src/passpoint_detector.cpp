// Passpoint detection (passpoint_detector.h): list mode and automatic mode
// over the search and fit pieces of passpoint_internal.h.
#include "platemeter/detect/passpoint_detector.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <tbb/parallel_for.h>

#include "masked_pixels.h"
#include "passpoint_internal.h"
#include "platemeter/core/error.h"

namespace platemeter {
namespace {

using internal::CandidateFit;
using internal::PasspointPeak;

double Distance(const PixelPoint& a, const PixelPoint& b) { return std::hypot(a.x_px - b.x_px, a.y_px - b.y_px); }

// The point of a fitted candidate: measured, rejected with the verdict's reason, or poor_fit
// when it is not the mark (then the fitted position, or the peak's with zero sigmas if no fit).
PasspointPoint FromFit(const CandidateFit& c, double score) {
  PasspointPoint p;
  p.point.kind = PointKind::kPasspoint;
  p.fit = c.fit;
  p.search_score = score;
  p.point.position_px = c.fit.converged ? c.fit.centre_px : c.start_px;
  if (c.fit.converged) {
    p.point.sigma_x_px = c.fit.sigma_x_px;
    p.point.sigma_y_px = c.fit.sigma_y_px;
    p.point.correlation_xy = c.fit.correlation_xy;
    if (c.fit.outlier_fraction > 0.0) p.flags.push_back("outliers");
  }
  if (c.clipped) p.flags.push_back("clipped");
  p.point.status = c.is_mark && c.reason.empty() ? PointStatus::kMeasured : PointStatus::kRejected;
  p.point.reason = c.is_mark ? c.reason : "poor_fit";
  if (c.fit.too_many_masked) {  // the scan holds no values there
    p.point.status = PointStatus::kMissing;
    p.point.reason = "masked_pixels";
  }
  return p;
}

double SearchRadiusPx(const PasspointDetectorOptions& options) {
  return options.search_radius_px > 0.0 ? options.search_radius_px : 2.0 * options.diameter_px;
}

// List mode: one entry searched around its listed position.
PasspointPoint MeasureListed(const Image& image, const PasspointDetectorOptions& options,
                             const internal::PasspointTemplate& templ, const internal::PasspointTemplate& look_alike,
                             const ApproximatePasspoint& entry,
                             int* candidates, int* masked) {
  PasspointPoint missing;
  missing.point.id = entry.id;
  missing.point.kind = PointKind::kPasspoint;
  missing.point.status = PointStatus::kMissing;
  missing.point.position_px = entry.position_px;
  missing.listed_px = entry.position_px;
  const PixelRect bounds = image.Bounds();
  const PixelPoint& q = entry.position_px;
  if (!(q.x_px >= -0.5 && q.y_px >= -0.5 && q.x_px < bounds.width_px - 0.5 && q.y_px < bounds.height_px - 0.5)) {
    missing.point.reason = "outside_scan";
    return missing;
  }
  const double radius = SearchRadiusPx(options);
  const long half = static_cast<long>(std::ceil(radius + templ.anchor_x)) + 1;
  const long cx = std::lround(q.x_px), cy = std::lround(q.y_px);
  const PixelRect search = image.Clip({cx - half, cy - half, 2 * half + 1, 2 * half + 1});
  missing.point.reason = "not_found";
  if (search.width_px < templ.image.cols || search.height_px < templ.image.rows) return missing;
  ImageWindow window = image.ReadWindow(search);
  detect_internal::FillMaskedWithMedian(window.values_dn.data(), window.values_dn.size());
  const cv::Mat view(static_cast<int>(search.height_px), static_cast<int>(search.width_px), CV_32F,
                     window.values_dn.data());
  std::vector<PasspointPeak> peaks;
  for (const PasspointPeak& p : internal::FindPasspointPeaks(view, search.x0_px, search.y0_px, templ,
                                                              options.min_list_score, 0.5 * options.diameter_px, 8,
                                                              &look_alike)) {
    if (Distance(p.position_px, q) > radius) continue;
    if (p.look_alike_score > p.score) continue;  // a blob or ring of the other shape, not this mark
    if (internal::InPasspointMask(options.mask, p.position_px)) {
      ++*masked;
      continue;
    }
    peaks.push_back(p);
  }
  *candidates += static_cast<int>(peaks.size());
  if (peaks.empty()) return missing;
  // Fit the strongest few: the marks among them decide. Clean marks (measured
  // or defect) compete: two distinct ones are ambiguous. Without one, the
  // strongest faint mark (low_contrast), else the strongest peak's failure.
  std::vector<CandidateFit> fits;
  std::vector<double> scores;
  std::vector<size_t> clean, faint;
  auto distinct = [&](const std::vector<size_t>& kept, const CandidateFit& f) {
    for (size_t m : kept)
      if (Distance(fits[m].fit.centre_px, f.fit.centre_px) < 0.5 * options.diameter_px) return false;
    return true;
  };
  for (size_t i = 0; i < peaks.size() && i < 4; ++i) {
    fits.push_back(internal::FitPasspointCandidate(image, options, peaks[i].position_px));
    scores.push_back(peaks[i].score);
    const CandidateFit& f = fits.back();
    if (!f.is_mark) continue;
    std::vector<size_t>& group = f.reason == "low_contrast" ? faint : clean;
    if (distinct(clean, f) && distinct(faint, f)) group.push_back(fits.size() - 1);
  }
  PasspointPoint p;
  if (!clean.empty()) {
    size_t nearest = clean[0];
    for (size_t m : clean)
      if (Distance(fits[m].fit.centre_px, q) < Distance(fits[nearest].fit.centre_px, q)) nearest = m;
    p = FromFit(fits[nearest], scores[nearest]);
    if (clean.size() > 1) {
      p.point.status = PointStatus::kRejected;
      p.point.reason = "ambiguous";
    }
  } else {
    const size_t best = faint.empty() ? 0 : faint[0];  // peaks are strongest first
    p = FromFit(fits[best], scores[best]);
  }
  p.point.id = entry.id;
  p.listed_px = entry.position_px;
  return p;
}

void Count(PasspointDetection* d) {
  d->measured = d->rejected = d->missing = 0;
  for (const PasspointPoint& p : d->points) {
    d->measured += p.point.status == PointStatus::kMeasured;
    d->rejected += p.point.status == PointStatus::kRejected;
    d->missing += p.point.status == PointStatus::kMissing;
  }
}

std::string ReasonCounts(const std::vector<PasspointPoint>& points, PointStatus status) {
  std::vector<std::pair<std::string, int>> counts;
  for (const PasspointPoint& p : points) {
    if (p.point.status != status) continue;
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == p.point.reason; });
    if (it == counts.end()) counts.emplace_back(p.point.reason, 1);
    else ++it->second;
  }
  std::string text;
  for (const auto& [reason, n] : counts) text += (text.empty() ? "" : ", ") + reason + ": " + std::to_string(n);
  return text.empty() ? "" : " (" + text + ")";
}

}  // namespace

bool PasspointDetectorOptions::Check(std::string* why) const {
  if (shape != MarkType::kDot && shape != MarkType::kRing) return *why = "shape must be dot or ring", false;
  if (!(diameter_px >= 3.0)) return *why = "diameter_px must be >= 3 (the mark must span a few pixels)", false;
  if (shape == MarkType::kRing && !(line_width_px > 0.0 && line_width_px < 0.5 * diameter_px))
    return *why = "a ring's line_width_px must be > 0 and below half its diameter", false;
  if (!(blur_sigma_px >= 0.0)) return *why = "blur_sigma_px must be >= 0", false;
  if (!(search_radius_px >= 0.0)) return *why = "search_radius_px must be >= 0", false;
  if (!(min_search_score > 0.0 && min_search_score < 1.0)) return *why = "min_search_score must be in (0, 1)", false;
  if (!(min_list_score > 0.0 && min_list_score < 1.0)) return *why = "min_list_score must be in (0, 1)", false;
  if (!(min_contrast_snr > 0.0)) return *why = "min_contrast_snr must be > 0", false;
  if (!(size_tolerance > 0.0 && size_tolerance < 1.0)) return *why = "size_tolerance must be in (0, 1)", false;
  if (!(line_width_tolerance > 0.0)) return *why = "line_width_tolerance must be > 0", false;
  if (!(max_blur_sigma_px >= 0.0)) return *why = "max_blur_sigma_px must be >= 0", false;
  for (const PasspointMask& m : mask)
    if (!(m.radius_px >= 0.0)) return *why = "mask radius_px must be >= 0", false;
  if (tile_px < 64) return *why = "tile_px must be >= 64", false;
  if (max_candidates_per_tile < 1) return *why = "max_candidates_per_tile must be >= 1", false;
  return fit.Check(why);
}

PasspointDetection DetectPasspoints(const Image& image, const PasspointDetectorOptions& options,
                                    const std::vector<ApproximatePasspoint>* list) {
  std::string why;
  if (!options.Check(&why)) throw Error("passpoint detector options", why);
  PasspointDetection d;
  const char* shape = options.shape == MarkType::kRing ? "ring" : "dot";
  std::ostringstream look;
  look << shape << " " << options.diameter_px << " px, " << (options.dark ? "dark" : "bright");
  if (list) {
    // Entries are few and far apart: full resolution, one window each.
    d.from_list = true;
    const internal::PasspointTemplate templ = internal::MakePasspointTemplate(options, 1);
    const internal::PasspointTemplate look_alike = internal::MakeLookAlikeTemplate(options, 1);
    d.points.resize(list->size());
    std::vector<int> candidates(list->size(), 0), masked(list->size(), 0);
    tbb::parallel_for(size_t{0}, list->size(), [&](size_t i) {
      d.points[i] = MeasureListed(image, options, templ, look_alike, (*list)[i], &candidates[i], &masked[i]);
    });
    for (size_t i = 0; i < list->size(); ++i) d.candidates += candidates[i], d.masked += masked[i];
    Count(&d);
    std::ostringstream s;
    s << d.measured << " of " << list->size() << " listed passpoints measured (" << look.str() << "), " << d.rejected
      << " rejected" << ReasonCounts(d.points, PointStatus::kRejected) << ", " << d.missing << " missing"
      << ReasonCounts(d.points, PointStatus::kMissing);
    d.summary = s.str();
    return d;
  }

  d.overview_factor = internal::PasspointSearchFactor(options);
  std::vector<PasspointPeak> peaks;
  d.candidates = 0;
  for (const PasspointPeak& p : internal::SearchWholeScan(image, options, &d.tiles, &d.masked)) {
    ++d.candidates;
    // Correlating better with the other shape (a dust disk for rings, a ring for dots): not fitted at all.
    if (p.look_alike_score > p.score) {
      ++d.not_passpoints, ++d.not_passpoint_reasons["look_alike"];
      continue;
    }
    peaks.push_back(p);
  }
  // The exact model fit is the expensive part: one task per peak, results in peak order.
  std::vector<CandidateFit> fits(peaks.size());
  tbb::parallel_for(size_t{0}, peaks.size(),
                    [&](size_t i) { fits[i] = internal::FitPasspointCandidate(image, options, peaks[i].position_px); });
  // Strongest first; a fit landing on a mark already kept is the same mark seen twice (tile overlap, side lobes).
  std::vector<size_t> order(peaks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return peaks[a].score > peaks[b].score; });
  std::vector<size_t> kept;
  for (size_t i : order) {
    if (!fits[i].is_mark) continue;
    bool same = false;
    for (size_t k : kept) same = same || Distance(fits[k].fit.centre_px, fits[i].fit.centre_px) < 0.5 * options.diameter_px;
    if (same) continue;
    // A mark's centre inside the mask (the search's peak was outside it) is still a cross or fiducial.
    if (internal::InPasspointMask(options.mask, fits[i].fit.centre_px)) {
      ++d.masked;
      continue;
    }
    kept.push_back(i);
  }
  for (size_t i : order) {
    if (fits[i].is_mark) continue;
    // A side lobe of a kept mark is not a separate thing.
    bool near = false;
    const PixelPoint& at = fits[i].start_px;
    for (size_t k : kept) near = near || Distance(fits[k].fit.centre_px, at) < options.diameter_px;
    if (!near) ++d.not_passpoints, ++d.not_passpoint_reasons[fits[i].reason];
  }
  for (size_t i : kept) d.points.push_back(FromFit(fits[i], peaks[i].score));
  // Numbering: row-major by fitted position (y, then x), so the same scan always gives the same ids.
  std::sort(d.points.begin(), d.points.end(), [](const PasspointPoint& a, const PasspointPoint& b) {
    if (a.point.position_px.y_px != b.point.position_px.y_px) return a.point.position_px.y_px < b.point.position_px.y_px;
    return a.point.position_px.x_px < b.point.position_px.x_px;
  });
  for (size_t i = 0; i < d.points.size(); ++i) d.points[i].point.id = "P" + std::to_string(i + 1);
  Count(&d);
  std::ostringstream s;
  s << d.points.size() << " passpoints found (" << look.str() << "): " << d.measured << " measured, " << d.rejected
    << " rejected" << ReasonCounts(d.points, PointStatus::kRejected) << "; " << d.candidates
    << " correlation peaks in " << d.tiles << " tiles, " << d.not_passpoints << " of them not this mark";
  std::string reasons;
  for (const auto& [reason, n] : d.not_passpoint_reasons) reasons += (reasons.empty() ? "" : ", ") + reason + ": " + std::to_string(n);
  if (!reasons.empty()) s << " (" << reasons << ")";
  s << ", " << d.masked << " masked";
  d.summary = s.str();
  return d;
}

}  // namespace platemeter
