// One band of rows of the star detector (star_band.h): background mesh, matched filter, components,
// their shape tests, and the fits of their images.
#include "star_band.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <set>
#include <opencv2/imgproc.hpp>

#include "masked_pixels.h"

namespace platemeter::star_internal {
namespace {

// The band's images: the contrast (star-positive, background-subtracted), its matched-filtered
// version, and the labels of the components above the threshold.
struct BandImages {
  std::shared_ptr<const BackgroundMesh> mesh;
  cv::Mat contrast, filtered, labels;
  double noise_gain = 1;  // filtered noise over pixel noise
  int labels_used = 0;    // labels 1.. are components
  std::vector<Component> components;
};

BandImages FilterBand(const Band& b, const StarDetectorOptions& o, double sign, double psf_sigma) {
  BandImages im;
  im.mesh = std::make_shared<const BackgroundMesh>(
      ComputeBackgroundMesh(b.raw, b.width, b.rows, o.mesh_px, o.clip_sigma, b.low_dn, b.high_dn));
  const BackgroundMesh& mesh = *im.mesh;
  im.contrast.create(static_cast<int>(b.rows), static_cast<int>(b.width), CV_32F);
  tbb::parallel_for(0L, b.rows, [&](long y) {
    float* c = im.contrast.ptr<float>(static_cast<int>(y));
    const float* r = b.raw + y * b.width;
    std::vector<float> level(b.width);
    mesh.LevelRow(y, b.width, level.data());
    for (long x = 0; x < b.width; ++x) c[x] = static_cast<float>(sign * (r[x] - level[x]));
    detect_internal::FillMasked(c, static_cast<size_t>(b.width), 0.0f);  // no value: the background's, to the filter
  });
  // Matched filter: a Gaussian of the PSF's sigma; its noise is sigma * sum(w^2)^(1/2).
  const int ksize = 2 * static_cast<int>(std::ceil(3.0 * psf_sigma)) + 1;
  const cv::Mat kernel = cv::getGaussianKernel(ksize, psf_sigma, CV_64F);
  im.noise_gain = kernel.dot(kernel);  // 2-D sum(w^2) = (1-D sum)^2, its root is the 1-D sum
  cv::GaussianBlur(im.contrast, im.filtered, cv::Size(ksize, ksize), psf_sigma, psf_sigma, cv::BORDER_REFLECT);
  cv::Mat mask(im.filtered.size(), CV_8U);
  tbb::parallel_for(0L, b.rows, [&](long y) {
    const float* f = im.filtered.ptr<float>(static_cast<int>(y));
    uint8_t* m = mask.ptr<uint8_t>(static_cast<int>(y));
    for (long x = 0; x < b.width; ++x) m[x] = f[x] > o.threshold_sigma * im.noise_gain * mesh.SigmaAt(x, y) ? 1 : 0;
  });
  cv::Mat stats, centroids;
  im.labels_used = cv::connectedComponentsWithStats(mask, im.labels, stats, centroids, 8, CV_32S);
  for (int l = 1; l < im.labels_used; ++l) {
    Component c;
    c.label = l;
    c.clump = l;
    c.area = stats.at<int>(l, cv::CC_STAT_AREA);
    c.x = stats.at<int>(l, cv::CC_STAT_LEFT), c.y = stats.at<int>(l, cv::CC_STAT_TOP);
    c.width = stats.at<int>(l, cv::CC_STAT_WIDTH), c.height = stats.at<int>(l, cv::CC_STAT_HEIGHT);
    if (c.area >= o.min_pixels) im.components.push_back(c);
  }
  return im;
}

// Ratio of the major to the minor second moment of a component's mask: large for a line at any
// angle (a slanted dash fills little of its box too), about 1 for a cross.
double MaskElongation(const cv::Mat& labels, const Component& c) {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (int y = c.y; y < c.y + c.height; ++y)
    for (int x = c.x; x < c.x + c.width; ++x)
      if (labels.at<int>(y, x) == c.label) n += 1, sx += x, sy += y, sxx += double(x) * x, syy += double(y) * y, sxy += double(x) * y;
  if (n < 2) return 1.0;
  const double mx = sx / n, my = sy / n;
  Eigen::Matrix2d m;
  m << sxx / n - mx * mx, sxy / n - mx * my, sxy / n - mx * my, syy / n - my * my;
  const Eigen::Vector2d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues();
  return l(1) / std::max(l(0), 1e-3);
}

// Trail mode: deblending (dashes of a run, a faint dot beside a bright dash): a piece must rise 3.5
// filtered noise sigmas above its saddle and hold 0.5 % of the component's flux (SExtractor's default).
void SplitClumps(const StarDetectorOptions& o, BandImages* im) {
  std::vector<Component>& components = im->components;
  const BackgroundMesh& mesh = *im->mesh;
  std::vector<float> level(components.size()), rise(components.size());
  for (size_t k = 0; k < components.size(); ++k) {
    const double sigma_f = im->noise_gain * mesh.SigmaAt(components[k].x + 0.5 * components[k].width,
                                                         components[k].y + 0.5 * components[k].height);
    level[k] = static_cast<float>(o.threshold_sigma * sigma_f);
    rise[k] = static_cast<float>(3.5 * sigma_f);
  }
  // Clumps: components longer than a run of five leading dashes (140 s = 7 dash lengths), or large and
  // not line-like (crossing trails; also reseau crosses, dust, scratches). They are deblended too (on a
  // crowded plate they hold a tenth of the measurable dots) and their pieces flagged crowded: a dash
  // crossed by other images may come out in parts, which the linker must not take for empty places. A
  // defect that does not fall apart stays whole and is rejected by the shape tests below.
  std::vector<Component> whole, split;
  std::vector<float> split_level, split_rise;
  for (size_t k = 0; k < components.size(); ++k) {
    Component& c = components[k];
    const double long_side = std::max(c.width, c.height);
    const bool too_long = long_side > 7.0 * (1.0 + o.dash_length_tolerance) * o.max_dash_length_px + 6.0 * o.psf_fwhm_px;
    const bool blob = long_side > 4.0 * o.psf_fwhm_px && MaskElongation(im->labels, c) <= 3.0;
    const bool cross_like = blob && c.area < 0.3 * c.width * c.height;
    c.crowded = too_long || blob;
    if (!too_long && cross_like) {  // a reseau cross's arms would pass as dashes
      c.crowded = false;
      whole.push_back(c);
    } else {
      split.push_back(c), split_level.push_back(level[k]), split_rise.push_back(rise[k]);
    }
  }
  int next_label = im->labels_used;
  const int min_piece = std::max(o.min_pixels, static_cast<int>(0.5 * o.psf_fwhm_px * o.psf_fwhm_px));
  components = SplitComponents(&im->labels, im->filtered, split, split_level, split_rise, 2.0 * o.psf_fwhm_px,
                               min_piece, 0.005, &next_label);
  components.insert(components.end(), whole.begin(), whole.end());
}

// What every component of a band is measured with.
struct BandContext {
  const Band& b;
  const StarDetectorOptions& o;
  const StarWidthModel& width_model;
  const BandImages& im;
  double sign, psf_sigma;
  bool dash_mode;
  double dash_box_px, line_box_px;  // the longest box of one dash; of anything not a line
  int window_reach;                 // px from the peak a fit window reaches at most
  double noise_peak_level;          // filtered noise sigmas; below: pure noise (point mode)
};

// The component's brightest matched-filtered pixel (band-relative) and its value.
struct ComponentPeak {
  int x = 0, y = 0;
  float filtered = -1e30f;
};
ComponentPeak PeakOf(const BandImages& im, const Component& c) {
  ComponentPeak p{c.x, c.y};
  for (int y = c.y; y < c.y + c.height; ++y)
    for (int x = c.x; x < c.x + c.width; ++x)
      if (im.labels.at<int>(y, x) == c.label && im.filtered.at<float>(y, x) > p.filtered)
        p.filtered = im.filtered.at<float>(y, x), p.x = x, p.y = y;
  return p;
}

// Shape tests on the component: lines (scratches; dashes and trails unless in trail mode), crosses,
// masked marks (a peak on a known cross's arm). Returns the defect, if it is one; near_crosses gets the
// known crosses whose arms keep their pixels out of the component's fit (crosses of the stars'
// polarity touching an image make one component with it, a defect by its shape; of the other polarity
// they are below the threshold but push the fit away from them).
std::optional<DetectedStar> ShapeDefect(const BandContext& k, const Component& c, const ComponentPeak& peak,
                                        std::vector<PixelPoint>* near_crosses) {
  const StarDetectorOptions& o = k.o;
  const long peak_y_abs = k.b.y0_abs + peak.y;
  const double long_side = std::max(c.width, c.height);
  const bool line_like = long_side > k.line_box_px;
  bool sparse = long_side > 4.0 * o.psf_fwhm_px && c.area < 0.3 * c.width * c.height;
  if (sparse && k.dash_mode && MaskElongation(k.im.labels, c) > 3.0) sparse = false;  // a slanted dash, not a cross
  const StarMask& mask = o.mask;
  const bool masked = mask.Covers({double(peak.x), double(peak_y_abs)}, 0.0);
  for (const PixelPoint& m : mask.points_px)
    if (mask.arm_reach_px > 0 && std::hypot(m.x_px - peak.x, m.y_px - peak_y_abs) < mask.radius_px + k.window_reach * std::sqrt(2.0))
      near_crosses->push_back(m);
  if (!line_like && !sparse && !masked) return std::nullopt;
  if (!line_like) return Defect(peak.x, peak_y_abs, sparse ? "cross" : "masked");
  // A line at the centre of its box, its extent the box's diagonal (what a trail linker asks it may hide).
  const double y_abs = k.b.y0_abs + c.y;
  DetectedStar line = Defect(c.x + 0.5 * (c.width - 1), y_abs + 0.5 * (c.height - 1), "line");
  line.length_px = std::hypot(c.width, c.height);
  line.box_min_px = {c.x - 0.5, y_abs - 0.5}, line.box_max_px = {c.x + c.width - 0.5, y_abs + c.height - 0.5};
  return line;
}

// The fit window (band-relative, [x0, x1) x [y0, y1)): the component grown by the PSF, at least +-3
// sigma around the peak, at most window_reach from it; truncated where the scan's edge cut it.
struct FitWindow {
  int x0, x1, y0, y1;
  bool truncated = false;
};
FitWindow WindowOf(const BandContext& k, const Component& c, const ComponentPeak& peak, double image_sigma) {
  const int grow = static_cast<int>(std::ceil(image_sigma)) + 1;
  const int half = static_cast<int>(std::ceil(3.0 * image_sigma)) + 1;
  FitWindow w{std::min(c.x, peak.x - half) - grow, std::max(c.x + c.width, peak.x + half + 1) + grow,
              std::min(c.y, peak.y - half) - grow, std::max(c.y + c.height, peak.y + half + 1) + grow};
  w.x0 = std::max(w.x0, peak.x - k.window_reach), w.x1 = std::min(w.x1, peak.x + k.window_reach + 1);
  w.y0 = std::max(w.y0, peak.y - k.window_reach), w.y1 = std::min(w.y1, peak.y + k.window_reach + 1);
  const Band& b = k.b;
  if (w.x0 < 0) w.x0 = 0, w.truncated = true;
  if (w.x1 > b.width) w.x1 = static_cast<int>(b.width), w.truncated = true;
  if (w.y0 < 0) w.y0 = 0, w.truncated = w.truncated || b.y0_abs == 0;
  if (w.y1 > b.rows) w.y1 = static_cast<int>(b.rows), w.truncated = w.truncated || b.y0_abs + b.rows == b.image_height;
  return w;
}

ComponentPixels GatherPixels(const BandContext& k, const Component& c, const FitWindow& w,
                             const std::vector<PixelPoint>& near_crosses) {
  const Band& b = k.b;
  const StarDetectorOptions& o = k.o;
  const auto on_arm = [&](int x, long y_abs) {
    for (const PixelPoint& m : near_crosses)
      if (std::hypot(m.x_px - x, m.y_px - y_abs) < o.mask.radius_px &&
          o.mask.ArmDistance_px(m, {double(x), double(y_abs)}) <= o.mask.arm_half_width_px)
        return true;
    return false;
  };
  ComponentPixels p;
  for (int y = w.y0; y < w.y1; ++y)
    for (int x = w.x0; x < w.x1; ++x) {
      const int lab = k.im.labels.at<int>(y, x);
      if (lab != 0 && lab != c.label) continue;  // another component's pixels
      if (!near_crosses.empty() && on_arm(x, b.y0_abs + y)) continue;
      const float raw = b.raw[long(y) * b.width + x];
      if (std::isnan(raw)) {  // masked: no value in the scan
        ++p.masked;
        continue;
      }
      if (raw >= b.high_dn || raw <= b.low_dn) {
        ++p.clipped;
        continue;
      }
      const float value = k.im.contrast.at<float>(y, x);
      if (lab == c.label) p.peak_contrast_dn = std::max<double>(p.peak_contrast_dn, value);
      p.pixels.push_back({float(x), float(b.y0_abs + y), value});
      p.own.push_back(lab == c.label ? 1 : 0);
    }
  return p;
}

// Trail mode: a line's box holds its whole component too (the fit window stops window_reach from the peak).
void WidenLineBoxes(const BandContext& k, const Component& c, size_t first, std::vector<DetectedStar>* result) {
  const double y_abs = k.b.y0_abs + c.y;
  for (size_t i = first; i < result->size(); ++i) {
    DetectedStar& d = (*result)[i];
    if (d.point.reason != "line") continue;
    d.box_min_px = {std::min(d.box_min_px.x_px, c.x - 0.5), std::min(d.box_min_px.y_px, y_abs - 0.5)};
    d.box_max_px = {std::max(d.box_max_px.x_px, c.x + c.width - 0.5), std::max(d.box_max_px.y_px, y_abs + c.height - 0.5)};
  }
}

// A component's images: rows in *result, or (point mode, with a pending list) a single fit whose pair
// test waits for the plate's width model in *wait. False when its peak is noise.
bool MeasureComponent(const BandContext& k, const Component& c, std::vector<DetectedStar>* result,
                      std::optional<PendingPair>* wait) {
  const Band& b = k.b;
  const StarDetectorOptions& o = k.o;
  const ComponentPeak peak = PeakOf(k.im, c);
  const long peak_y_abs = b.y0_abs + peak.y;
  if (peak_y_abs < b.keep_y0 || peak_y_abs >= b.keep_y1) return true;
  const BackgroundMesh& mesh = *k.im.mesh;
  if (peak.filtered < k.noise_peak_level * k.im.noise_gain * mesh.SigmaAt(peak.x, peak.y)) return false;
  std::vector<PixelPoint> near_crosses;
  if (std::optional<DetectedStar> defect = ShapeDefect(k, c, peak, &near_crosses)) {
    result->push_back(*defect);
    return true;
  }
  // The width expected here: the plate's model from the bands measured so far (the start value until
  // there are bright stars to fit it to).
  const double image_sigma = k.width_model.SigmaAt(peak.x, peak_y_abs);
  const FitWindow w = WindowOf(k, c, peak, image_sigma);
  ComponentPixels pixels = GatherPixels(k, c, w, near_crosses);
  if (pixels.masked > o.max_masked_fraction * (pixels.pixels.size() + pixels.clipped + pixels.masked)) {
    result->push_back(Defect(peak.x, peak_y_abs, "masked_pixels"));
    return true;
  }
  const double noise = std::max(1e-3f, mesh.SigmaAt(peak.x, peak.y));
  const Box window{w.x0 - 0.5, w.x1 - 0.5, b.y0_abs + w.y0 - 0.5, b.y0_abs + w.y1 - 0.5};
  if (k.dash_mode) {
    // A sweep clearly longer than the PSF: fitted as a segment (dash, long dot), not as a star.
    const SweepMoments m = ComponentSweep(pixels);
    if (m.length_px > o.psf_fwhm_px) {
      const size_t first = result->size();
      MeasureSegment(m, pixels, noise, k.psf_sigma, w.truncated, o, mesh, b.y0_abs, k.sign, window, result);
      WidenLineBoxes(k, c, first, result);
      return true;
    }
  }
  FittedGaussian start;
  start.x_px = peak.x;
  start.y_px = peak_y_abs;
  start.sigma_px = image_sigma;
  start.flux_dn = std::max(4.0 * M_PI * image_sigma * image_sigma * peak.filtered,
                           2.0 * M_PI * image_sigma * image_sigma * pixels.peak_contrast_dn);
  const double min_sigma = o.min_fwhm_ratio * image_sigma * 0.5;
  GaussianFitResult fit = FitGaussians(pixels.pixels, {start}, noise, min_sigma);
  if (fit.stars.empty()) return true;
  const PointFitPlace at{k.psf_sigma, image_sigma, noise, k.im.mesh, k.sign, b.y0_abs, window, pixels.clipped > 0, w.truncated};
  bool blended = false;
  if (PairTestWanted(fit, image_sigma)) {
    if (wait) {  // reported as one star for now (it counts for the width model), decided at the end
      ReportPointFits(fit, false, pixels.pixels, at, o, result);
      *wait = PendingPair{std::move(pixels), at, start, std::move(fit), 0, result->size()};
      return true;
    }
    blended = TryPair(pixels, start, image_sigma, noise, min_sigma, o, &fit);
  }
  ReportPointFits(fit, blended, pixels.pixels, at, o, result);
  return true;
}

// A clump still holding a line after deblending holds a scratch: its other pieces are parts of it, or
// of what it crosses (a reseau cross's arms, cut from it, pass as dashes): all rejected as the line. (A
// piece too long for its box is seen in every band; a segment fitted too long only in the band of its
// peak.)
void FlagCrowdedPieces(const std::vector<Component>& components, double line_box_px,
                       std::vector<std::vector<DetectedStar>>* found) {
  std::set<int> line_clumps;
  for (size_t ci = 0; ci < components.size(); ++ci) {
    const Component& cc = components[ci];
    if (!cc.crowded) continue;
    if (std::max(cc.width, cc.height) > line_box_px) line_clumps.insert(cc.clump);
    for (const DetectedStar& d : (*found)[ci])
      if (d.point.reason == "line") line_clumps.insert(cc.clump);
  }
  for (size_t ci = 0; ci < components.size(); ++ci) {
    if (!components[ci].crowded) continue;
    for (DetectedStar& d : (*found)[ci]) {
      d.flags |= kStarCrowded;
      if (line_clumps.count(components[ci].clump) && d.point.status == PointStatus::kMeasured)
        d.point.status = PointStatus::kRejected, d.point.reason = "line", d.flags |= kStarDefect;
    }
  }
}

void CountBand(const BandImages& im, long noise_peaks, double noise_peak_level, StarDetectionStats* stats) {
  if (!stats) return;
  stats->components += im.labels_used - 1, stats->noise_peaks += noise_peaks, ++stats->bands;
  stats->noise_peak_level_sigma = noise_peak_level;
  if (stats->noise_sigma_dn == 0 && !im.mesh->sigma_dn.empty()) {
    std::vector<float> s = im.mesh->sigma_dn;
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    stats->noise_sigma_dn = s[s.size() / 2];
  }
}

}  // namespace

void ProcessBand(const Band& b, const StarDetectorOptions& o, const StarWidthModel& width_model,
                 std::vector<DetectedStar>* out, StarDetectionStats* stats, std::vector<PendingPair>* pending) {
  const double sign = o.dark ? -1.0 : 1.0;
  const double psf_sigma = o.psf_fwhm_px / kFwhmPerSigma;
  BandImages im = FilterBand(b, o, sign, psf_sigma);
  // Trail mode: the longest box one dash may have (its length, the tolerance, and the PSF's wings
  // above the threshold at both ends); longer components are split at their gaps first.
  const bool dash_mode = o.max_dash_length_px > 0;
  const double dash_box_px = (1.0 + o.dash_length_tolerance) * o.max_dash_length_px + 6.0 * o.psf_fwhm_px;
  const double line_box_px = dash_mode ? std::max(o.max_component_fwhm * o.psf_fwhm_px, dash_box_px)
                                       : o.max_component_fwhm * o.psf_fwhm_px;
  if (dash_mode) SplitClumps(o, &im);
  const int window_reach = dash_mode ? std::max(40, static_cast<int>(std::ceil(0.5 * dash_box_px + 3.0 * psf_sigma))) : 40;
  // Point mode: below the level that pure noise, filtered, reaches once in ten scans of this size, a
  // peak cannot be told from noise: not fitted, no row (a star that faint has no position worth one).
  constexpr double kNoisePeaksPerScan = 0.1;
  const double noise_peak_level =
      dash_mode ? 0.0 : NoisePeakLevel(static_cast<double>(b.width) * b.image_height, psf_sigma, kNoisePeaksPerScan);
  const BandContext k{b, o, width_model, im, sign, psf_sigma, dash_mode, dash_box_px, line_box_px, window_reach, noise_peak_level};

  const std::vector<Component>& components = im.components;
  std::vector<std::vector<DetectedStar>> found(components.size());
  std::vector<std::optional<PendingPair>> waiting(pending ? components.size() : 0);
  std::atomic<long> noise_peaks{0};
  tbb::parallel_for(size_t{0}, components.size(), [&](size_t ci) {
    if (!MeasureComponent(k, components[ci], &found[ci], pending ? &waiting[ci] : nullptr)) ++noise_peaks;
  });
  FlagCrowdedPieces(components, line_box_px, &found);
  for (size_t ci = 0; ci < components.size(); ++ci) {
    if (pending && waiting[ci]) {
      waiting[ci]->first_row = out->size();
      pending->push_back(std::move(*waiting[ci]));
    }
    for (DetectedStar& d : found[ci]) {
      const bool provisional = pending && waiting[ci];  // counted once decided (ResolvePendingPairs)
      if (stats && !provisional && d.point.status == PointStatus::kRejected) ++stats->defects;
      out->push_back(std::move(d));
    }
  }
  CountBand(im, noise_peaks, noise_peak_level, stats);
}

}  // namespace platemeter::star_internal
