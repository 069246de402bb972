#include "platemeter/detect/fiducial_fit.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

#include "bar_profile.h"
#include "mark_disk_profile.h"
#include "mark_fit_engine.h"
#include "platemeter/detect/cross_fit.h"

namespace platemeter {
namespace {

using internal::BarProfile;
using internal::DiskProfileTable;
using internal::DiskProfileValue;
using internal::EvaluateBarProfile;
using internal::MarkSample;

constexpr double kHalfDiagonal = 0.70710678118654752;

// 6-node Gauss-Legendre on [-1, 1].
constexpr double kNodes6[6] = {-0.9324695142031521, -0.6612093864662645, -0.2386191860831969,
                               0.2386191860831969,  0.6612093864662645,  0.9324695142031521};
constexpr double kWeights6[6] = {0.1713244923791704, 0.3607615730481386, 0.4679139345726910,
                                 0.4679139345726910, 0.3607615730481386, 0.1713244923791704};

// Quadrature nodes over the unit pixel: cells x cells sub-cells of 6 x 6 nodes; weights sum to 1.
struct PixelRule {
  std::vector<double> dx, dy, w;
  explicit PixelRule(int cells) {
    const double h = 1.0 / cells;
    for (int cy = 0; cy < cells; ++cy)
      for (int cx = 0; cx < cells; ++cx)
        for (int j = 0; j < 6; ++j)
          for (int i = 0; i < 6; ++i) {
            dx.push_back(-0.5 + (cx + 0.5) * h + 0.5 * h * kNodes6[i]);
            dy.push_back(-0.5 + (cy + 0.5) * h + 0.5 * h * kNodes6[j]);
            w.push_back(0.25 * h * h * kWeights6[i] * kWeights6[j]);
          }
  }
};

int CellsForBlur(double sigma_px) {
  return static_cast<int>(std::clamp(std::ceil(1.0 / (2.5 * sigma_px) - 1e-9), 1.0, 12.0));
}

// Adds sign * (pixel mean of the blurred disk) and its derivatives (x0, y0, radius, sigma).
void AddDisk(const DiskProfileTable& table, const PixelRule& rule, double dx, double dy, double sign, double* value,
             double* d) {
  const double rc = std::hypot(dx, dy);
  if (rc >= table.reach_px() + kHalfDiagonal) return;
  if (table.inner_px() > 0.0 && rc <= table.inner_px() - kHalfDiagonal) {
    *value += sign;
    return;
  }
  double v = 0, gx = 0, gy = 0, gr = 0, gs = 0;
  for (size_t k = 0; k < rule.w.size(); ++k) {
    const double x = dx + rule.dx[k], y = dy + rule.dy[k];
    const double r = std::hypot(x, y);
    const DiskProfileValue p = table.At(r);
    const double w = rule.w[k];
    v += w * p.value;
    if (d && r > 0.0) {
      gx -= w * p.d_r * x / r;  // d r / d x0 = -x / r
      gy -= w * p.d_r * y / r;
    }
    gr += w * p.d_radius;
    gs += w * p.d_sigma;
  }
  *value += sign * v;
  if (d) {
    d[0] += sign * gx;
    d[1] += sign * gy;
    d[2] += sign * gr;
    d[3] += sign * gs;
  }
}

// Dot: x0, y0, diameter, sigma.
class DotModel : public internal::MarkShapeModel {
 public:
  int num_shape() const override { return 2; }
  void Evaluate(const double* p, const std::vector<MarkSample>& samples, double* values,
                double* derivatives) const override {
    const double sigma = std::max(p[3], 1e-3);
    const DiskProfileTable table(0.5 * std::max(p[2], 1e-3), sigma);
    const PixelRule rule(CellsForBlur(sigma));
    for (size_t i = 0; i < samples.size(); ++i) {
      double value = 0.0, d[4] = {0, 0, 0, 0};
      AddDisk(table, rule, samples[i].x_px - p[0], samples[i].y_px - p[1], 1.0, &value, derivatives ? d : nullptr);
      values[i] = value;
      if (derivatives) {
        double* row = derivatives + i * 4;
        row[0] = d[0];
        row[1] = d[1];
        row[2] = 0.5 * d[2];  // per diameter
        row[3] = d[3];
      }
    }
  }
};

// Ring: x0, y0, outer diameter, line width, sigma.
class RingModel : public internal::MarkShapeModel {
 public:
  int num_shape() const override { return 3; }
  void Evaluate(const double* p, const std::vector<MarkSample>& samples, double* values,
                double* derivatives) const override {
    const double sigma = std::max(p[4], 1e-3);
    const double outer = 0.5 * std::max(p[2], 1e-3);
    const double inner = outer - p[3];
    const DiskProfileTable outer_table(outer, sigma);
    const bool has_inner = inner > 1e-3;
    const DiskProfileTable inner_table(has_inner ? inner : 1.0, sigma);
    const PixelRule rule(CellsForBlur(sigma));
    for (size_t i = 0; i < samples.size(); ++i) {
      const double dx = samples[i].x_px - p[0], dy = samples[i].y_px - p[1];
      double value = 0.0, a[4] = {0, 0, 0, 0}, b[4] = {0, 0, 0, 0};
      AddDisk(outer_table, rule, dx, dy, 1.0, &value, derivatives ? a : nullptr);
      if (has_inner) AddDisk(inner_table, rule, dx, dy, -1.0, &value, derivatives ? b : nullptr);
      values[i] = value;
      if (derivatives) {
        // b holds -(derivatives of the inner disk); inner radius = outer - w.
        double* row = derivatives + i * 5;
        row[0] = a[0] + b[0];
        row[1] = a[1] + b[1];
        row[2] = 0.5 * (a[2] + b[2]);  // d/d diameter: both radii move by half of it
        row[3] = -b[2];                // d/dw = -dD_inner/d inner_radius * (-1), with b = -dD_inner
        row[4] = a[3] + b[3];
      }
    }
  }
};

// The bar profile, exactly 1 or 0 (no derivatives) where the pixel and 7 blur
// sigmas lie wholly inside or outside the bar (error below 1e-11): most
// pixels of a long arm are far from the arm's ends.
BarProfile FastBarProfile(double t, double width, double sigma) {
  const double reach = 0.5 + 7.0 * sigma, a = std::abs(t);
  if (a <= 0.5 * width - reach) return {1.0, 0.0, 0.0, 0.0};
  if (a >= 0.5 * width + reach) return {};
  return EvaluateBarProfile(t, width, sigma);
}

// Corner: x0, y0, theta, w1, w2, sigma; arm length and handedness fixed.
class CornerModel : public internal::MarkShapeModel {
 public:
  CornerModel(double length_px, int handedness) : length_(length_px), chi_(handedness >= 0 ? 1.0 : -1.0) {}
  int num_shape() const override { return 4; }
  void Evaluate(const double* p, const std::vector<MarkSample>& samples, double* values,
                double* derivatives) const override {
    const double c = std::cos(p[2]), sn = std::sin(p[2]);
    const double w1 = p[3], w2 = p[4], s = std::max(p[5], 1e-3), len = length_;
    for (size_t i = 0; i < samples.size(); ++i) {
      const double dx = samples[i].x_px - p[0], dy = samples[i].y_px - p[1];
      const double pp = c * dx + sn * dy;            // along arm 1
      const double qq = chi_ * (-sn * dx + c * dy);  // along arm 2
      // arm 1: q in [-w1/2, w1/2], p in [-w2/2, len]; arm 2: p in [-w2/2, w2/2], q in [-w1/2, len].
      const BarProfile q1 = FastBarProfile(qq, w1, s);
      const BarProfile p1 = FastBarProfile(pp - 0.5 * (len - 0.5 * w2), len + 0.5 * w2, s);
      const BarProfile p2 = FastBarProfile(pp, w2, s);
      const BarProfile q2 = FastBarProfile(qq - 0.5 * (len - 0.5 * w1), len + 0.5 * w1, s);
      values[i] = q1.value * p1.value + p2.value * q2.value - p2.value * q1.value;
      if (!derivatives) continue;
      const double ds_dp = q1.value * p1.d_t + p2.d_t * q2.value - p2.d_t * q1.value;
      const double ds_dq = q1.d_t * p1.value + p2.value * q2.d_t - p2.value * q1.d_t;
      const double dp1_dw2 = 0.25 * p1.d_t + 0.5 * p1.d_width;
      const double dq2_dw1 = 0.25 * q2.d_t + 0.5 * q2.d_width;
      double* row = derivatives + i * 6;
      // dp/dx0 = -c, dp/dy0 = -sn; dq/dx0 = chi sn, dq/dy0 = -chi c; dp/dtheta = chi q, dq/dtheta = -chi p.
      row[0] = -c * ds_dp + chi_ * sn * ds_dq;
      row[1] = -sn * ds_dp - chi_ * c * ds_dq;
      row[2] = chi_ * qq * ds_dp - chi_ * pp * ds_dq;
      row[3] = q1.d_width * p1.value + p2.value * dq2_dw1 - p2.value * q1.d_width;
      row[4] = q1.value * dp1_dw2 + p2.d_width * q2.value - p2.d_width * q1.value;
      row[5] = q1.d_sigma * p1.value + q1.value * p1.d_sigma + p2.d_sigma * q2.value + p2.value * q2.d_sigma -
               p2.d_sigma * q1.value - p2.value * q1.d_sigma;
    }
  }

 private:
  double length_;
  double chi_;
};

double DiskUncertaintyPx(const MarkFitStart& start) { return 0.25 * start.size_px + 1.0; }
double CornerUncertaintyPx(const MarkFitStart& start) { return 0.5 * start.line_width_px + 2.0; }

double DiskSampleRadius(const MarkFitStart& start, const MarkFitOptions& options) {
  return 0.5 * start.size_px + 4.0 * std::max(start.blur_sigma_px, 0.5) + options.margin_px + DiskUncertaintyPx(start);
}

// Corner geometry: the band around each arm's centre line and how far along the arm pixels are used.
struct CornerReach {
  double band_px, behind_px, ahead_px;
};
CornerReach CornerReachOf(const MarkFitStart& start, const MarkFitOptions& options) {
  const double blur = 4.0 * std::max(start.blur_sigma_px, 0.5);
  CornerReach r;
  r.band_px = 0.5 * start.line_width_px + blur + options.margin_px + CornerUncertaintyPx(start);
  r.behind_px = r.band_px;
  // Short of the far end (blur, margin and the start's uncertainty), and never beyond the cap.
  r.ahead_px = std::min(start.size_px - blur - options.margin_px - CornerUncertaintyPx(start), options.max_corner_arm_px);
  r.ahead_px = std::max(r.ahead_px, r.band_px + start.line_width_px);
  return r;
}

MarkFitResult FromCross(const CrossFitResult& fit) {
  MarkFitResult r;
  r.type = MarkType::kCross;
  r.converged = fit.converged;
  r.centre_px = fit.centre_px;
  r.sigma_x_px = fit.sigma_x_px;
  r.sigma_y_px = fit.sigma_y_px;
  r.correlation_xy = fit.correlation_xy;
  r.size_px = fit.arm_length_px;
  r.line_width_px = fit.width_h_px;
  r.line_width_2_px = fit.width_v_px;
  r.rotation_rad = fit.rotation_rad;
  r.blur_sigma_px = fit.blur_sigma_px;
  r.gain_dn = fit.gain_dn;
  r.background_dn = fit.background_dn;
  r.residual_sigma_dn = fit.residual_sigma_dn;
  r.outlier_fraction = fit.outlier_fraction;
  r.pixels_masked = fit.pixels_masked;
  r.masked_fraction = fit.masked_fraction;
  r.too_many_masked = fit.too_many_masked;
  r.pixels_used = fit.pixels_used;
  r.summary = fit.summary;
  return r;
}

CrossFitOptions CrossOptions(const MarkFitOptions& options) {
  CrossFitOptions c;
  c.margin_px = options.margin_px;
  c.min_blur_sigma_px = options.min_blur_sigma_px;
  c.outlier_threshold = options.outlier_threshold;
  c.min_outlier_contrast = options.min_outlier_contrast;
  c.max_masked_fraction = options.max_masked_fraction;
  c.max_iterations = options.max_iterations;
  return c;
}

CrossFitStart CrossStart(const MarkFitStart& start) {
  CrossFitStart c;
  c.centre_px = start.centre_px;
  c.rotation_rad = start.rotation_rad;
  c.line_width_px = start.line_width_px;
  c.arm_length_px = start.size_px;
  c.blur_sigma_px = start.blur_sigma_px;
  return c;
}

}  // namespace

bool MarkFitOptions::Check(std::string* why) const {
  if (!(margin_px >= 0.0)) return *why = "margin_px must be >= 0", false;
  if (!(min_blur_sigma_px > 0.0)) return *why = "min_blur_sigma_px must be > 0", false;
  if (!(outlier_threshold > 1.0)) return *why = "outlier_threshold must be > 1", false;
  if (!(min_outlier_contrast >= 0.0)) return *why = "min_outlier_contrast must be >= 0", false;
  if (!(max_outlier_fraction >= 0.0 && max_outlier_fraction < 1.0))
    return *why = "max_outlier_fraction must be in [0, 1)", false;
  if (!(max_masked_fraction >= 0.0 && max_masked_fraction < 1.0))
    return *why = "max_masked_fraction must be in [0, 1)", false;
  if (!(max_corner_arm_px > 0.0)) return *why = "max_corner_arm_px must be > 0", false;
  if (max_iterations < 1) return *why = "max_iterations must be >= 1", false;
  return true;
}

PixelRect MarkFitWindow(const MarkFitStart& start, const MarkFitOptions& options) {
  double x_min, x_max, y_min, y_max;
  const double cx = start.centre_px.x_px, cy = start.centre_px.y_px;
  switch (start.type) {
    case MarkType::kCross:
      return CrossFitWindow(CrossStart(start), CrossOptions(options));
    case MarkType::kDot:
    case MarkType::kRing: {
      const double r = DiskSampleRadius(start, options);
      x_min = cx - r, x_max = cx + r, y_min = cy - r, y_max = cy + r;
      break;
    }
    case MarkType::kCorner:
    default: {
      const CornerReach reach = CornerReachOf(start, options);
      const double c = std::cos(start.rotation_rad), sn = std::sin(start.rotation_rad);
      const double chi = start.corner_handedness >= 0 ? 1.0 : -1.0;
      const double e1[2] = {c, sn}, e2[2] = {-chi * sn, chi * c};
      x_min = y_min = 1e300;
      x_max = y_max = -1e300;
      for (double a : {-reach.behind_px, reach.ahead_px})
        for (double b : {-reach.behind_px, reach.ahead_px}) {
          const double x = cx + a * e1[0] + b * e2[0], y = cy + a * e1[1] + b * e2[1];
          x_min = std::min(x_min, x), x_max = std::max(x_max, x);
          y_min = std::min(y_min, y), y_max = std::max(y_max, y);
        }
      break;
    }
  }
  const long x0 = static_cast<long>(std::floor(x_min)), y0 = static_cast<long>(std::floor(y_min));
  const long x1 = static_cast<long>(std::ceil(x_max)), y1 = static_cast<long>(std::ceil(y_max));
  return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

MarkFitResult FitMark(const ImageWindow& window, const MarkFitStart& start, const MarkFitOptions& options) {
  if (start.type == MarkType::kCross) return FromCross(FitCross(window, CrossStart(start), CrossOptions(options)));
  MarkFitResult result;
  result.type = start.type;
  const double cx = start.centre_px.x_px, cy = start.centre_px.y_px;
  std::vector<MarkSample> samples;
  internal::MarkEngineSettings settings;
  settings.outlier_threshold = options.outlier_threshold;
  settings.min_outlier_contrast = options.min_outlier_contrast;
  settings.max_iterations = options.max_iterations;
  const double w = start.line_width_px, size = start.size_px;
  const double blur0 = std::max(start.blur_sigma_px, options.min_blur_sigma_px);
  std::unique_ptr<internal::MarkShapeModel> model;

  auto add_pixels = [&](auto&& keep) {
    for (long row = window.rect.y0_px; row < window.rect.y_end_px(); ++row)
      for (long col = window.rect.x0_px; col < window.rect.x_end_px(); ++col) {
        if (!keep(col - cx, row - cy)) continue;
        const float value = window.at(col, row);
        if (std::isfinite(value)) {
          samples.push_back({static_cast<double>(col), static_cast<double>(row), static_cast<double>(value)});
        } else {
          ++result.pixels_masked;  // no value in the scan: left out
        }
      }
  };
  const double blur_cap = 2.0 * std::max(w, 0.15 * size) + 3.0;
  if (start.type == MarkType::kDot || start.type == MarkType::kRing) {
    const double radius = DiskSampleRadius(start, options);
    add_pixels([&](double dx, double dy) { return dx * dx + dy * dy <= radius * radius; });
    const double reach = DiskUncertaintyPx(start);
    settings.start = {cx, cy, size};
    settings.lower = {cx - reach, cy - reach, 0.5 * size};
    settings.upper = {cx + reach, cy + reach, 1.5 * size + 2.0};
    if (start.type == MarkType::kRing) {
      settings.start.push_back(w);
      settings.lower.push_back(0.2 * w);
      settings.upper.push_back(std::max(0.2 * w + 0.1, std::min(3.0 * w + 1.0, 0.5 * size)));
      model = std::make_unique<RingModel>();
    } else {
      model = std::make_unique<DotModel>();
    }
    settings.start.push_back(blur0);
    settings.lower.push_back(options.min_blur_sigma_px);
    settings.upper.push_back(std::max(blur0, blur_cap));
  } else {
    const CornerReach reach = CornerReachOf(start, options);
    const double c = std::cos(start.rotation_rad), sn = std::sin(start.rotation_rad);
    const double chi = start.corner_handedness >= 0 ? 1.0 : -1.0;
    add_pixels([&](double dx, double dy) {
      const double p = c * dx + sn * dy, q = chi * (-sn * dx + c * dy);
      const bool arm1 = std::abs(q) <= reach.band_px && p >= -reach.behind_px && p <= reach.ahead_px;
      const bool arm2 = std::abs(p) <= reach.band_px && q >= -reach.behind_px && q <= reach.ahead_px;
      return arm1 || arm2;
    });
    const double shift = CornerUncertaintyPx(start);
    // A generous blur widens the basin of the first (shape-held) pass, as in the cross fit.
    const double blur_start = std::max(blur0, 0.5 * w + 0.5);
    settings.start = {cx, cy, start.rotation_rad, w, w, blur_start};
    settings.lower = {cx - shift, cy - shift, start.rotation_rad - 0.1, 0.2 * w, 0.2 * w, options.min_blur_sigma_px};
    settings.upper = {cx + shift, cy + shift, start.rotation_rad + 0.1, 3.0 * w + 1.0, 3.0 * w + 1.0,
                      std::max(blur_start, blur_cap)};
    if (!options.fit_corner_rotation) {  // held at the start's (known) rotation
      settings.held = {2};
    }
    model = std::make_unique<CornerModel>(size, start.corner_handedness);
    if (options.quadratic_corner_background) settings.background_terms = 6;
  }

  const size_t region_px = samples.size() + static_cast<size_t>(result.pixels_masked);
  result.masked_fraction = region_px > 0 ? static_cast<double>(result.pixels_masked) / static_cast<double>(region_px) : 0.0;
  if (result.masked_fraction > options.max_masked_fraction) {
    result.too_many_masked = true;
    result.summary = std::to_string(result.pixels_masked) + " of the " + MarkTypeName(start.type) + "'s " +
                     std::to_string(region_px) + " px are masked (no value in the scan): too few left to fit it";
    return result;
  }
  const internal::MarkEngineResult fit = internal::RunMarkFit(*model, std::move(samples), settings);
  result.outlier_fraction = fit.outlier_fraction;
  if (!fit.converged) {
    result.summary = "the " + std::string(MarkTypeName(start.type)) + " fit did not converge (" + fit.message + ")";
    return result;
  }
  const std::vector<double>& p = fit.params;
  const int ns = model->num_shape() + 2;
  result.converged = true;
  result.centre_px = {p[0], p[1]};
  result.sigma_x_px = std::sqrt(std::max(fit.cov_xx, 0.0));
  result.sigma_y_px = std::sqrt(std::max(fit.cov_yy, 0.0));
  result.correlation_xy = fit.cov_xy / std::max(result.sigma_x_px * result.sigma_y_px, 1e-300);
  switch (start.type) {
    case MarkType::kDot:
      result.size_px = p[2];
      result.blur_sigma_px = p[3];
      break;
    case MarkType::kRing:
      result.size_px = p[2];
      result.line_width_px = p[3];
      result.blur_sigma_px = p[4];
      break;
    default:
      result.size_px = size;
      result.rotation_rad = p[2];
      result.line_width_px = p[3];
      result.line_width_2_px = p[4];
      result.blur_sigma_px = p[5];
      break;
  }
  result.gain_dn = p[ns];
  result.background_dn = p[ns + 1];
  result.residual_sigma_dn = fit.sigma0_dn;
  result.pixels_used = fit.pixels_used;
  std::ostringstream summary;
  summary << MarkTypeName(start.type) << " fitted on " << fit.pixels_used << " px ("
          << static_cast<int>(100.0 * fit.outlier_fraction + 0.5) << "% dropped as outliers";
  if (result.pixels_masked > 0) summary << ", " << result.pixels_masked << " masked left out";
  summary << "), residual sigma " << fit.sigma0_dn << " DN";
  result.summary = summary.str();
  return result;
}

}  // namespace platemeter
