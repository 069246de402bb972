// The trail decoder's options checked (TrailOptions::Check) and its result's one-line summary (trail_linker.h).
#include <string>

#include "platemeter/detect/trail_linker.h"

namespace platemeter {

bool TrailOptions::Check(std::string* why) const {
  auto fail = [&](const char* r) {
    if (why) *why = r;
    return false;
  };
  if (!(psf_fwhm_px > 0)) return fail("psf_fwhm_px must be > 0");
  if (!(max_dash_spacing_px > 0)) return fail("max_dash_spacing_px must be > 0");
  if (!(edge_margin_px >= 0)) return fail("edge_margin_px must be >= 0");
  if (!blind.Check(nullptr)) return fail("blind: radius and arm widths must be >= 0, arm axes unit vectors");
  if (!(match_tolerance > 0 && match_tolerance < 0.5)) return fail("match_tolerance must be in (0, 0.5)");
  if (!(flux_tolerance >= 0)) return fail("flux_tolerance must be >= 0");
  if (!(position_floor_px >= 0)) return fail("position_floor_px must be >= 0");
  if (track_degree < 1 || track_degree > 6) return fail("track_degree must be 1..6");
  if (!(join_tolerance_px > 0)) return fail("join_tolerance_px must be > 0");
  if (!(flow_tolerance_px > 0)) return fail("flow_tolerance_px must be > 0");
  const Tuning& t = tuning;
  if (!(t.run_spacing_tolerance > 0 && t.run_spacing_tolerance < 0.5)) return fail("run_spacing_tolerance must be in (0, 0.5)");
  if (!(t.max_run_bend_deg > 0 && t.max_run_bend_deg < 45)) return fail("max_run_bend_deg must be in (0, 45)");
  if (!(t.min_tolerance_px > 0)) return fail("min_tolerance_px must be > 0");
  if (t.min_exposures_after_run < 1) return fail("min_exposures_after_run must be >= 1");
  if (t.max_missed_in_row < 1) return fail("max_missed_in_row must be >= 1");
  if (!(t.min_elongated_exposure_s >= 0)) return fail("min_elongated_exposure_s must be >= 0");
  if (!(t.dash_length_tolerance > 0)) return fail("dash_length_tolerance must be > 0");
  if (!(t.bad_sigma > 1) || !(t.min_bad_px >= 0)) return fail("bad_sigma must be > 1 and min_bad_px >= 0");
  if (!(t.join_tolerance_fraction >= 0)) return fail("join_tolerance_fraction must be >= 0");
  if (!(t.max_median_residual_px > 0) || !(t.max_median_residual_fwhm >= 0)) return fail("max_median_residual_px must be > 0");
  if (!(t.run_flux_tolerance > 0)) return fail("run_flux_tolerance must be > 0");
  if (!(t.crowd_radius_fwhm >= 0)) return fail("crowd_radius_fwhm must be >= 0");
  if (!(t.tight_tolerance_px > 0)) return fail("tight_tolerance_px must be > 0");
  if (!(t.max_leverage > 0 && t.max_leverage <= 1)) return fail("max_leverage must be in (0, 1]");
  if (t.min_sibling_images < 1 || !(t.sibling_window_s >= 0)) return fail("min_sibling_images must be >= 1");
  if (!(t.sibling_tolerance_px > 0) || !(t.sibling_tolerance_fraction >= 0)) return fail("sibling_tolerance_px must be > 0");
  if (!(t.clean_radius_spacings >= 0)) return fail("clean_radius_spacings must be >= 0");
  if (!(t.sibling_growth_window_s > 0)) return fail("sibling_growth_window_s must be > 0");
  if (!(t.motion_radius_px > 0)) return fail("motion_radius_px must be > 0");
  if (t.flow_degree < 1 || t.flow_degree > 10) return fail("flow_degree must lie in 1..10");
  if (!(t.flow_tolerance_fraction >= 0)) return fail("flow_tolerance_fraction must be >= 0");
  if (t.flow_min_images < 6 || t.flow_min_sibling_images < 6) return fail("flow_min_images must be >= 6");
  return true;
}

std::string TrailLinkResult::Summary() const {
  long decoded = 0;
  for (const TrailChain& c : chains) decoded += c.trail > 0;
  return std::to_string(assigned_dots) + " dots and " + std::to_string(assigned_dashes) + " dashes tagged in " +
         std::to_string(decoded) + " trails of " + std::to_string(stars.size()) + " stars (" +
         std::to_string(bad_images) + " bad); " + std::to_string(chains.size() - decoded) + " runs refused";
}

}  // namespace platemeter
