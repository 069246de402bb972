#pragma once
// The simulated Orbigon star plate of the trail tests (Beltsville, 12 May 1972, first opening
// 05:30:00 UTC, duty cycle of seed 001 Table 1), shared by tests/detect and tests/cli.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/samples/simulate.h"

namespace platemeter::testing {

// Simulator spec: catalog stars to magnitude_limit, a star of reference_magnitude exposed 10 s
// peaking at reference_peak_dn, PSF FWHM 30 um; noise_dn > 0 adds that sensor and grain noise (DN).
inline std::string OrbigonTrailSpec(const std::string& name, double magnitude_limit, double reference_magnitude,
                                    double reference_peak_dn, double pixel_size_um = 12.5, double noise_dn = 0.0) {
  std::string spec = "name = \"" + name + "\"\ncamera = \"orbigon\"\nseed = 5\n[output]\npixel_size_um = " +
                     std::to_string(pixel_size_um) + "\n[stars]\nfwhm_um = 30\nreference_magnitude = " +
                     std::to_string(reference_magnitude) + "\nreference_peak_dn = " + std::to_string(reference_peak_dn) +
                     "\n[star_field]\nlatitude_deg = 39.03\nlongitude_deg = -76.93\nheight_m = 50\n"
                     "start_utc = \"1972-05-12T05:30:00Z\"\nmagnitude_limit = " + std::to_string(magnitude_limit) + "\n";
  if (noise_dn > 0)
    spec += "[noise]\nsensor_sigma_dn = " + std::to_string(noise_dn) + "\ngrain_sigma_dn = " + std::to_string(noise_dn) + "\n";
  return spec;
}

// Seconds after 05:30:00 of an ISO time "1972-05-12Thh:mm:ss.sssZ" (independent of the tool).
inline double SecondsAfter0530(const std::string& iso) {
  int h = 0, mi = 0;
  double s = 0;
  EXPECT_EQ(std::sscanf(iso.c_str() + 11, "%d:%d:%lf", &h, &mi, &s), 3) << iso;
  return (h - 5) * 3600.0 + (mi - 30) * 60.0 + s;
}

// The exposed 114 mm format (the simulator draws no image outside it) in the plate's pixels.
inline std::vector<PixelPoint> OrbigonFormatOutline_px(const sim::SimulatedPlate& plate) {
  std::vector<PixelPoint> outline;
  for (const auto& [u_mm, v_mm] : {std::pair{-57.0, -57.0}, {57.0, -57.0}, {57.0, 57.0}, {-57.0, 57.0}})
    outline.push_back(plate.chain.PixelFromPlate({u_mm, v_mm}));
  return outline;
}

}  // namespace platemeter::testing
