// The final sidereal fit of one trail (step 3, decoder.h): its weighted track, outliers flagged bad one at
// a time.
#include <algorithm>
#include <cmath>

#include "trail_internal.h"

namespace platemeter::trail_internal {

bool FitTrail(const Context& c, const std::vector<std::pair<int, int>>& taken, TrailChain* chain,
              std::vector<TrailImage>* out, Track* final_track) {
  const TrailOptions& o = c.o;
  const int n = static_cast<int>(taken.size());
  std::vector<bool> bad(n, false);
  std::vector<double> t(n), sx(n), sy(n);
  std::vector<PixelPoint> p(n);
  for (int k = 0; k < n; ++k) {
    const int i = taken[k].second;
    const DetectedStar& d = c.images[i];
    t[k] = (*out)[i].mid_s;
    p[k] = c.p[i];
    const FitSigma sigma = FitSigmaOf(o, d);
    sx[k] = sigma.x_px, sy[k] = sigma.y_px;
  }
  Track track;
  bool fitted = false;
  // Every pass refits without the images flagged so far: the final track never holds a bad one.
  for (int marked = 0;; ++marked) {
    std::vector<double> ft, fsx, fsy;
    std::vector<PixelPoint> fp;
    for (int k = 0; k < n; ++k)
      if (!bad[k]) ft.push_back(t[k]), fp.push_back(p[k]), fsx.push_back(sx[k]), fsy.push_back(sy[k]);
    if (ft.size() < 4) return false;
    const int degree = DegreeFor(static_cast<int>(ft.size()), ft.back() - ft.front(), o.track_degree);
    if (!track.Fit(ft, fp, fsx, fsy, degree)) break;
    fitted = true;
    // Studentised residuals (a fitted image's residual has the sigma sigma sqrt(1 - leverage): an
    // image near a trail's end, which the track follows, is judged fairly); their robust spread
    // (median chi of 2 dof = 1.177) scales the limit. deleted[k]: the residual had image k been left
    // out of the fit, r / (1 - h).
    std::vector<double> chi(n), deleted(n), good_chi;
    for (int k = 0; k < n; ++k) {
      const PixelPoint m = track.At(t[k]);
      double hx = 0, hy = 0;
      if (!bad[k]) track.LeverageAt(t[k], sx[k], sy[k], &hx, &hy);
      const double rx = p[k].x_px - m.x_px, ry = p[k].y_px - m.y_px;
      chi[k] = std::hypot(rx / (sx[k] * std::sqrt(1 - hx)), ry / (sy[k] * std::sqrt(1 - hy)));
      deleted[k] = std::hypot(rx / (1 - hx), ry / (1 - hy));
      if (!bad[k]) good_chi.push_back(chi[k]);
    }
    std::nth_element(good_chi.begin(), good_chi.begin() + good_chi.size() / 2, good_chi.end());
    const double spread = std::max(1.0, good_chi[good_chi.size() / 2] / 1.1774);
    int worst = -1;
    for (int k = 0; k < n; ++k) {
      if (bad[k]) continue;
      if (chi[k] > o.tuning.bad_sigma * spread && deleted[k] > o.tuning.min_bad_px && (worst < 0 || chi[k] > chi[worst])) worst = k;
    }
    // At most a third of the images bad, and enough left for the track.
    if (worst < 0 || marked + 1 > n / 3 || ft.size() <= 6) break;
    bad[worst] = true;
  }
  if (!fitted) return false;
  double ss = 0;
  int good = 0;
  for (int k = 0; k < n; ++k) {
    TrailImage& ti = (*out)[taken[k].second];
    const PixelPoint m = track.At(t[k]);
    ti.residual_x_px = p[k].x_px - m.x_px;
    ti.residual_y_px = p[k].y_px - m.y_px;
    ti.residual_px = std::hypot(ti.residual_x_px, ti.residual_y_px);
    ti.refined_px = m;
    track.SigmaAt(t[k], &ti.sigma_refined_x_px, &ti.sigma_refined_y_px);
    ti.bad = bad[k];
    if (bad[k]) {
      ti.reason = TrailReason::kBadFit;
      ++chain->bad_images;
    } else {
      ss += ti.residual_px * ti.residual_px, ++good;
    }
  }
  chain->rms_px = good > 0 ? std::sqrt(ss / good) : 0.0;
  *final_track = track;
  return true;
}

}  // namespace platemeter::trail_internal
