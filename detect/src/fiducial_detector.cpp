#include "platemeter/detect/fiducial_detector.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <numbers>

#include "platemeter/core/error.h"
#include "platemeter/detect/overview.h"

#include "masked_pixels.h"
#include "orientation_matrix.h"

namespace platemeter {
namespace {


// One mark to find: where it is on the plate and how it is drawn.
struct Target {
  std::string id;
  double x_mm = 0, y_mm = 0;
  MarkType type = MarkType::kCross;
  double line_width_um = 0, size_um = 0;
  double arm1_mm[2] = {1, 0}, arm2_mm[2] = {0, 1};  // corner: arm directions on the plate
};

std::vector<Target> TargetsOf(const CameraDefinition& camera, const FiducialSet* set,
                              const FiducialDetectorOptions& options) {
  std::vector<Target> targets;
  if (set) {
    for (const FiducialMark& m : set->marks) {
      Target t;
      t.id = m.id;
      t.x_mm = m.x_mm, t.y_mm = m.y_mm;
      t.type = m.mark.type;
      t.line_width_um = m.mark.line_width_um;
      t.size_um = m.mark.arm_length_um;
      targets.push_back(t);
    }
  }
  if (camera.format_corners_as_fiducials) {
    struct Corner {
      const char* id;
      double sx, sy;
    };
    for (const Corner& c : {Corner{"UL", -1, 1}, Corner{"UR", 1, 1}, Corner{"LL", -1, -1}, Corner{"LR", 1, -1}}) {
      Target t;
      t.id = c.id;
      t.x_mm = 0.5 * c.sx * camera.format_width_mm;
      t.y_mm = 0.5 * c.sy * camera.format_height_mm;
      t.type = MarkType::kCorner;
      t.line_width_um = options.corner_line_width_um;
      t.size_um = options.corner_arm_length_um;
      // The arms run inward along the format edges.
      t.arm1_mm[0] = -c.sx, t.arm1_mm[1] = 0;
      t.arm2_mm[0] = 0, t.arm2_mm[1] = -c.sy;
      targets.push_back(t);
    }
  }
  return targets;
}

Eigen::Matrix2d MatrixOf(const PlateToPixel& m) {
  Eigen::Matrix2d a;
  a << m.a[0], m.a[1], m.a[2], m.a[3];
  return a;
}

// A mark as it looks on the scan (full-resolution pixels).
struct PixelShape {
  MarkType type = MarkType::kCross;
  double line_width_px = 1, size_px = 10;
  double e1[2] = {1, 0}, e2[2] = {0, 1};  // cross: arm axes; corner: arm 1 and arm 2
};

PixelShape ShapeOnScan(const Target& t, const Eigen::Matrix2d& a_px_per_mm) {
  PixelShape s;
  const double scale_px_per_mm = std::sqrt(std::abs(a_px_per_mm.determinant()));
  s.type = t.type;
  s.line_width_px = t.line_width_um * 1e-3 * scale_px_per_mm;
  s.size_px = t.size_um * 1e-3 * scale_px_per_mm;
  Eigen::Vector2d e1 = a_px_per_mm * Eigen::Vector2d(t.arm1_mm[0], t.arm1_mm[1]);
  Eigen::Vector2d e2 = a_px_per_mm * Eigen::Vector2d(t.arm2_mm[0], t.arm2_mm[1]);
  e1.normalize(), e2.normalize();
  s.e1[0] = e1.x(), s.e1[1] = e1.y(), s.e2[0] = e2.x(), s.e2[1] = e2.y();
  return s;
}

// Coverage of a point (full-res px offsets from the mark's anchor) by the unblurred mark.
bool Inside(const PixelShape& s, double dx, double dy) {
  const double u = s.e1[0] * dx + s.e1[1] * dy, v = s.e2[0] * dx + s.e2[1] * dy;
  const double hw = 0.5 * s.line_width_px;
  switch (s.type) {
    case MarkType::kCross:
      return (std::abs(u) <= hw && std::abs(v) <= 0.5 * s.size_px) || (std::abs(v) <= hw && std::abs(u) <= 0.5 * s.size_px);
    case MarkType::kDot:
      return std::hypot(dx, dy) <= 0.5 * s.size_px;
    case MarkType::kRing: {
      const double r = std::hypot(dx, dy);
      return r <= 0.5 * s.size_px && r >= 0.5 * s.size_px - s.line_width_px;
    }
    case MarkType::kCorner:
      return (std::abs(v) <= hw && u >= -hw && u <= s.size_px) || (std::abs(u) <= hw && v >= -hw && v <= s.size_px);
  }
  return false;
}

// A template of the mark at 1/factor resolution: supersampled coverage, blurred.
// anchor: template pixel coordinates of the mark's anchor (centre, corner point).
struct Template {
  cv::Mat image;
  double anchor_x = 0, anchor_y = 0;
};

Template MakeTemplate(const PixelShape& s, double factor, double blur_px, double max_arm_template_px) {
  const double f = factor;
  // Extent in full-res px around the anchor.
  double x_min, x_max, y_min, y_max;
  const double pad = 2.0 * f + 2.0 * blur_px + 0.5 * s.line_width_px;
  if (s.type == MarkType::kCorner) {
    const double reach = std::min(s.size_px, max_arm_template_px * f);
    x_min = y_min = 1e300, x_max = y_max = -1e300;
    for (double a : {-pad - 0.5 * s.line_width_px, reach})
      for (double b : {-pad - 0.5 * s.line_width_px, reach}) {
        const double x = a * s.e1[0] + b * s.e2[0], y = a * s.e1[1] + b * s.e2[1];
        x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, y), y_max = std::max(y_max, y);
      }
  } else {
    double half = s.type == MarkType::kCross ? 0.5 * s.size_px : 0.5 * s.size_px + 0.25 * s.size_px;
    half = std::min(half, max_arm_template_px * f) + pad;
    x_min = y_min = -half, x_max = y_max = half;
  }
  const int x0 = static_cast<int>(std::floor(x_min / f)), x1 = static_cast<int>(std::ceil(x_max / f));
  const int y0 = static_cast<int>(std::floor(y_min / f)), y1 = static_cast<int>(std::ceil(y_max / f));
  Template t;
  t.image = cv::Mat::zeros(y1 - y0 + 1, x1 - x0 + 1, CV_32F);
  const int sub = 5;
  for (int r = 0; r < t.image.rows; ++r)
    for (int c = 0; c < t.image.cols; ++c) {
      int in = 0;
      for (int j = 0; j < sub; ++j)
        for (int i = 0; i < sub; ++i) {
          const double dx = ((c + x0) + (i + 0.5) / sub - 0.5) * f, dy = ((r + y0) + (j + 0.5) / sub - 0.5) * f;
          in += Inside(s, dx, dy);
        }
      t.image.at<float>(r, c) = static_cast<float>(in) / (sub * sub);
    }
  const double blur_template = blur_px / f;
  if (blur_template > 0.3) cv::GaussianBlur(t.image, t.image, cv::Size(0, 0), blur_template);
  t.anchor_x = -x0;
  t.anchor_y = -y0;
  return t;
}

struct Peak {
  double x = 0, y = 0;  // anchor position in the searched image's pixels
  double score = 0;     // signed normalized correlation
};

// Local maxima of |NCC| above min_score, strongest first, at least `separation` apart.
std::vector<Peak> FindPeaks(const cv::Mat& image, const Template& t, double min_score, double separation, int max_peaks) {
  std::vector<Peak> peaks;
  if (image.rows < t.image.rows || image.cols < t.image.cols) return peaks;
  cv::Mat score;
  cv::matchTemplate(image, t.image, score, cv::TM_CCOEFF_NORMED);
  cv::Mat magnitude = cv::abs(score);
  cv::Mat dilated;
  cv::dilate(magnitude, dilated, cv::Mat::ones(3, 3, CV_8U));
  for (int r = 0; r < score.rows; ++r)
    for (int c = 0; c < score.cols; ++c) {
      const float m = magnitude.at<float>(r, c);
      if (m >= min_score && m >= dilated.at<float>(r, c) && std::isfinite(m))
        peaks.push_back({c + t.anchor_x, r + t.anchor_y, score.at<float>(r, c)});
    }
  std::sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) { return std::abs(a.score) > std::abs(b.score); });
  std::vector<Peak> kept;
  for (const Peak& p : peaks) {
    bool close = false;
    for (const Peak& k : kept) close = close || std::hypot(p.x - k.x, p.y - k.y) < separation;
    if (!close) kept.push_back(p);
    if (static_cast<int>(kept.size()) >= max_peaks) break;
  }
  return kept;
}

cv::Mat AsMat(ImageWindow& window) {
  return cv::Mat(static_cast<int>(window.rect.height_px), static_cast<int>(window.rect.width_px), CV_32F,
                 window.values_dn.data());
}

// Search and fit of one mark around its predicted position.
void MeasureOne(const Image& image, const Target& target, const PlateToPixel& map, const FiducialDetectorOptions& options,
                DetectedPoint* point, MarkFitResult* fit) {
  const Eigen::Matrix2d a = MatrixOf(map);
  const double scale_px_per_mm = std::sqrt(std::abs(a.determinant()));
  const PixelShape shape = ShapeOnScan(target, a);
  const PixelPoint predicted = map.Apply(target.x_mm, target.y_mm);
  point->id = target.id;
  point->kind = PointKind::kFiducial;
  point->position_px = predicted;
  point->status = PointStatus::kMissing;
  const PixelRect bounds = image.Bounds();
  if (!(predicted.x_px >= -0.5 && predicted.y_px >= -0.5 && predicted.x_px < bounds.width_px - 0.5 &&
        predicted.y_px < bounds.height_px - 0.5)) {
    point->reason = "outside_scan";
    return;
  }
  // Full-resolution search window: the template (arms cut to keep it small) anywhere within the search radius.
  const Template templ = MakeTemplate(shape, 1.0, options.blur_sigma_px, 60.0);
  const double radius = options.search_radius_mm * scale_px_per_mm;
  const long x0 = static_cast<long>(std::floor(predicted.x_px - radius - templ.anchor_x));
  const long y0 = static_cast<long>(std::floor(predicted.y_px - radius - templ.anchor_y));
  const PixelRect search = image.Clip({x0, y0, static_cast<long>(2 * radius) + templ.image.cols + 2,
                                       static_cast<long>(2 * radius) + templ.image.rows + 2});
  if (search.width_px < templ.image.cols + 2 || search.height_px < templ.image.rows + 2) {
    point->reason = "outside_scan";
    return;
  }
  ImageWindow window = image.ReadWindow(search);
  detect_internal::FillMaskedWithMedian(window.values_dn.data(), window.values_dn.size());
  const std::vector<Peak> peaks = FindPeaks(AsMat(window), templ, options.min_search_score, 1.0, 1);
  if (peaks.empty()) {
    point->reason = "not_found";
    return;
  }
  MarkFitStart start;
  start.type = shape.type;
  start.centre_px = {search.x0_px + peaks[0].x, search.y0_px + peaks[0].y};
  start.line_width_px = shape.line_width_px;
  start.size_px = shape.size_px;
  start.blur_sigma_px = options.blur_sigma_px;
  start.rotation_rad = std::atan2(shape.e1[1], shape.e1[0]);
  start.corner_handedness = shape.e1[0] * shape.e2[1] - shape.e1[1] * shape.e2[0] >= 0 ? 1 : -1;
  const PixelRect fit_rect = image.Clip(MarkFitWindow(start, options.fit));
  if (fit_rect.empty()) {
    point->reason = "outside_scan";
    return;
  }
  *fit = FitMark(image.ReadWindow(fit_rect), start, options.fit);
  point->status = PointStatus::kRejected;
  point->position_px = start.centre_px;  // where the search found it
  if (fit->too_many_masked) {
    point->status = PointStatus::kMissing;  // the scan holds no values there
    point->reason = "masked_pixels";
    return;
  }
  if (!fit->converged) {
    point->reason = "poor_fit";
    return;
  }
  // A rejected mark keeps its fitted position and sigmas, with the reason (as the reseau detector does).
  point->position_px = fit->centre_px;
  point->sigma_x_px = fit->sigma_x_px;
  point->sigma_y_px = fit->sigma_y_px;
  point->correlation_xy = fit->correlation_xy;
  const double snr = std::abs(fit->gain_dn) / std::max(fit->residual_sigma_dn, 1e-9);
  // The fit's bounds keep it near its start; ending at the edge of that box means it found something else.
  const double box = (shape.type == MarkType::kDot || shape.type == MarkType::kRing) ? 0.25 * shape.size_px + 1.0
                     : shape.type == MarkType::kCorner                                 ? 0.5 * shape.line_width_px + 2.0
                                                                                       : 2.0 * shape.line_width_px + 2.0;
  const double shift = std::hypot(fit->centre_px.x_px - start.centre_px.x_px, fit->centre_px.y_px - start.centre_px.y_px);
  if (snr < options.min_contrast_snr) {
    point->reason = "low_contrast";
  } else if (shift > 0.98 * box) {
    point->reason = "poor_fit";
  } else if (fit->outlier_fraction > options.fit.max_outlier_fraction) {
    point->reason = "defect";
  } else {
    point->status = PointStatus::kMeasured;
    point->reason.clear();
  }
}

// Least-squares similarity pixel = s R (A0 plate) + t on pairs; returns the map and the RMS.
bool FitSimilarity(const std::vector<Eigen::Vector2d>& plate_oriented, const std::vector<Eigen::Vector2d>& pixel,
                   const std::vector<double>& weights, const Eigen::Matrix2d& a0, PlateToPixel* map, double* chi2) {
  const int n = static_cast<int>(pixel.size());
  if (n < 2) return false;
  Eigen::MatrixXd m(2 * n, 4);
  Eigen::VectorXd rhs(2 * n);
  for (int i = 0; i < n; ++i) {
    const double w = std::sqrt(weights[i]);
    const Eigen::Vector2d& q = plate_oriented[i];
    m.row(2 * i) << w * q.x(), -w * q.y(), w, 0;
    m.row(2 * i + 1) << w * q.y(), w * q.x(), 0, w;
    rhs(2 * i) = w * pixel[i].x();
    rhs(2 * i + 1) = w * pixel[i].y();
  }
  const Eigen::Vector4d p = m.colPivHouseholderQr().solve(rhs);
  *chi2 = (m * p - rhs).squaredNorm();
  Eigen::Matrix2d sr;
  sr << p(0), -p(1), p(1), p(0);
  const Eigen::Matrix2d a = sr * a0;
  map->a[0] = a(0, 0), map->a[1] = a(0, 1), map->a[2] = a(1, 0), map->a[3] = a(1, 1);
  map->t[0] = p(2), map->t[1] = p(3);
  return true;
}

struct Candidate {
  PixelPoint position_px;
  double score = 0;
  int templ = 0;  // index of the template that found it
};

struct LayoutHypothesis {
  ScanOrientation orientation;
  PlateToPixel map;
  int matched = 0;
  double score_sum = 0;
};

// Corner L class on the scan from its bisector's quadrant (the scanner's small rotation does not change it).
int CornerClass(const PixelShape& s) {
  const double bx = s.e1[0] + s.e2[0], by = s.e1[1] + s.e2[1];
  return (bx > 0 ? 1 : 0) + (by > 0 ? 2 : 0);
}

std::string TemplateKey(const PixelShape& s) {
  std::ostringstream key;
  key << static_cast<int>(s.type) << ':' << s.line_width_px << ':' << s.size_px;
  if (s.type == MarkType::kCorner) key << ':' << CornerClass(s);
  return key.str();
}

// No prior: coarse candidates on an overview and a robust layout fit, one best hypothesis per orientation.
std::vector<LayoutHypothesis> PlaceLayout(const Image& image, const std::vector<Target>& targets,
                                          const FiducialDetectorOptions& options, int* candidate_count,
                                          long* masked_px) {
  const double nominal_px_per_mm = 1000.0 / options.pixel_size_um;
  const std::vector<ScanOrientation> orientations =
      options.orientation ? std::vector<ScanOrientation>{*options.orientation} : ScanOrientation::All();
  // Templates: one per distinct look of a target over all orientations.
  std::vector<std::string> keys;
  std::vector<PixelShape> shapes;
  std::vector<std::vector<int>> template_of(orientations.size(), std::vector<int>(targets.size()));
  double largest_px = 0.0, thinnest_px = 1e300;
  for (size_t o = 0; o < orientations.size(); ++o) {
    const Eigen::Matrix2d a = nominal_px_per_mm * detect_internal::OrientationMatrix(orientations[o]);
    for (size_t t = 0; t < targets.size(); ++t) {
      const PixelShape s = ShapeOnScan(targets[t], a);
      const std::string key = TemplateKey(s);
      auto it = std::find(keys.begin(), keys.end(), key);
      if (it == keys.end()) {
        keys.push_back(key);
        shapes.push_back(s);
        it = keys.end() - 1;
      }
      template_of[o][t] = static_cast<int>(it - keys.begin());
      largest_px = std::max(largest_px, std::min(s.size_px, 60.0 * s.line_width_px));
      thinnest_px = std::min(thinnest_px, s.line_width_px);
    }
  }
  // Overview: lines kept about 1.5 px wide (a thinner line drowns in the
  // background's variation), marks no more than 16 overview px across, and
  // the overview within 4096 px.
  const long long_side = std::max(image.info().width_px, image.info().height_px);
  const int by_shape = std::min(static_cast<int>(std::floor(largest_px / 16.0)), static_cast<int>(std::floor(thinnest_px / 1.5)));
  const int factor = std::max({1, by_shape, static_cast<int>((long_side + 4095) / 4096)});
  const Overview overview = BuildOverview(image, factor);
  *masked_px = overview.masked_px;
  // matchTemplate only reads its input: a header over the overview's own memory, no copy.
  const cv::Mat view(static_cast<int>(overview.height_px), static_cast<int>(overview.width_px), CV_32F,
                     const_cast<float*>(overview.values_dn.data()));
  std::vector<Candidate> candidates;
  for (size_t k = 0; k < shapes.size(); ++k) {
    const Template templ = MakeTemplate(shapes[k], factor, options.blur_sigma_px, 16.0);
    const double separation = 0.5 * std::max(templ.image.rows, templ.image.cols);
    for (const Peak& p : FindPeaks(view, templ, options.min_search_score, separation, options.candidates_per_template))
      candidates.push_back({overview.ToScan(p.x, p.y), p.score, static_cast<int>(k)});
  }
  *candidate_count = static_cast<int>(candidates.size());

  const double match_px = std::max(options.match_radius_mm * nominal_px_per_mm, 2.0 * factor);
  const double max_rotation_rad = options.max_rotation_deg * std::numbers::pi / 180.0;
  std::vector<LayoutHypothesis> best(orientations.size());
  for (size_t o = 0; o < orientations.size(); ++o) {
    const Eigen::Matrix2d a0 = detect_internal::OrientationMatrix(orientations[o]);
    std::vector<Eigen::Vector2d> q(targets.size());
    for (size_t t = 0; t < targets.size(); ++t) q[t] = a0 * Eigen::Vector2d(targets[t].x_mm, targets[t].y_mm);
    best[o].orientation = orientations[o];
    auto evaluate = [&](const Eigen::Matrix2d& sr, const Eigen::Vector2d& shift, std::vector<int>* match) {
      int matched = 0;
      double score_sum = 0;
      match->assign(targets.size(), -1);
      for (size_t t = 0; t < targets.size(); ++t) {
        const Eigen::Vector2d p = sr * q[t] + shift;
        double best_d = match_px;
        for (size_t c = 0; c < candidates.size(); ++c) {
          if (candidates[c].templ != template_of[o][t]) continue;
          const double d = std::hypot(candidates[c].position_px.x_px - p.x(), candidates[c].position_px.y_px - p.y());
          if (d <= best_d) best_d = d, (*match)[t] = static_cast<int>(c);
        }
        if ((*match)[t] >= 0) ++matched, score_sum += std::abs(candidates[(*match)[t]].score);
      }
      return std::make_pair(matched, score_sum);
    };
    std::vector<int> best_match;
    for (size_t ti = 0; ti < targets.size(); ++ti)
      for (size_t tj = ti + 1; tj < targets.size(); ++tj) {
        const Eigen::Vector2d dq = q[tj] - q[ti];
        if (dq.norm() < 1e-9) continue;
        for (size_t ci = 0; ci < candidates.size(); ++ci) {
          if (candidates[ci].templ != template_of[o][ti]) continue;
          for (size_t cj = 0; cj < candidates.size(); ++cj) {
            if (cj == ci || candidates[cj].templ != template_of[o][tj]) continue;
            const Eigen::Vector2d dp(candidates[cj].position_px.x_px - candidates[ci].position_px.x_px,
                                     candidates[cj].position_px.y_px - candidates[ci].position_px.y_px);
            // s R = dp / dq as complex numbers.
            const double den = dq.squaredNorm();
            const double re = (dp.x() * dq.x() + dp.y() * dq.y()) / den, im = (dp.y() * dq.x() - dp.x() * dq.y()) / den;
            const double s = std::hypot(re, im), angle = std::atan2(im, re);
            if (std::abs(s / nominal_px_per_mm - 1.0) > options.scale_tolerance || std::abs(angle) > max_rotation_rad)
              continue;
            Eigen::Matrix2d sr;
            sr << re, -im, im, re;
            const Eigen::Vector2d shift =
                Eigen::Vector2d(candidates[ci].position_px.x_px, candidates[ci].position_px.y_px) - sr * q[ti];
            std::vector<int> match;
            const auto [matched, score_sum] = evaluate(sr, shift, &match);
            if (matched > best[o].matched || (matched == best[o].matched && score_sum > best[o].score_sum + 1e-9)) {
              best[o].matched = matched;
              best[o].score_sum = score_sum;
              best_match = match;
            }
          }
        }
      }
    if (best[o].matched < 2) continue;
    std::vector<Eigen::Vector2d> plate, pixel;
    for (size_t t = 0; t < targets.size(); ++t)
      if (best_match[t] >= 0) {
        plate.push_back(q[t]);
        pixel.emplace_back(candidates[best_match[t]].position_px.x_px, candidates[best_match[t]].position_px.y_px);
      }
    double chi2 = 0;
    FitSimilarity(plate, pixel, std::vector<double>(plate.size(), 1.0), a0, &best[o].map, &chi2);
  }
  std::stable_sort(best.begin(), best.end(), [](const LayoutHypothesis& a, const LayoutHypothesis& b) {
    return a.matched > b.matched;
  });
  return best;
}

// Chi-square of the measured marks against one layout hypothesis (ids as that hypothesis assigns them).
double LayoutChi2(const std::vector<Target>& targets, const std::vector<DetectedPoint>& measured,
                  const LayoutHypothesis& h, double match_px, double floor_px, int* pairs) {
  const Eigen::Matrix2d a0 = detect_internal::OrientationMatrix(h.orientation);
  std::vector<Eigen::Vector2d> plate, pixel;
  std::vector<double> weights;
  for (const Target& t : targets) {
    const PixelPoint p = h.map.Apply(t.x_mm, t.y_mm);
    for (const DetectedPoint& m : measured) {
      if (m.status != PointStatus::kMeasured) continue;
      if (std::hypot(m.position_px.x_px - p.x_px, m.position_px.y_px - p.y_px) > match_px) continue;
      plate.push_back(a0 * Eigen::Vector2d(t.x_mm, t.y_mm));
      pixel.emplace_back(m.position_px.x_px, m.position_px.y_px);
      const double var = 0.5 * (m.sigma_x_px * m.sigma_x_px + m.sigma_y_px * m.sigma_y_px) + floor_px * floor_px;
      weights.push_back(1.0 / var);
      break;
    }
  }
  *pairs = static_cast<int>(plate.size());
  PlateToPixel map;
  double chi2 = 0;
  if (!FitSimilarity(plate, pixel, weights, a0, &map, &chi2)) return 1e300;
  return chi2;
}

ScanOrientation OrientationOf(const PlateToPixel& map) {
  // The 90-degree step and mirroring nearest to the map.
  const Eigen::Matrix2d a = MatrixOf(map);
  ScanOrientation best;
  double best_d = 1e300;
  for (const ScanOrientation& o : ScanOrientation::All()) {
    const Eigen::Matrix2d a0 = detect_internal::OrientationMatrix(o);
    const double d = (a / std::sqrt(std::abs(a.determinant())) - a0).norm();
    if (d < best_d) best_d = d, best = o;
  }
  return best;
}

}  // namespace

bool FiducialDetectorOptions::Check(std::string* why) const {
  if (!(pixel_size_um >= 0.0)) return *why = "pixel_size_um must be >= 0", false;
  if (!(scale_tolerance >= 0.0 && scale_tolerance < 0.5)) return *why = "scale_tolerance must be in [0, 0.5)", false;
  if (!(max_rotation_deg >= 0.0 && max_rotation_deg <= 45.0)) return *why = "max_rotation_deg must be in [0, 45]", false;
  if (!(search_radius_mm > 0.0)) return *why = "search_radius_mm must be > 0", false;
  if (!(match_radius_mm > 0.0)) return *why = "match_radius_mm must be > 0", false;
  if (!(min_search_score > 0.0 && min_search_score < 1.0)) return *why = "min_search_score must be in (0, 1)", false;
  if (!(min_contrast_snr > 0.0)) return *why = "min_contrast_snr must be > 0", false;
  if (!(blur_sigma_px >= 0.0)) return *why = "blur_sigma_px must be >= 0", false;
  if (!(corner_line_width_um > 0.0 && corner_arm_length_um > corner_line_width_um))
    return *why = "corner_arm_length_um must exceed corner_line_width_um > 0", false;
  if (!(layout_sigma_floor_px >= 0.0)) return *why = "layout_sigma_floor_px must be >= 0", false;
  if (candidates_per_template < 1) return *why = "candidates_per_template must be >= 1", false;
  return fit.Check(why);
}

FiducialDetection DetectFiducialMarks(const Image& image, const CameraDefinition& camera, const FiducialSet* set,
                                      const PlateToPixel* prior, const FiducialDetectorOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("fiducial detector options", why);
  const std::vector<Target> targets = TargetsOf(camera, set, options);
  if (targets.empty()) throw Error("camera " + camera.name, "has no fiducial set and no format corners");
  FiducialDetection result;
  result.points.resize(targets.size());
  result.fits.resize(targets.size());

  auto measure_all = [&](const PlateToPixel& map) {
    // Marks are few; one after another keeps the image cache's memory small.
    for (size_t t = 0; t < targets.size(); ++t) {
      result.points[t] = DetectedPoint{};
      result.fits[t] = MarkFitResult{};
      MeasureOne(image, targets[t], map, options, &result.points[t], &result.fits[t]);
    }
  };

  if (prior) {
    result.used_prior = true;
    result.found = true;
    result.plate_to_pixel = *prior;
    result.orientation = OrientationOf(*prior);
    result.orientation_evidence = "from the prior plate-to-pixel map";
    measure_all(*prior);
  } else {
    if (!(options.pixel_size_um > 0.0))
      throw Error("fiducial detector options", "pixel_size_um is required to find fiducials without a prior");
    const std::vector<LayoutHypothesis> hypotheses = PlaceLayout(image, targets, options, &result.candidates, &result.masked_px);
    if (hypotheses.empty() || hypotheses[0].matched < 2) {
      result.summary = "the fiducial layout could not be placed (" + std::to_string(result.candidates) + " candidates)";
      for (size_t t = 0; t < targets.size(); ++t) {
        result.points[t].id = targets[t].id;
        result.points[t].kind = PointKind::kFiducial;
        result.points[t].status = PointStatus::kMissing;
        result.points[t].reason = "not_found";
      }
      result.missing = static_cast<int>(targets.size());
      return result;
    }
    result.found = true;
    measure_all(hypotheses[0].map);
    // Orientations whose layouts match as many candidates compete on the fitted marks.
    const double match_px = options.match_radius_mm * 1000.0 / options.pixel_size_um;
    size_t chosen = 0;
    std::vector<double> chi2(hypotheses.size(), 1e300);
    std::vector<int> pairs(hypotheses.size(), 0);
    for (size_t h = 0; h < hypotheses.size() && hypotheses[h].matched == hypotheses[0].matched; ++h) {
      chi2[h] = LayoutChi2(targets, result.points, hypotheses[h], match_px, options.layout_sigma_floor_px, &pairs[h]);
      // Lower chi2 wins only by a real margin (a symmetric layout's chi2s differ by rounding).
      if (pairs[h] > pairs[chosen] || (pairs[h] == pairs[chosen] && chi2[h] < chi2[chosen] - 1e-6 * (1.0 + chi2[chosen])))
        chosen = h;
    }
    std::ostringstream evidence;
    int ties = 0;
    for (size_t h = 0; h < hypotheses.size() && hypotheses[h].matched == hypotheses[0].matched; ++h) {
      if (h == chosen) continue;
      if (pairs[h] == pairs[chosen] && chi2[h] - chi2[chosen] < options.orientation_min_excess_chi2) {
        ++ties;
        evidence << (ties == 1 ? "" : ", ") << hypotheses[h].orientation.Name() << " (chi2 " << chi2[h] << ")";
      }
    }
    if (chosen != 0) measure_all(hypotheses[chosen].map);
    result.orientation = hypotheses[chosen].orientation;
    result.plate_to_pixel = hypotheses[chosen].map;
    result.orientation_ambiguous = ties > 0;
    std::ostringstream text;
    text << "layout: orientation " << result.orientation.Name() << " matched " << hypotheses[chosen].matched << " of "
         << targets.size() << " marks, chi2 " << chi2[chosen];
    if (ties > 0) text << "; equally good: " << evidence.str();
    result.orientation_evidence = text.str();
  }
  for (const DetectedPoint& p : result.points) {
    result.measured += p.status == PointStatus::kMeasured;
    result.rejected += p.status == PointStatus::kRejected;
    result.missing += p.status == PointStatus::kMissing;
  }
  std::ostringstream summary;
  summary << result.measured << " of " << targets.size() << " fiducials measured, " << result.rejected << " rejected, "
          << result.missing << " missing" << (result.orientation_ambiguous ? "; orientation ambiguous" : "");
  result.summary = summary.str();
  return result;
}

std::vector<DetectedPoint> DetectFiducials(const Image& image, const CameraDefinition& camera, const FiducialSet* set,
                                           const PlateToPixel* prior, const FiducialDetectorOptions& options) {
  return DetectFiducialMarks(image, camera, set, prior, options).points;
}

}  // namespace platemeter
