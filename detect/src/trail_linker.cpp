// Trail linking and schedule decoding; the method is in trail_linker.h.
#include "platemeter/detect/trail_linker.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <unordered_map>

#include <Eigen/Dense>

#include "platemeter/core/error.h"

namespace platemeter {

bool TrailOptions::Check(std::string* why) const {
  auto fail = [&](const char* r) {
    if (why) *why = r;
    return false;
  };
  if (!(max_link_px > 0)) return fail("max_link_px must be > 0");
  if (!(min_link_px >= 0 && min_link_px < max_link_px)) return fail("min_link_px must be in [0, max_link_px)");
  if (!(max_bend_deg > 0 && max_bend_deg < 90)) return fail("max_bend_deg must be in (0, 90)");
  if (!(match_tolerance > 0 && match_tolerance < 0.5)) return fail("match_tolerance must be in (0, 0.5)");
  if (!(max_gap_ratio > 1)) return fail("max_gap_ratio must be > 1");
  if (min_images < 3) return fail("min_images must be >= 3");
  if (max_unmatched < 0) return fail("max_unmatched must be >= 0");
  if (!(min_elongated_exposure_s >= 0)) return fail("min_elongated_exposure_s must be >= 0");
  if (!(edge_margin_px >= 0)) return fail("edge_margin_px must be >= 0");
  return true;
}

namespace {

struct Pt {
  double x, y;
};

// Spatial hash of points in cells of `cell` px.
class Grid {
 public:
  Grid(const std::vector<Pt>& p, const std::vector<int>& ids, double cell) : p_(p), cell_(cell) {
    for (int i : ids) cells_[Key(p[i].x, p[i].y)].push_back(i);
  }
  template <class F>
  void Near(int i, double r, F f) const {
    const long cx = static_cast<long>(std::floor(p_[i].x / cell_)), cy = static_cast<long>(std::floor(p_[i].y / cell_));
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells_.find(Pack(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (int j : it->second)
          if (j != i && std::hypot(p_[j].x - p_[i].x, p_[j].y - p_[i].y) <= r) f(j);
      }
  }

 private:
  static long long Pack(long x, long y) { return (static_cast<long long>(x) << 32) ^ (y & 0xffffffffLL); }
  long long Key(double x, double y) const {
    return Pack(static_cast<long>(std::floor(x / cell_)), static_cast<long>(std::floor(y / cell_)));
  }
  const std::vector<Pt>& p_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

// Chains of mutually linked images (degree <= 2, nearly straight).
std::vector<std::vector<int>> BuildChains(const std::vector<Pt>& p, const std::vector<int>& ids, const TrailOptions& o) {
  const Grid grid(p, ids, o.max_link_px);
  const double cos_straight = std::cos((180.0 - o.max_bend_deg) * std::numbers::pi / 180.0);  // negative
  std::map<int, std::vector<int>> proposed;
  for (int i : ids) {
    std::vector<std::pair<double, int>> nb;
    grid.Near(i, o.max_link_px, [&](int j) {
      const double d = std::hypot(p[j].x - p[i].x, p[j].y - p[i].y);
      if (d >= o.min_link_px) nb.push_back({d, j});
    });
    std::sort(nb.begin(), nb.end());
    if (nb.empty()) continue;
    const int a = nb[0].second;
    proposed[i].push_back(a);
    const double ax = p[a].x - p[i].x, ay = p[a].y - p[i].y, an = nb[0].first;
    for (size_t k = 1; k < nb.size(); ++k) {
      const int b = nb[k].second;
      const double c = (ax * (p[b].x - p[i].x) + ay * (p[b].y - p[i].y)) / (an * nb[k].first);
      if (c <= cos_straight) {
        proposed[i].push_back(b);
        break;
      }
    }
  }
  auto has = [&](int i, int j) {
    auto it = proposed.find(i);
    return it != proposed.end() && std::find(it->second.begin(), it->second.end(), j) != it->second.end();
  };
  std::map<int, std::vector<int>> adj;
  for (const auto& [i, js] : proposed)
    for (int j : js)
      if (i < j && has(j, i)) {
        adj[i].push_back(j);
        adj[j].push_back(i);
      }
  std::vector<std::vector<int>> chains;
  std::map<int, bool> seen;
  auto walk = [&](int start) {
    std::vector<int> c{start};
    seen[start] = true;
    int prev = -1, cur = start;
    for (;;) {
      int next = -1;
      for (int j : adj[cur])
        if (j != prev && !seen[j]) next = j;
      if (next < 0) break;
      seen[next] = true;
      c.push_back(next);
      prev = cur;
      cur = next;
    }
    return c;
  };
  for (const auto& [i, js] : adj)
    if (js.size() == 1 && !seen[i]) chains.push_back(walk(i));
  for (const auto& [i, js] : adj)
    if (!seen[i]) chains.push_back(walk(i));  // closed loops: cut anywhere (will not match a schedule)
  // Cut at gaps far above the chain's median (the break between two trails of one star: ~500 s
  // against 20-108 s within a trail).
  std::vector<std::vector<int>> cut;
  for (const std::vector<int>& c : chains) {
    std::vector<double> gaps;
    for (size_t k = 1; k < c.size(); ++k) gaps.push_back(std::hypot(p[c[k]].x - p[c[k - 1]].x, p[c[k]].y - p[c[k - 1]].y));
    std::vector<double> sorted = gaps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double limit = sorted.empty() ? 0.0 : o.max_gap_ratio * sorted[sorted.size() / 2];
    std::vector<int> piece{c[0]};
    for (size_t k = 1; k < c.size(); ++k) {
      if (gaps[k - 1] > limit) {
        cut.push_back(piece);
        piece.clear();
      }
      piece.push_back(c[k]);
    }
    cut.push_back(piece);
  }
  return cut;
}

struct Labelling {
  int trail = 0;                 // 0-based
  std::vector<int> exposure;     // per chain element (in time order): index into the trail's exposures, -1 none
  std::vector<double> residual_s;
  int score = -1000000;
  int matched = 0, missing_leading = 0;
  double rms_s = 0.0, rate = 0.0;
  bool reversed = false;
};

// Assigns each arc length to the nearest exposure time through s(t) = c0 + c1 t + c2 t^2 (inverted
// by Newton from the linear guess).
void Assign(const std::vector<double>& s, const std::vector<double>& tau, const std::vector<double>& tol,
            const std::vector<bool>& elongated, const std::vector<bool>& short_exposure, const Eigen::Vector3d& c,
            Labelling* L) {
  const size_t m = s.size();
  L->exposure.assign(m, -1);
  L->residual_s.assign(m, 0.0);
  int last = -1;
  for (size_t k = 0; k < m; ++k) {
    double t = (s[k] - c[0]) / c[1];
    for (int it = 0; it < 3; ++it) t -= (c[0] + c[1] * t + c[2] * t * t - s[k]) / (c[1] + 2 * c[2] * t);
    const auto pos = std::lower_bound(tau.begin(), tau.end(), t) - tau.begin();
    int best = -1;
    double bd = 1e300;
    for (long j : {static_cast<long>(pos) - 1, static_cast<long>(pos)}) {
      if (j < 0 || j >= static_cast<long>(tau.size())) continue;
      const double d = std::abs(t - tau[j]);
      if (d < bd) bd = d, best = static_cast<int>(j);
    }
    // An elongated image is a dash or a long dot, never a short dot.
    if (best >= 0 && bd <= tol[best] && best > last && !(elongated[k] && short_exposure[best])) {
      L->exposure[k] = best;
      L->residual_s[k] = t - tau[best];
      last = best;
    }
  }
}

bool Refit(const std::vector<double>& s, const std::vector<double>& tau, const Labelling& L, Eigen::Vector3d* c) {
  std::vector<int> ks;
  for (size_t k = 0; k < s.size(); ++k)
    if (L.exposure[k] >= 0) ks.push_back(static_cast<int>(k));
  if (ks.size() < 4) return false;
  // The curvature term only with many matches: on a short piece it would bend the scale onto a wrong pattern.
  const bool quadratic = ks.size() >= 15;
  Eigen::MatrixXd A(ks.size(), quadratic ? 3 : 2);
  Eigen::VectorXd b(ks.size());
  for (size_t r = 0; r < ks.size(); ++r) {
    const double t = tau[L.exposure[ks[r]]];
    A(r, 0) = 1.0;
    A(r, 1) = t;
    if (quadratic) A(r, 2) = t * t;
    b[r] = s[ks[r]];
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  *c = Eigen::Vector3d(x[0], x[1], quadratic ? x[2] : 0.0);
  return std::isfinite((*c)[1]) && (*c)[1] > 0;
}

}  // namespace

TrailLinkResult LinkTrails(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("trail options", why);
  const std::vector<ShutterExposure> schedule = BuildShutterSchedule(program);
  const int trails = static_cast<int>(program.leading_dashes.size());
  std::vector<std::vector<ShutterExposure>> per_trail(trails);
  for (const ShutterExposure& e : schedule) per_trail[e.trail - 1].push_back(e);
  // Times relative to each trail's first mid-exposure (better conditioned), and match tolerances.
  std::vector<std::vector<double>> tau(trails), tol(trails);
  std::vector<std::vector<bool>> short_exposure(trails);
  for (int t = 0; t < trails; ++t) {
    const auto& ex = per_trail[t];
    for (const auto& e : ex) {
      tau[t].push_back(e.mid_s - ex.front().mid_s);
      short_exposure[t].push_back(e.duration_s < options.min_elongated_exposure_s);
    }
    for (size_t j = 0; j < ex.size(); ++j) {
      double gap = 1e300;
      if (j > 0) gap = std::min(gap, tau[t][j] - tau[t][j - 1]);
      if (j + 1 < ex.size()) gap = std::min(gap, tau[t][j + 1] - tau[t][j]);
      tol[t].push_back(options.match_tolerance * gap);
    }
  }

  TrailLinkResult result;
  result.images.resize(images.size());
  std::vector<Pt> p(images.size());
  std::vector<int> ids;
  for (size_t i = 0; i < images.size(); ++i) {
    const DetectedStar& d = images[i];
    p[i] = {d.point.position_px.x_px, d.point.position_px.y_px};
    if (d.point.status != PointStatus::kMeasured || (d.flags & kStarDefect)) {
      result.images[i].reason = "not_star";
      continue;
    }
    result.images[i].reason = "unlinked";
    ids.push_back(static_cast<int>(i));
  }

  for (std::vector<int>& chain : BuildChains(p, ids, options)) {
    const int cid = static_cast<int>(result.chains.size());
    TrailChain tc;
    for (int i : chain) result.images[i].chain = cid;
    auto give_up = [&](const std::string& reason) {
      tc.reason = reason;
      for (int i : tc.images) result.images[i].reason = reason;
      result.chains.push_back(tc);
    };
    tc.images = chain;
    if (static_cast<int>(chain.size()) < options.min_images) {
      give_up("short_chain");
      continue;
    }
    const size_t m = chain.size();
    // Best labelling over trail, direction and the exposures of the chain's ends.
    std::map<std::vector<int>, Labelling> distinct;
    for (int dir = 0; dir < 2; ++dir) {
      std::vector<int> ordered = chain;
      if (dir) std::reverse(ordered.begin(), ordered.end());
      std::vector<double> s(m, 0.0);
      std::vector<bool> elongated(m);
      for (size_t k = 0; k < m; ++k) elongated[k] = (images[ordered[k]].flags & kStarElongated) != 0;
      for (size_t k = 1; k < m; ++k)
        s[k] = s[k - 1] + std::hypot(p[ordered[k]].x - p[ordered[k - 1]].x, p[ordered[k]].y - p[ordered[k - 1]].y);
      for (int t = 0; t < trails; ++t) {
        const auto& T = tau[t];
        const int n = static_cast<int>(T.size());
        const int N = program.leading_dashes[t];
        for (int k0 : {0, 1})
          for (int k1 : {static_cast<int>(m) - 1, static_cast<int>(m) - 2}) {
            if (k1 <= k0) continue;
            for (int j0 = 0; j0 < n; ++j0)
              for (int j1 = j0 + (k1 - k0); j1 < n; ++j1) {
                Labelling L;
                L.trail = t;
                L.reversed = dir;
                const double rate = (s[k1] - s[k0]) / (T[j1] - T[j0]);
                Eigen::Vector3d c(s[k0] - rate * T[j0], rate, 0.0);
                Assign(s, T, tol[t], elongated, short_exposure[t], c, &L);
                int matched = 0;
                for (int e : L.exposure) matched += e >= 0;
                if (matched * 2 < static_cast<int>(m)) continue;
                for (int iter = 0; iter < 2; ++iter) {
                  if (!Refit(s, T, L, &c)) break;
                  Assign(s, T, tol[t], elongated, short_exposure[t], c, &L);
                }
                // Score: matched images minus exposures expected between the trail's start and the last match.
                L.matched = 0;
                int last = -1;
                for (int e : L.exposure)
                  if (e >= 0) ++L.matched, last = e;
                std::vector<bool> seen(n, false);
                for (int e : L.exposure)
                  if (e >= 0) seen[e] = true;
                int missing = 0;
                L.missing_leading = 0;
                for (int j = 0; j <= last; ++j)
                  if (!seen[j]) {
                    ++missing;
                    if (j < N) ++L.missing_leading;
                  }
                L.score = L.matched - missing;
                double ss = 0;
                for (size_t k = 0; k < m; ++k)
                  if (L.exposure[k] >= 0) ss += L.residual_s[k] * L.residual_s[k];
                L.rms_s = std::sqrt(ss / std::max(1, L.matched));
                L.rate = c[1];
                // Key: the (image -> trail, exposure) labels, independent of direction.
                std::vector<int> key(m, -1);
                for (size_t k = 0; k < m; ++k)
                  if (L.exposure[k] >= 0) {
                    const size_t pos = dir ? m - 1 - k : k;
                    key[pos] = t * 1000 + L.exposure[k];
                  }
                auto it = distinct.find(key);
                if (it == distinct.end() || it->second.score < L.score) distinct[key] = std::move(L);
              }
          }
      }
    }
    if (distinct.empty()) {
      give_up("no_schedule_match");
      continue;
    }
    const Labelling* best = nullptr;
    int runner = -1000000;
    for (const auto& [key, L] : distinct)
      if (!best || L.score > best->score) best = &L;
    for (const auto& [key, L] : distinct)
      if (&L != best) runner = std::max(runner, L.score);
    tc.score = best->score;
    tc.runner_up_score = runner;
    tc.trail = best->trail + 1;
    tc.leading_dashes = program.leading_dashes[best->trail];
    tc.rate_px_per_s = best->rate;
    tc.rms_s = best->rms_s;
    std::vector<int> ordered = chain;
    if (best->reversed) std::reverse(ordered.begin(), ordered.end());
    tc.images = ordered;
    const int unmatched = static_cast<int>(m) - best->matched;
    std::string reason;
    int last_matched = -1, round_leading = 0;
    for (size_t k = 0; k < m; ++k)
      if (best->exposure[k] >= 0) {
        last_matched = std::max(last_matched, best->exposure[k]);
        if (best->exposure[k] < tc.leading_dashes && !(images[ordered[k]].flags & kStarElongated)) ++round_leading;
      }
    if (best->missing_leading > 0) reason = "leading_dashes_incomplete";
    // The leading run must be seen as dashes, and the pattern must run on past the first two dot
    // groups: a short piece of dots fits the dash pattern under some scale.
    else if (options.require_elongated_dashes && round_leading > 0) reason = "leading_dashes_not_elongated";
    else if (last_matched < tc.leading_dashes + options.min_exposures_after_run) reason = "short_pattern";
    else if (runner >= best->score) reason = "ambiguous";
    else if (unmatched > options.max_unmatched) reason = "no_schedule_match";
    else if (options.image_max_px.x_px > options.image_min_px.x_px) {
      // One dash before the run: extrapolated from the first two dashes (30 s apart both).
      int k0 = -1, k1 = -1;
      for (size_t k = 0; k < m; ++k)
        if (best->exposure[k] == 0) k0 = static_cast<int>(k);
        else if (best->exposure[k] == 1) k1 = static_cast<int>(k);
      if (k0 < 0 || k1 < 0) {
        reason = "leading_dashes_incomplete";
      } else {
        const Pt a = p[ordered[k0]], b = p[ordered[k1]];
        const double x = 2 * a.x - b.x, y = 2 * a.y - b.y, e = options.edge_margin_px;
        if (x < options.image_min_px.x_px + e || y < options.image_min_px.y_px + e ||
            x > options.image_max_px.x_px - e || y > options.image_max_px.y_px - e)
          reason = "at_edge";
        // An image where the dash before the run would be: perhaps that dash, not linked.
        const double r = 0.5 * std::hypot(b.x - a.x, b.y - a.y);
        for (size_t i = 0; i < p.size() && reason.empty(); ++i)
          if (std::hypot(p[i].x - x, p[i].y - y) < r) reason = "image_before_run";
      }
    }
    if (!reason.empty()) {
      tc.trail = 0;
      give_up(reason);
      continue;
    }
    for (size_t k = 0; k < m; ++k) {
      TrailImage& ti = result.images[ordered[k]];
      const int e = best->exposure[k];
      if (e < 0) {
        ti.reason = "stray";
        continue;
      }
      const ShutterExposure& ex = per_trail[best->trail][e];
      ti.assigned = true;
      ti.reason.clear();
      ti.trail = ex.trail;
      ti.kind = ex.kind;
      ti.dot_index = ex.dot_index;
      ti.dash_index = ex.dash_index;
      ti.mid_s = ex.mid_s;
      ti.residual_s = best->residual_s[k];
      (ex.kind == ExposureKind::kDot ? result.assigned_dots : result.assigned_dashes)++;
    }
    result.chains.push_back(tc);
  }
  return result;
}

}  // namespace platemeter
