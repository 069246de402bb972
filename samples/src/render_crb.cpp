#include "platemeter/samples/render_crb.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include "platemeter/core/error.h"

namespace platemeter::sim {

bool CramerRaoOptions::Check(std::string* why) const {
  if (margin_px < 0) {
    if (why) *why = "margin_px must be >= 0";
    return false;
  }
  if (!(step_px > 0.0 && step_px < 0.5)) {
    if (why) *why = "step_px must be in (0, 0.5)";
    return false;
  }
  return true;
}

double PixelNoiseVariance(const SceneNoise& noise) {
  return noise.sensor_sigma_dn * noise.sensor_sigma_dn + noise.grain_sigma_dn * noise.grain_sigma_dn +
         (noise.quantize ? 1.0 / 12.0 : 0.0);
}

MarkCramerRao CramerRaoBound(const MarkModel& model, const SceneNoise& noise, const PixelRect& window,
                             const CramerRaoOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("Cramer-Rao options", why);
  MarkCramerRao result;
  const double variance = PixelNoiseVariance(noise);
  const double amplitude = model.mark().amplitude_dn;
  if (window.empty() || !(variance > 0.0) || amplitude == 0.0) return result;
  const double h = options.step_px;
  Eigen::Matrix4d fisher = Eigen::Matrix4d::Zero();
  // Outside the support (which has a pixel of slack for the shifts, h < 0.5 px)
  // the mark gives 0 at every shifted centre: such a pixel only informs the
  // background, j = (0, 0, 0, 1). Counted, not evaluated five times.
  const PixelRect& support = model.support();
  long background_only = 0;
  for (long y = window.y0_px; y < window.y_end_px(); ++y)
    for (long x = window.x0_px; x < window.x_end_px(); ++x) {
      if (x < support.x0_px || x >= support.x_end_px() || y < support.y0_px || y >= support.y_end_px()) {
        ++background_only;
        continue;
      }
      double v[5];  // at the centre, then moved +x, -x, +y, -y
      model.PixelValuesShifted(h, x, y, v);
      Eigen::Vector4d j;
      j[0] = (v[1] - v[2]) / (2 * h);
      j[1] = (v[3] - v[4]) / (2 * h);
      j[2] = v[0] / amplitude;
      j[3] = 1.0;
      fisher.noalias() += j * j.transpose();
    }
  fisher(3, 3) += static_cast<double>(background_only);
  fisher /= variance;
  result.window_pixels = window.width_px * window.height_px;
  // Scale to unit diagonal before inverting: the entries span many decades.
  const Eigen::Vector4d d = fisher.diagonal().cwiseSqrt();
  if ((d.array() <= 0).any()) return result;
  const Eigen::Matrix4d scaled = d.cwiseInverse().asDiagonal() * fisher * d.cwiseInverse().asDiagonal();
  Eigen::LDLT<Eigen::Matrix4d> ldlt(scaled);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() < 1e-12) return result;
  const Eigen::Matrix4d covariance =
      d.cwiseInverse().asDiagonal() * ldlt.solve(Eigen::Matrix4d::Identity()) * d.cwiseInverse().asDiagonal();
  result.sigma_x_px = std::sqrt(covariance(0, 0));
  result.sigma_y_px = std::sqrt(covariance(1, 1));
  result.correlation_xy = covariance(0, 1) / (result.sigma_x_px * result.sigma_y_px);
  result.sigma_amplitude_dn = std::sqrt(covariance(2, 2));
  result.sigma_background_dn = std::sqrt(covariance(3, 3));
  result.valid = std::isfinite(result.sigma_x_px) && std::isfinite(result.sigma_y_px);
  return result;
}

namespace {

PixelRect CrbWindow(const MarkModel& model, const Scene& scene, long margin) {
  const PixelRect& s = model.support();
  const long x0 = std::max(0L, s.x0_px - margin), y0 = std::max(0L, s.y0_px - margin);
  const long x1 = std::min(scene.width_px, s.x_end_px() + margin);
  const long y1 = std::min(scene.height_px, s.y_end_px() + margin);
  return {x0, y0, std::max(0L, x1 - x0), std::max(0L, y1 - y0)};
}

}  // namespace

MarkCramerRao CramerRaoBound(const Scene& scene, const SceneMark& mark, const RenderOptions& render_options,
                             const CramerRaoOptions& options) {
  const MarkModel model(mark, scene.noise.scanner_blur_sigma_px, render_options);
  return CramerRaoBound(model, scene.noise, CrbWindow(model, scene, options.margin_px), options);
}

std::vector<MarkCramerRao> CramerRaoBounds(const Scene& scene, const RenderOptions& render_options,
                                           const CramerRaoOptions& options) {
  std::vector<MarkCramerRao> results(scene.marks.size());
  tbb::parallel_for(size_t{0}, scene.marks.size(), [&](size_t i) {
    results[i] = CramerRaoBound(scene, scene.marks[i], render_options, options);
  });
  return results;
}

}  // namespace platemeter::sim
