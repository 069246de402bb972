#include "platemeter/samples/render_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "render_geometry.h"

namespace platemeter::sim {

using render_detail::GaussLegendre;
using render_detail::FastNormalCdf;
using render_detail::Point2;

bool RenderOptions::Check(std::string* why) const {
  auto fail = [why](const char* reason) {
    if (why) *why = reason;
    return false;
  };
  if (quadrature_nodes < 2 || quadrature_nodes > 32) return fail("quadrature_nodes must be in 2..32");
  if (!(max_cell_over_sigma > 0.0)) return fail("max_cell_over_sigma must be > 0");
  if (max_cells_per_axis < 1 || max_cells_per_axis > 64) return fail("max_cells_per_axis must be in 1..64");
  if (!(min_blur_sigma_px >= 0.0)) return fail("min_blur_sigma_px must be >= 0");
  if (!(tail_sigmas >= 6.0)) return fail("tail_sigmas must be >= 6");
  if (!(dust_edge_fraction > 0.0)) return fail("dust_edge_fraction must be > 0");
  return true;
}

namespace {

struct Bounds {  // continuous extent in px relative to the mark centre
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min;
  double y_min = x_min, y_max = -x_min;
  void Add(double x, double y) {
    x_min = std::min(x_min, x), x_max = std::max(x_max, x);
    y_min = std::min(y_min, y), y_max = std::max(y_max, y);
  }
};

// Quadrature nodes over one pixel: offsets (px) from the pixel centre and
// weights summing to 1, k x k sub-cells of n x n Gauss-Legendre nodes.
// The rule is the tensor product of a 1-D rule (axis, axis_w: k n offsets and
// weights summing to 1), which lets a Gaussian's exponential factor per axis.
struct PixelNodes {
  std::vector<double> dx, dy, w;
  std::vector<double> axis, axis_w;
  PixelNodes(int cells, int n) {
    const auto& rule = GaussLegendre(n);
    const double h = 1.0 / cells;
    for (int c = 0; c < cells; ++c)
      for (int i = 0; i < n; ++i) {
        axis.push_back(-0.5 + (c + 0.5) * h + 0.5 * h * rule.nodes[i]);
        axis_w.push_back(0.5 * h * rule.weights[i]);
      }
    // Exactly antisymmetric (the split form then needs half the exponentials).
    const size_t m = axis.size();
    for (size_t i = 0; i < m / 2; ++i) axis[m - 1 - i] = -axis[i], axis_w[m - 1 - i] = axis_w[i];
    if (m % 2 == 1) axis[m / 2] = 0.0;
    for (int cy = 0; cy < cells; ++cy)
      for (int cx = 0; cx < cells; ++cx)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            dx.push_back(-0.5 + (cx + 0.5) * h + 0.5 * h * rule.nodes[i]);
            dy.push_back(-0.5 + (cy + 0.5) * h + 0.5 * h * rule.nodes[j]);
            w.push_back(0.25 * h * h * rule.weights[i] * rule.weights[j]);
          }
  }
};

// The pixel rule for a Gaussian of sigma_px: k x k sub-cells of n x n nodes.
// The base rule (quadrature_nodes, cells <= max_cell_over_sigma sigma) and
// two higher-order ones with proportionally larger cells, (n + 2, 2 r) and
// (n + 4, 3 r), are about equally accurate (Gauss-Legendre converges faster
// with more nodes); the cheapest wins, which matters for sharp blurs.
// Rules are shared (a plate has tens of thousands of trail images, most with
// the same rule): built once per (cells, nodes), kept for the process.
std::shared_ptr<const PixelNodes> SharedNodes(int cells, int nodes) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::shared_ptr<const PixelNodes>> rules;
  std::lock_guard<std::mutex> lock(mutex);
  auto& rule = rules[{cells, nodes}];
  if (!rule) rule = std::make_shared<const PixelNodes>(cells, nodes);
  return rule;
}

std::shared_ptr<const PixelNodes> NodesFor(double sigma_px, const RenderOptions& options) {
  int best_cells = 0, best_nodes = 0;
  long best_cost = -1;
  for (int order = 0; order < 3; ++order) {
    const int nodes = options.quadrature_nodes + 2 * order;
    const double ratio = options.max_cell_over_sigma * (order + 1);
    const double cells_real = std::ceil(1.0 / (ratio * sigma_px) - 1e-9);
    const int cells = static_cast<int>(std::clamp(cells_real, 1.0, static_cast<double>(options.max_cells_per_axis)));
    const long cost = static_cast<long>(cells) * cells * nodes * nodes;
    if (best_cost < 0 || cost < best_cost) best_cost = cost, best_cells = cells, best_nodes = nodes;
  }
  return SharedNodes(best_cells, best_nodes);
}

// An axis-aligned rectangle [-half0, half0] x [-half1, half1] in its own frame
// q = M d - o, d the pixel offset from the mark centre (px), q in um.
struct RectPart {
  double m[4];
  double o[2];
  double half[2];
  double sigma[2];     // um along each rectangle axis; 0: no blur
  double reach[2];     // um: pixel half extent + tail
  double det_m = 1.0;  // um^2 per px^2
  double weight = 1.0;
  bool closed_form = true;  // use exact box averages where they apply
  bool separable = false;   // each rectangle axis depends on one pixel axis only
  std::vector<double> node_q0, node_q1, node_w;  // quadrature nodes in the rectangle frame

  double Value(double dx, double dy) const {
    const double q0 = m[0] * dx + m[1] * dy - o[0];
    const double q1 = m[2] * dx + m[3] * dy - o[1];
    const double a0 = std::abs(q0), a1 = std::abs(q1);
    if (a0 >= half[0] + reach[0] || a1 >= half[1] + reach[1]) return 0.0;
    const bool in0 = a0 <= half[0] - reach[0], in1 = a1 <= half[1] - reach[1];
    if (in0 && in1) return weight;
    if (sigma[0] == 0.0) {  // no blur: exact coverage of the pixel (a parallelogram here)
      std::array<Point2, 4> poly;
      const double corners[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
      for (int i = 0; i < 4; ++i) {
        const double x = dx + corners[i][0], y = dy + corners[i][1];
        poly[i] = {m[0] * x + m[1] * y - o[0], m[2] * x + m[3] * y - o[1]};
      }
      return weight * render_detail::ConvexPolygonBoxArea(poly, half[0], half[1]) / det_m;
    }
    // Over the pixel, q_i = q_i(centre) + m_i0 ox + m_i1 oy with ox, oy uniform
    // on [-1/2, 1/2]: when one factor is constant (1) or the two factors depend
    // on different pixel axes, the pixel mean is a product of exact box averages.
    if (closed_form) {
      if (in0) return weight * render_detail::BoxAveragedInterval(q1, half[1], sigma[1], m[2], m[3]);
      if (in1) return weight * render_detail::BoxAveragedInterval(q0, half[0], sigma[0], m[0], m[1]);
      if (separable)
        return weight * render_detail::BoxAveragedInterval(q0, half[0], sigma[0], m[0], m[1]) *
               render_detail::BoxAveragedInterval(q1, half[1], sigma[1], m[2], m[3]);
    }
    const render_detail::NormalCdfTable& cdf = render_detail::TheNormalCdfTable();
    const double inv0 = 1.0 / sigma[0], inv1 = 1.0 / sigma[1];
    double sum = 0.0;
    const size_t n = node_w.size();
    for (size_t k = 0; k < n; ++k) {
      const double u = q0 + node_q0[k], v = q1 + node_q1[k];
      const double f0 =
          in0 ? 1.0 : FastNormalCdf(cdf, (half[0] - u) * inv0) - FastNormalCdf(cdf, (-half[0] - u) * inv0);
      const double f1 =
          in1 ? 1.0 : FastNormalCdf(cdf, (half[1] - v) * inv1) - FastNormalCdf(cdf, (-half[1] - v) * inv1);
      sum += node_w[k] * f0 * f1;
    }
    return weight * sum;
  }
};

// A disk of radius `radius` (um) about the mark centre, u = M d.
struct DiskPart {
  double m[4];
  double radius = 0.0;
  double sigma = 0.0;  // um; 0: no blur
  double reach = 0.0;  // um: pixel half diagonal + tail
  double det_m = 1.0;
  double weight = 1.0;
  double r_lo = 0.0, r_hi = 0.0, step = 1.0;  // table of the blurred profile on [r_lo, r_hi]
  std::vector<double> f, df;
  std::vector<double> node_u, node_v, node_w;

  double Profile(double r) const {
    if (r <= r_lo) return r_lo > 0.0 ? 1.0 : f[0];
    if (r >= r_hi) return 0.0;
    const double s = (r - r_lo) / step;
    const size_t i = std::min(static_cast<size_t>(s), f.size() - 2);
    const double t = s - i, t2 = t * t, t3 = t2 * t;
    // Cubic Hermite with exact end derivatives: O(step^4) error.
    return (2 * t3 - 3 * t2 + 1) * f[i] + (t3 - 2 * t2 + t) * step * df[i] + (-2 * t3 + 3 * t2) * f[i + 1] +
           (t3 - t2) * step * df[i + 1];
  }

  double Value(double dx, double dy) const {
    const double u = m[0] * dx + m[1] * dy, v = m[2] * dx + m[3] * dy;
    const double r = std::hypot(u, v);
    if (r >= radius + reach) return 0.0;
    if (r <= radius - reach) return weight;
    if (sigma == 0.0) {
      std::array<Point2, 4> poly;
      const double corners[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
      for (int i = 0; i < 4; ++i) {
        const double x = dx + corners[i][0], y = dy + corners[i][1];
        poly[i] = {m[0] * x + m[1] * y, m[2] * x + m[3] * y};
      }
      return weight * render_detail::DiskPolygonArea(poly, radius) / det_m;
    }
    double sum = 0.0;
    for (size_t k = 0; k < node_w.size(); ++k) sum += node_w[k] * Profile(std::hypot(u + node_u[k], v + node_v[k]));
    return weight * sum;
  }
};

// A Gaussian PSF (covariance c in px^2, unit flux), optionally swept uniformly
// along the segment from -half_segment to +half_segment (px).
//
// Swept: with e the unit direction, f = (-e1, e0) across it, a = e^T P e, the
// density at d is norm sqrt(2 pi / a) / L exp(-kappa (f.d)^2 / 2)
// [Phi(sa (L/2 - g.d)) - Phi(sa (-L/2 - g.d))], kappa = det P / a, sa = sqrt a,
// g = e + (f^T P e / a) f (g.d: where along the segment the point projects in
// the PSF's metric). Over the tensor rule's nodes (X_i, Y_j) the across factor
// splits into exp(-kappa u_c f0 X_i) exp(-kappa u_c f1 Y_j) and a per-mark table
// of exp(-kappa (f0 X_i + f1 Y_j)^2 / 2) (u_c = f.d at the pixel centre), so a
// pixel costs k n exponentials (the axis is antisymmetric) instead of (k n)^2;
// the CDFs come from the Taylor table (FastNormalCdf). A point PSF splits the
// same way.
struct GaussPart {
  static constexpr size_t kMaxTensorNodes = 64;   // per axis; larger rules go node by node
  static constexpr double kMaxSplitExponent = 300.0;  // larger factors could overflow: node by node

  double c[3];  // xx, xy, yy
  double p[3];  // inverse covariance
  double norm = 0.0;
  bool diagonal = false;
  double sx = 0.0, sy = 0.0;
  double seg[2] = {0.0, 0.0};  // half segment (px)
  double e[2] = {1.0, 0.0};    // unit direction
  double length = 0.0;         // px
  double along_a = 0.0;        // e^T P e
  double reach_sq = 0.0;       // Mahalanobis^2 beyond which the value is 0
  double along_pixel_reach = 0.0;  // px: how far the along-segment parameter moves within a pixel
  bool isotropic = false;          // C = s^2 I
  bool closed_form = true;
  double tail = 8.5;
  std::shared_ptr<const PixelNodes> nodes;  // the pixel rule (node by node when the split form cannot serve)
  // Split form (see above).
  double f[2] = {0.0, 1.0};     // across unit vector
  double g[2] = {1.0, 0.0};     // t = g.d
  double kappa = 0.0;           // 1/px^2: det P / a
  double sa = 0.0;              // 1/px: sqrt(a)
  double swept_norm = 0.0;      // norm sqrt(2 pi / a) / L
  bool split = false;           // use the split form
  double split_reach = 0.0;     // px: max |f.n| (swept) or max |n_x| = max |n_y| (point) over the nodes
  std::vector<double> axis;       // 1-D node offsets (px)
  std::vector<double> axis_u[2];  // swept: f0 X_i, f1 Y_j
  std::vector<double> axis_t[2];  // swept: sa g0 X_i, sa g1 Y_j
  double t_min = 0.0, t_max = 0.0;  // extremes of axis_t[0]
  std::vector<double> pair_w;     // [j * m + i]: W_i W_j times the node-only exponential factor

  void PrepareSplit(const PixelNodes& nodes) {
    const size_t m = nodes.axis.size();
    if (m > kMaxTensorNodes) return;
    axis = nodes.axis;
    split_reach = 0.0;
    pair_w.resize(m * m);
    if (length > 0.0) {
      f[0] = -e[1], f[1] = e[0];
      const double det_p = p[0] * p[2] - p[1] * p[1];
      kappa = det_p / along_a;
      sa = std::sqrt(along_a);
      const double pfe = f[0] * (p[0] * e[0] + p[1] * e[1]) + f[1] * (p[1] * e[0] + p[2] * e[1]);
      g[0] = e[0] + pfe / along_a * f[0];
      g[1] = e[1] + pfe / along_a * f[1];
      swept_norm = norm * std::sqrt(2.0 * M_PI / along_a) / length;
      for (int k = 0; k < 2; ++k) {
        axis_u[k].resize(m);
        axis_t[k].resize(m);
        for (size_t i = 0; i < m; ++i) {
          axis_u[k][i] = f[k] * axis[i];
          axis_t[k][i] = sa * g[k] * axis[i];
        }
      }
      t_min = *std::min_element(axis_t[0].begin(), axis_t[0].end());
      t_max = *std::max_element(axis_t[0].begin(), axis_t[0].end());
      for (size_t j = 0; j < m; ++j)
        for (size_t i = 0; i < m; ++i) {
          const double u = axis_u[0][i] + axis_u[1][j];
          pair_w[j * m + i] = nodes.axis_w[i] * nodes.axis_w[j] * std::exp(-0.5 * kappa * u * u);
          split_reach = std::max(split_reach, std::abs(u));
        }
    } else {
      for (size_t j = 0; j < m; ++j)
        for (size_t i = 0; i < m; ++i) {
          const double x = axis[i], y = axis[j];
          const double q = p[0] * x * x + 2 * p[1] * x * y + p[2] * y * y;
          pair_w[j * m + i] = nodes.axis_w[i] * nodes.axis_w[j] * std::exp(-0.5 * q);
        }
      for (double x : axis) split_reach = std::max(split_reach, std::abs(x));
    }
    split = true;
  }

  double Density(double x, double y, const render_detail::NormalCdfTable& cdf) const {
    const double q = p[0] * x * x + 2 * p[1] * x * y + p[2] * y * y;
    if (length == 0.0) return norm * std::exp(-0.5 * q);
    const double b = e[0] * (p[0] * x + p[1] * y) + e[1] * (p[1] * x + p[2] * y);
    const double across = q - b * b / along_a;
    const double sa_local = std::sqrt(along_a);
    const double t0 = b / along_a;
    return norm * std::exp(-0.5 * across) * std::sqrt(2.0 * M_PI / along_a) / length *
           (FastNormalCdf(cdf, sa_local * (0.5 * length - t0)) - FastNormalCdf(cdf, sa_local * (-0.5 * length - t0)));
  }

  // One row of nodes: sum over i of w_i ex_i [Phi(hi - tx_i) - Phi(lo - tx_i)].
  // Where a whole row lies beyond the table (Phi 1 at the far end, 0 before the
  // near one) that CDF is skipped: pixels off a trail's ends often need one.
  double SweptRow(const render_detail::NormalCdfTable& cdf, const double* w, const double* ex, double hi,
                  double lo) const {
    const size_t m = axis.size();
    const double* tx = axis_t[0].data();
    constexpr double kLimit = render_detail::NormalCdfTable::kLimit;
    const bool hi_is_one = hi - t_max >= kLimit, lo_is_zero = lo - t_min <= -kLimit;
    double row = 0.0;
    if (hi_is_one && lo_is_zero) {
      for (size_t i = 0; i < m; ++i) row += w[i] * ex[i];
    } else if (hi_is_one) {
      for (size_t i = 0; i < m; ++i) row += w[i] * ex[i] * (1.0 - FastNormalCdf(cdf, lo - tx[i]));
    } else if (lo_is_zero) {
      for (size_t i = 0; i < m; ++i) row += w[i] * ex[i] * FastNormalCdf(cdf, hi - tx[i]);
    } else {
      for (size_t i = 0; i < m; ++i)
        row += w[i] * ex[i] * (FastNormalCdf(cdf, hi - tx[i]) - FastNormalCdf(cdf, lo - tx[i]));
    }
    return row;
  }

  // The per-pixel factors of the split swept form at d: the CDF arguments at the
  // node grid's origin, the across factors per axis, and the pixel's scale.
  struct SweptPixel {
    double hi = 0.0, lo = 0.0;  // sa (+-L/2 - g.d)
    double scale = 0.0;         // swept_norm exp(-kappa u_c^2 / 2)
    double ex[kMaxTensorNodes], ey[kMaxTensorNodes];
  };

  // False when a factor could overflow (a Gaussian much narrower than the pixel).
  bool PrepareSwept(double dx, double dy, SweptPixel* pixel) const {
    const size_t m = axis.size();
    const double u_c = f[0] * dx + f[1] * dy;
    const double slope = kappa * u_c;
    const double half_exponent = 0.5 * slope * u_c;
    if (half_exponent + std::abs(slope) * split_reach > kMaxSplitExponent) return false;
    // The axis is antisymmetric: exp(-s a_(m-1-i)) = 1 / exp(-s a_i).
    for (size_t i = 0; i < (m + 1) / 2; ++i) {
      pixel->ex[i] = std::exp(-slope * axis_u[0][i]);
      pixel->ey[i] = std::exp(-slope * axis_u[1][i]);
    }
    for (size_t i = (m + 1) / 2; i < m; ++i) {
      pixel->ex[i] = 1.0 / pixel->ex[m - 1 - i];
      pixel->ey[i] = 1.0 / pixel->ey[m - 1 - i];
    }
    const double t_c = g[0] * dx + g[1] * dy;
    pixel->hi = sa * (0.5 * length - t_c);
    pixel->lo = sa * (-0.5 * length - t_c);
    pixel->scale = swept_norm * std::exp(-half_exponent);
    return true;
  }

  // The pixel mean by the split form; false when a factor could overflow.
  bool SplitValue(double dx, double dy, const render_detail::NormalCdfTable& cdf, double* value) const {
    const size_t m = axis.size();
    if (length > 0.0) {
      SweptPixel pixel;
      if (!PrepareSwept(dx, dy, &pixel)) return false;
      double sum = 0.0;
      for (size_t j = 0; j < m; ++j)
        sum += pixel.ey[j] *
               SweptRow(cdf, pair_w.data() + j * m, pixel.ex, pixel.hi - axis_t[1][j], pixel.lo - axis_t[1][j]);
      *value = pixel.scale * sum;
      return true;
    }
    double ex[kMaxTensorNodes], ey[kMaxTensorNodes];
    const double r0 = p[0] * dx + p[1] * dy, r1 = p[1] * dx + p[2] * dy;  // P d
    const double half_exponent = 0.5 * (dx * r0 + dy * r1);
    if (half_exponent + (std::abs(r0) + std::abs(r1)) * split_reach > kMaxSplitExponent) return false;
    for (size_t i = 0; i < m; ++i) {
      ex[i] = std::exp(-r0 * axis[i]);
      ey[i] = std::exp(-r1 * axis[i]);
    }
    double sum = 0.0;
    for (size_t j = 0; j < m; ++j) {
      const double* w = pair_w.data() + j * m;
      double row = 0.0;
      for (size_t i = 0; i < m; ++i) row += w[i] * ex[i];
      sum += ey[j] * row;
    }
    *value = norm * std::exp(-half_exponent) * sum;
    return true;
  }

  // The value where no quadrature is needed: a diagonal point PSF (closed form),
  // an isotropic trail's middle (closed form), or beyond the reach (0).
  bool Shortcut(double dx, double dy, const render_detail::NormalCdfTable& cdf, double* value) const {
    if (length == 0.0 && diagonal) {  // exact: product of erf differences
      if (std::abs(dx) >= tail * sx + 0.5 || std::abs(dy) >= tail * sy + 0.5) {
        *value = 0.0;
      } else {
        *value = (FastNormalCdf(cdf, (dx + 0.5) / sx) - FastNormalCdf(cdf, (dx - 0.5) / sx)) *
                 (FastNormalCdf(cdf, (dy + 0.5) / sy) - FastNormalCdf(cdf, (dy - 0.5) / sy));
      }
      return true;
    }
    // Isotropic PSF away from the segment's ends: Gaussian across times 1 along,
    // the pixel mean in closed form.
    if (length > 0.0 && isotropic && closed_form) {
      const double along = e[0] * dx + e[1] * dy;
      if (std::abs(along) + 0.5 * (std::abs(e[0]) + std::abs(e[1])) + tail * sx <= 0.5 * length) {
        const double across = -e[1] * dx + e[0] * dy;
        *value = render_detail::BoxAveragedDensity(across, sx, -e[1], e[0]) / length;
        return true;
      }
    }
    // Mahalanobis distance of the pixel centre to the segment's line.
    const double q = p[0] * dx * dx + 2 * p[1] * dx * dy + p[2] * dy * dy;
    double across = q;
    *value = 0.0;
    if (length > 0.0) {
      const double b = e[0] * (p[0] * dx + p[1] * dy) + e[1] * (p[1] * dx + p[2] * dy);
      across = q - b * b / along_a;
      // Beyond the segment's ends by more than the tail (over the whole pixel): nothing.
      if (std::sqrt(along_a) * (std::abs(b / along_a) - 0.5 * length - along_pixel_reach) >= tail) return true;
    }
    return across >= reach_sq;
  }

  double Quadrature(double dx, double dy, const render_detail::NormalCdfTable& cdf) const {
    double value;
    if (split && SplitValue(dx, dy, cdf, &value)) return value;
    double sum = 0.0;
    const PixelNodes& rule = *nodes;
    for (size_t k = 0; k < rule.w.size(); ++k) sum += rule.w[k] * Density(dx + rule.dx[k], dy + rule.dy[k], cdf);
    return sum;
  }

  double Value(double dx, double dy) const {
    const render_detail::NormalCdfTable& cdf = render_detail::TheNormalCdfTable();
    double value;
    if (Shortcut(dx, dy, cdf, &value)) return value;
    return Quadrature(dx, dy, cdf);
  }

  // Adds Value(dx[k], dy[k]) to out[k] for count <= kLanes pixel offsets, each
  // within shift_px of the first along x or y (the Cramer-Rao bound's centre
  // and its four shifts). Swept marks evaluate them together (SweptLanes).
  void AddValues(const double* dx, const double* dy, int count, double shift_px, double* out) const {
    const render_detail::NormalCdfTable& cdf = render_detail::TheNormalCdfTable();
    if (count > kLanes) {
      for (int k = 0; k < count; ++k) out[k] += Value(dx[k], dy[k]);
      return;
    }
    int pending[kLanes], n_pending = 0;
    for (int k = 0; k < count; ++k) {
      double value;
      if (Shortcut(dx[k], dy[k], cdf, &value)) out[k] += value;
      else pending[n_pending++] = k;
    }
    // A node's CDF arguments span at most 2 sa |g| shift_px over the offsets:
    // at most one table interval, so the interval of their midpoint serves all.
    const double max_arg_shift = sa * std::max(std::abs(g[0]), std::abs(g[1])) * shift_px;
    const bool together = split && length > 0.0 && n_pending > 1 &&
                          max_arg_shift <= 0.5 / render_detail::NormalCdfTable::kPerUnit;
    if (!together) {
      for (int r = 0; r < n_pending; ++r) out[pending[r]] += Quadrature(dx[pending[r]], dy[pending[r]], cdf);
      return;
    }
    SweptLanes lanes;
    int ready[kLanes], n_ready = 0;
    for (int r = 0; r < n_pending; ++r) {
      const int k = pending[r];
      SweptPixel pixel;
      if (PrepareSwept(dx[k], dy[k], &pixel)) lanes.Set(n_ready, pixel, axis.size()), ready[n_ready++] = k;
      else out[k] += Quadrature(dx[k], dy[k], cdf);
    }
    if (n_ready == 0) return;
    for (int r = n_ready; r < kLanes; ++r) lanes.Copy(r, 0, axis.size());  // idle lanes repeat the first
    Vec2 sums[kVectors];
    SweptLanesSum(cdf, lanes, sums);
    for (int r = 0; r < n_ready; ++r) out[ready[r]] += lanes.scale[r] * sums[r / 2][r % 2];
  }

  // Several pixels of the split swept form side by side, two per SIMD vector
  // (GCC/Clang vector extension: SSE2 on x86-64, NEON on arm64, scalar elsewhere).
  using Vec2 = double __attribute__((vector_size(16)));
  static constexpr int kVectors = 3, kLanes = 2 * kVectors;
  struct SweptLanes {
    double scale[kLanes];
    Vec2 hi[kVectors], lo[kVectors];
    Vec2 ex[kMaxTensorNodes][kVectors], ey[kMaxTensorNodes][kVectors];
    void Set(int r, const SweptPixel& pixel, size_t m) {
      scale[r] = pixel.scale;
      hi[r / 2][r % 2] = pixel.hi, lo[r / 2][r % 2] = pixel.lo;
      for (size_t i = 0; i < m; ++i) ex[i][r / 2][r % 2] = pixel.ex[i], ey[i][r / 2][r % 2] = pixel.ey[i];
    }
    void Copy(int r, int from, size_t m) {
      scale[r] = scale[from];
      hi[r / 2][r % 2] = hi[from / 2][from % 2], lo[r / 2][r % 2] = lo[from / 2][from % 2];
      for (size_t i = 0; i < m; ++i) {
        ex[i][r / 2][r % 2] = ex[i][from / 2][from % 2];
        ey[i][r / 2][r % 2] = ey[i][from / 2][from % 2];
      }
    }
  };

  // Phi(z[v]) for the lanes, from the table interval of base; the lanes lie
  // within half an interval of base (a polynomial holds to 3e-16 up to twice
  // its half width from its centre). Beyond the table's ends all are 0 or 1.
  static void CdfLanes(const render_detail::NormalCdfTable& cdf, double base, const Vec2* z, Vec2* phi) {
    using Table = render_detail::NormalCdfTable;
    constexpr double kEdge = Table::kLimit + 0.5 / Table::kPerUnit;
    if (base >= kEdge || base <= -kEdge) {
      const double value = base > 0.0 ? 1.0 : 0.0;
      for (int v = 0; v < kVectors; ++v) phi[v] = Vec2{value, value};
      return;
    }
    const double clamped = std::max(-Table::kLimit, std::min(base, Table::kLimit));
    const int i = std::min(static_cast<int>((clamped + Table::kLimit) * Table::kPerUnit), Table::kIntervals - 1);
    const double centre = (i + 0.5) * (1.0 / Table::kPerUnit) - Table::kLimit;
    const double* c = cdf.coefficients[i];
    for (int v = 0; v < kVectors; ++v) {
      const Vec2 t = z[v] - centre, t2 = t * t, t4 = t2 * t2;
      phi[v] = ((c[0] + t * c[1]) + t2 * (c[2] + t * c[3])) + t4 * ((c[4] + t * c[5]) + t2 * (c[6] + t * c[7]));
    }
  }

  // sums = the node sums of the split form for every lane.
  void SweptLanesSum(const render_detail::NormalCdfTable& cdf, const SweptLanes& lanes, Vec2* sums) const {
    const size_t m = axis.size();
    const double* tx = axis_t[0].data();
    // Midpoints of the lanes' arguments (the table interval is found from them).
    double hi_min = lanes.hi[0][0], hi_max = hi_min, lo_min = lanes.lo[0][0], lo_max = lo_min;
    for (int r = 1; r < kLanes; ++r) {
      hi_min = std::min(hi_min, lanes.hi[r / 2][r % 2]), hi_max = std::max(hi_max, lanes.hi[r / 2][r % 2]);
      lo_min = std::min(lo_min, lanes.lo[r / 2][r % 2]), lo_max = std::max(lo_max, lanes.lo[r / 2][r % 2]);
    }
    const double hi_mid = 0.5 * (hi_min + hi_max), lo_mid = 0.5 * (lo_min + lo_max);
    for (int v = 0; v < kVectors; ++v) sums[v] = Vec2{0.0, 0.0};
    for (size_t j = 0; j < m; ++j) {
      const double* w = pair_w.data() + j * m;
      const double ty = axis_t[1][j];
      Vec2 rows[kVectors] = {};
      for (size_t i = 0; i < m; ++i) {
        const double shift = ty + tx[i];
        Vec2 z_hi[kVectors], z_lo[kVectors], phi_hi[kVectors], phi_lo[kVectors];
        for (int v = 0; v < kVectors; ++v) z_hi[v] = (lanes.hi[v] - ty) - tx[i], z_lo[v] = (lanes.lo[v] - ty) - tx[i];
        CdfLanes(cdf, hi_mid - shift, z_hi, phi_hi);
        CdfLanes(cdf, lo_mid - shift, z_lo, phi_lo);
        for (int v = 0; v < kVectors; ++v) rows[v] += w[i] * lanes.ex[i][v] * (phi_hi[v] - phi_lo[v]);
      }
      for (int v = 0; v < kVectors; ++v) sums[v] += lanes.ey[j][v] * rows[v];
    }
  }
};

}  // namespace

struct MarkModel::Impl {
  SceneMark mark;
  double scale = 1.0;  // DN: amplitude (contrast) or flux
  std::vector<RectPart> rects;
  std::vector<DiskPart> disks;
  std::vector<GaussPart> gausses;
  Bounds bounds;

  double Value(double dx, double dy) const {
    double sum = 0.0;
    for (const auto& part : rects) sum += part.Value(dx, dy);
    for (const auto& part : disks) sum += part.Value(dx, dy);
    for (const auto& part : gausses) sum += part.Value(dx, dy);
    return scale * sum;
  }

  // Value at five offsets within shift_px of each other, in the same order of parts.
  void Values5(const double dx[5], const double dy[5], double shift_px, double out[5]) const {
    for (int k = 0; k < 5; ++k) out[k] = 0.0;
    for (const auto& part : rects)
      for (int k = 0; k < 5; ++k) out[k] += part.Value(dx[k], dy[k]);
    for (const auto& part : disks)
      for (int k = 0; k < 5; ++k) out[k] += part.Value(dx[k], dy[k]);
    for (const auto& part : gausses) part.AddValues(dx, dy, 5, shift_px, out);
    for (int k = 0; k < 5; ++k) out[k] *= scale;
  }
};

namespace {

struct Frame {
  double a[4];      // px_from_um
  double inv[4];    // um_from_px
  double det = 1.0; // |det a|: px^2 per um^2
};

Frame MakeFrame(const SceneMark& mark) {
  Frame frame;
  std::copy(mark.px_from_um, mark.px_from_um + 4, frame.a);
  const double det = frame.a[0] * frame.a[3] - frame.a[1] * frame.a[2];
  if (!std::isfinite(det) || std::abs(det) < 1e-12)
    throw Error("scene mark " + mark.id, "px_from_um is singular or not finite");
  frame.inv[0] = frame.a[3] / det;
  frame.inv[1] = -frame.a[1] / det;
  frame.inv[2] = -frame.a[2] / det;
  frame.inv[3] = frame.a[0] / det;
  frame.det = std::abs(det);
  return frame;
}

// Adds a rectangle centred at (cu, cv) um in the mark frame, first axis at
// angle_rad from u toward v, half sizes (h0, h1) um.
void AddRect(MarkModel::Impl* impl, const Frame& frame, double cu, double cv, double angle_rad, double h0,
             double h1, double weight, double blur_px, const RenderOptions& options) {
  if (h0 <= 0.0 || h1 <= 0.0) return;
  RectPart part;
  const double cs = std::cos(angle_rad), sn = std::sin(angle_rad);
  // M = R^T um_from_px, R = [[cs, -sn], [sn, cs]].
  part.m[0] = cs * frame.inv[0] + sn * frame.inv[2];
  part.m[1] = cs * frame.inv[1] + sn * frame.inv[3];
  part.m[2] = -sn * frame.inv[0] + cs * frame.inv[2];
  part.m[3] = -sn * frame.inv[1] + cs * frame.inv[3];
  part.o[0] = cs * cu + sn * cv;
  part.o[1] = -sn * cu + cs * cv;
  part.half[0] = h0;
  part.half[1] = h1;
  part.det_m = 1.0 / frame.det;
  part.weight = weight;
  const double tail = options.tail_sigmas;
  for (int i = 0; i < 2; ++i) {
    const double row_norm = std::hypot(part.m[2 * i], part.m[2 * i + 1]);
    part.sigma[i] = blur_px * row_norm;  // blur covariance in the rectangle frame: s^2 M M^T (diagonal kept)
    part.reach[i] = 0.5 * (std::abs(part.m[2 * i]) + std::abs(part.m[2 * i + 1])) + tail * part.sigma[i];
  }
  part.closed_form = options.closed_form;
  const double tiny = 1e-14 * (std::abs(part.m[0]) + std::abs(part.m[1]) + std::abs(part.m[2]) + std::abs(part.m[3]));
  part.separable = (std::abs(part.m[1]) <= tiny && std::abs(part.m[2]) <= tiny) ||
                   (std::abs(part.m[0]) <= tiny && std::abs(part.m[3]) <= tiny);
  if (blur_px > 0.0) {
    const PixelNodes& nodes = *NodesFor(blur_px, options);
    for (size_t k = 0; k < nodes.w.size(); ++k) {
      part.node_q0.push_back(part.m[0] * nodes.dx[k] + part.m[1] * nodes.dy[k]);
      part.node_q1.push_back(part.m[2] * nodes.dx[k] + part.m[3] * nodes.dy[k]);
    }
    part.node_w = nodes.w;
  }
  // Extent in px: the rectangle grown by the tail, mapped back (d = M^-1 (q + o)).
  const double det_m = part.m[0] * part.m[3] - part.m[1] * part.m[2];
  const double mi[4] = {part.m[3] / det_m, -part.m[1] / det_m, -part.m[2] / det_m, part.m[0] / det_m};
  const double e0 = h0 + tail * part.sigma[0], e1 = h1 + tail * part.sigma[1];
  for (double s0 : {-1.0, 1.0})
    for (double s1 : {-1.0, 1.0}) {
      const double q0 = s0 * e0 + part.o[0], q1 = s1 * e1 + part.o[1];
      impl->bounds.Add(mi[0] * q0 + mi[1] * q1, mi[2] * q0 + mi[3] * q1);
    }
  impl->rects.push_back(std::move(part));
}

void AddDisk(MarkModel::Impl* impl, const Frame& frame, double radius_um, double edge_sigma_um, double weight,
             double blur_px, const RenderOptions& options) {
  if (radius_um <= 0.0) return;
  DiskPart part;
  std::copy(frame.inv, frame.inv + 4, part.m);
  part.radius = radius_um;
  part.det_m = 1.0 / frame.det;
  part.weight = weight;
  // um per px, averaged over directions (exact for a rotation and scale).
  const double um_per_px = std::sqrt(0.5 * (frame.inv[0] * frame.inv[0] + frame.inv[1] * frame.inv[1] +
                                            frame.inv[2] * frame.inv[2] + frame.inv[3] * frame.inv[3]));
  part.sigma = std::hypot(blur_px * um_per_px, edge_sigma_um);
  const double half_diagonal =
      0.5 * std::max(std::hypot(part.m[0] + part.m[1], part.m[2] + part.m[3]),
                     std::hypot(part.m[0] - part.m[1], part.m[2] - part.m[3]));
  const double tail = options.tail_sigmas;
  part.reach = half_diagonal + tail * part.sigma;
  if (part.sigma > 0.0) {
    part.r_lo = std::max(0.0, radius_um - tail * part.sigma);
    part.r_hi = radius_um + tail * part.sigma;
    const int count = static_cast<int>(std::ceil((part.r_hi - part.r_lo) / (part.sigma / 24.0))) + 1;
    part.step = (part.r_hi - part.r_lo) / (count - 1);
    part.f.resize(count);
    part.df.resize(count);
    for (int i = 0; i < count; ++i)
      render_detail::BlurredDisk(part.r_lo + i * part.step, radius_um, part.sigma, &part.f[i], &part.df[i]);
    const double sigma_px = part.sigma / um_per_px;
    const PixelNodes& nodes = *NodesFor(sigma_px, options);
    for (size_t k = 0; k < nodes.w.size(); ++k) {
      part.node_u.push_back(part.m[0] * nodes.dx[k] + part.m[1] * nodes.dy[k]);
      part.node_v.push_back(part.m[2] * nodes.dx[k] + part.m[3] * nodes.dy[k]);
    }
    part.node_w = nodes.w;
  }
  const double extent = radius_um + tail * part.sigma;
  const double ex = extent * std::hypot(frame.a[0], frame.a[1]);
  const double ey = extent * std::hypot(frame.a[2], frame.a[3]);
  impl->bounds.Add(-ex, -ey);
  impl->bounds.Add(ex, ey);
  impl->disks.push_back(std::move(part));
}

void AddGauss(MarkModel::Impl* impl, const Frame& frame, const SceneMark& mark, double blur_px,
              const RenderOptions& options) {
  if (!(mark.psf_fwhm_um >= 0.0)) throw Error("scene mark " + mark.id, "psf_fwhm_um must be >= 0");
  const double s_um = mark.psf_fwhm_um / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  GaussPart part;
  const double* a = frame.a;
  // C = s^2 A A^T + blur^2 I.
  part.c[0] = s_um * s_um * (a[0] * a[0] + a[1] * a[1]) + blur_px * blur_px;
  part.c[1] = s_um * s_um * (a[0] * a[2] + a[1] * a[3]);
  part.c[2] = s_um * s_um * (a[2] * a[2] + a[3] * a[3]) + blur_px * blur_px;
  const double det = part.c[0] * part.c[2] - part.c[1] * part.c[1];
  if (!(det > 1e-12))
    throw Error("scene mark " + mark.id, "a point image needs psf_fwhm_um > 0 or a scanner blur");
  part.p[0] = part.c[2] / det;
  part.p[1] = -part.c[1] / det;
  part.p[2] = part.c[0] / det;
  part.norm = 1.0 / (2.0 * M_PI * std::sqrt(det));
  part.sx = std::sqrt(part.c[0]);
  part.sy = std::sqrt(part.c[2]);
  part.diagonal = std::abs(part.c[1]) <= 1e-12 * (part.c[0] + part.c[2]);
  part.isotropic = part.diagonal && std::abs(part.c[0] - part.c[2]) <= 1e-12 * (part.c[0] + part.c[2]);
  part.closed_form = options.closed_form;
  part.tail = options.tail_sigmas;
  if (mark.shape == MarkShapeKind::kSegment) {
    part.seg[0] = 0.5 * (a[0] * mark.segment_u_um + a[1] * mark.segment_v_um);
    part.seg[1] = 0.5 * (a[2] * mark.segment_u_um + a[3] * mark.segment_v_um);
    const double length = 2.0 * std::hypot(part.seg[0], part.seg[1]);
    if (length > 1e-9) {
      part.length = length;
      part.e[0] = 2.0 * part.seg[0] / length;
      part.e[1] = 2.0 * part.seg[1] / length;
      part.along_a = part.e[0] * (part.p[0] * part.e[0] + part.p[1] * part.e[1]) +
                     part.e[1] * (part.p[1] * part.e[0] + part.p[2] * part.e[1]);
      // t = e^T P d / a moves by |P e| / a per px of d; a pixel's half diagonal is sqrt(1/2) px.
      part.along_pixel_reach = std::sqrt(0.5) *
                               std::hypot(part.p[0] * part.e[0] + part.p[1] * part.e[1],
                                          part.p[1] * part.e[0] + part.p[2] * part.e[1]) / part.along_a;
    }
  }
  const double lambda_min = 0.5 * (part.c[0] + part.c[2]) - std::sqrt(0.25 * (part.c[0] - part.c[2]) * (part.c[0] - part.c[2]) + part.c[1] * part.c[1]);
  // Mahalanobis reach: tail sigmas plus a pixel's half diagonal.
  const double reach = options.tail_sigmas + std::sqrt(0.5) / std::sqrt(lambda_min);
  part.reach_sq = reach * reach;
  if (!(part.length == 0.0 && part.diagonal)) {
    part.nodes = NodesFor(std::sqrt(lambda_min), options);
    part.PrepareSplit(*part.nodes);
  }
  const double ex = options.tail_sigmas * part.sx + std::abs(part.seg[0]);
  const double ey = options.tail_sigmas * part.sy + std::abs(part.seg[1]);
  impl->bounds.Add(-ex, -ey);
  impl->bounds.Add(ex, ey);
  impl->gausses.push_back(std::move(part));
}

uint64_t NextRandom(uint64_t* state) {
  *state += 0x9E3779B97F4A7C15ull;
  return render_detail::Mix64(*state);
}
double UniformFrom(uint64_t* state) { return (NextRandom(state) >> 11) * (1.0 / 9007199254740992.0); }

void AddCross(MarkModel::Impl* impl, const Frame& frame, const SceneMark& mark, double blur_px,
              const RenderOptions& options) {
  const double half_length = 0.5 * mark.size_um, half_width = 0.5 * mark.line_width_um;
  if (!(half_length > half_width && half_width > 0.0))
    throw Error("scene mark " + mark.id, "a cross needs size_um > line_width_um > 0");
  if (!(mark.damage_fraction >= 0.0 && mark.damage_fraction <= 1.0))
    throw Error("scene mark " + mark.id, "damage_fraction must be in [0, 1]");
  if (mark.damage_fraction == 0.0) {
    AddRect(impl, frame, 0, 0, 0, half_length, half_width, 1.0, blur_px, options);
    AddRect(impl, frame, 0, 0, 0, half_width, half_length, 1.0, blur_px, options);
    AddRect(impl, frame, 0, 0, 0, half_width, half_width, -1.0, blur_px, options);
    return;
  }
  // Damaged: the centre square stays; each arm (length L outside the square)
  // loses one gap; the gaps share damage_fraction * 4L by random weights.
  AddRect(impl, frame, 0, 0, 0, half_width, half_width, 1.0, blur_px, options);
  const double arm = half_length - half_width;
  uint64_t state = mark.seed ^ 0xD1B54A32D192ED03ull;
  double weights[4], total = 0.0;
  for (double& w : weights) total += (w = 0.2 + UniformFrom(&state));
  double removed[4];
  double left = mark.damage_fraction * 4.0 * arm;
  for (int i = 0; i < 4; ++i) removed[i] = std::min(arm, left * weights[i] / total);
  double assigned = removed[0] + removed[1] + removed[2] + removed[3];
  for (int pass = 0; pass < 4 && left - assigned > 1e-12 * arm; ++pass)  // give the excess to arms with room
    for (int i = 0; i < 4; ++i) {
      const double add = std::min(arm - removed[i], left - assigned);
      removed[i] += add;
      assigned += add;
    }
  for (int i = 0; i < 4; ++i) {
    const double gap_start = half_width + UniformFrom(&state) * (arm - removed[i]);  // distance from centre
    const double gap_end = gap_start + removed[i];
    const double angle = i * 0.5 * M_PI;  // +u, +v, -u, -v
    const double pieces[2][2] = {{half_width, gap_start}, {gap_end, half_length}};
    for (const auto& piece : pieces) {
      const double len = piece[1] - piece[0];
      if (len <= 1e-9) continue;
      const double mid = 0.5 * (piece[0] + piece[1]);
      AddRect(impl, frame, mid * std::cos(angle), mid * std::sin(angle), angle, 0.5 * len, half_width, 1.0, blur_px,
              options);
    }
  }
}

}  // namespace

MarkModel::MarkModel(const SceneMark& mark, double scanner_blur_sigma_px, const RenderOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("render options", why);
  if (!(scanner_blur_sigma_px >= 0.0)) throw Error("scene noise", "scanner_blur_sigma_px must be >= 0");
  auto impl = std::make_shared<Impl>();
  impl->mark = mark;
  impl->scale = mark.amplitude_dn;
  const Frame frame = MakeFrame(mark);
  const double blur_px = scanner_blur_sigma_px < options.min_blur_sigma_px ? 0.0 : scanner_blur_sigma_px;
  if (!std::isfinite(mark.amplitude_dn)) throw Error("scene mark " + mark.id, "amplitude_dn is not finite");

  if (mark.kind == MarkKind::kDust) {
    if (!(mark.size_um > 0.0)) throw Error("scene mark " + mark.id, "dust needs size_um > 0");
    AddDisk(impl.get(), frame, 0.5 * mark.size_um, options.dust_edge_fraction * mark.size_um, 1.0, blur_px, options);
  } else if (mark.kind == MarkKind::kScratch) {
    if (!(mark.size_um > 0.0 && mark.line_width_um > 0.0))
      throw Error("scene mark " + mark.id, "a scratch needs size_um > 0 and line_width_um > 0");
    AddRect(impl.get(), frame, 0, 0, mark.corner_angle_rad, 0.5 * mark.size_um, 0.5 * mark.line_width_um, 1.0,
            blur_px, options);
  } else {
    switch (mark.shape) {
      case MarkShapeKind::kCross:
        AddCross(impl.get(), frame, mark, blur_px, options);
        break;
      case MarkShapeKind::kDot:
        if (!(mark.size_um > 0.0)) throw Error("scene mark " + mark.id, "a dot needs size_um > 0");
        AddDisk(impl.get(), frame, 0.5 * mark.size_um, 0.0, 1.0, blur_px, options);
        break;
      case MarkShapeKind::kRing: {
        const double outer = 0.5 * mark.size_um, inner = outer - mark.line_width_um;
        if (!(outer > 0.0 && mark.line_width_um > 0.0))
          throw Error("scene mark " + mark.id, "a ring needs size_um > 0 and line_width_um > 0");
        AddDisk(impl.get(), frame, outer, 0.0, 1.0, blur_px, options);
        if (inner > 0.0) AddDisk(impl.get(), frame, inner, 0.0, -1.0, blur_px, options);
        break;
      }
      case MarkShapeKind::kCorner: {
        const double w = mark.line_width_um, len = mark.size_um;
        if (!(len > w && w > 0.0)) throw Error("scene mark " + mark.id, "a corner needs size_um > line_width_um > 0");
        const double a1 = mark.corner_angle_rad - 0.25 * M_PI, a2 = mark.corner_angle_rad + 0.25 * M_PI;
        const double mid = 0.5 * (len - 0.5 * w), half = 0.5 * (len + 0.5 * w);
        AddRect(impl.get(), frame, mid * std::cos(a1), mid * std::sin(a1), a1, half, 0.5 * w, 1.0, blur_px, options);
        AddRect(impl.get(), frame, mid * std::cos(a2), mid * std::sin(a2), a2, half, 0.5 * w, 1.0, blur_px, options);
        AddRect(impl.get(), frame, 0, 0, a1, 0.5 * w, 0.5 * w, -1.0, blur_px, options);
        break;
      }
      case MarkShapeKind::kPsf:
      case MarkShapeKind::kSegment:
        AddGauss(impl.get(), frame, mark, blur_px, options);
        break;
    }
  }
  centre_px_ = mark.centre_px;
  const Bounds& b = impl->bounds;
  if (!std::isfinite(b.x_min)) throw Error("scene mark " + mark.id, "the mark has no extent");
  // One pixel of slack so small centre shifts (derivatives, fits) stay inside.
  support_.x0_px = PixelIndexOf(centre_px_.x_px + b.x_min) - 1;
  support_.y0_px = PixelIndexOf(centre_px_.y_px + b.y_min) - 1;
  support_.width_px = PixelIndexOf(centre_px_.x_px + b.x_max) + 2 - support_.x0_px;
  support_.height_px = PixelIndexOf(centre_px_.y_px + b.y_max) + 2 - support_.y0_px;
  impl_ = std::move(impl);
}

const SceneMark& MarkModel::mark() const { return impl_->mark; }

void MarkModel::PixelValuesShifted(double step_px, long x_px, long y_px, double values[5]) const {
  const PixelPoint c = centre_px_;
  const double x = static_cast<double>(x_px), y = static_cast<double>(y_px);
  // The offsets exactly as PixelValueWithCentre forms them for each moved centre.
  const double dx[5] = {x - c.x_px, x - (c.x_px + step_px), x - (c.x_px - step_px), x - c.x_px, x - c.x_px};
  const double dy[5] = {y - c.y_px, y - c.y_px, y - c.y_px, y - (c.y_px + step_px), y - (c.y_px - step_px)};
  impl_->Values5(dx, dy, std::abs(step_px), values);
}

double MarkModel::PixelValueWithCentre(PixelPoint centre_px, long x_px, long y_px) const {
  return impl_->Value(static_cast<double>(x_px) - centre_px.x_px, static_cast<double>(y_px) - centre_px.y_px);
}

std::vector<double> MarkModelWindow(const MarkModel& model, const PixelRect& window) {
  return MarkModelWindow(model, window, model.mark().centre_px);
}

std::vector<double> MarkModelWindow(const MarkModel& model, const PixelRect& window, PixelPoint centre_px) {
  std::vector<double> values(static_cast<size_t>(std::max(0L, window.width_px) * std::max(0L, window.height_px)));
  for (long row = 0; row < window.height_px; ++row)
    for (long col = 0; col < window.width_px; ++col)
      values[row * window.width_px + col] =
          model.PixelValueWithCentre(centre_px, window.x0_px + col, window.y0_px + row);
  return values;
}

std::vector<double> MarkModelWindow(const Scene& scene, const SceneMark& mark, const PixelRect& window,
                                    const RenderOptions& options) {
  return MarkModelWindow(MarkModel(mark, scene.noise.scanner_blur_sigma_px, options), window);
}

}  // namespace platemeter::sim
