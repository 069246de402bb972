#pragma once
// Seed 000 Tables 1 and 3 (the Hasselblad self-calibrations) as camera
// definitions, for the profile tests of calib/ and cli/. The OCR
// reconstructions are documented in tests/calib/profile_seed000_test.cpp and
// docs/cameras.md.

namespace platemeter::testing {

inline constexpr char kSeed000Tables1And3Toml[] = R"toml(
[[camera]]
name = "hasselblad-500-selfcal"
description = "Apollo 14 500 mm Hasselblad, pure in-flight self-calibration (seed 000 Table 1)"
source = "seed 000, Table 1"
format_width_mm = 55.0
format_height_mm = 55.0
nominal_principal_distance_mm = 500.0
format_corners_as_fiducials = true

[camera.lens]
model = "brown-balanced"
source = "seed 000, Table 1 (pure self-calibration), balanced at r = 30 mm"
principal_distance_mm = 502.630
principal_point_x_mm = 0.0
principal_point_y_mm = 0.0

[camera.lens.coefficients]
k0 = -0.14065e-1
k1_per_mm2 = +0.15614e-4
k2_per_mm4 = 0.0
p1_per_mm = +0.3604e-5
p2_per_mm = +0.2998e-5

[camera.lens.sigmas]
principal_distance_mm = 2.060
k0 = 0.58e-4
k1_per_mm2 = 0.172e-6
k2_per_mm4 = 0.0
p1_per_mm = 0.3575e-5
p2_per_mm = 0.3020e-5

[[camera]]
name = "hasselblad-500-selfcal-constrained"
description = "Apollo 14 500 mm Hasselblad, self-calibration with positional constraints (seed 000 Table 3)"
source = "seed 000, Table 3"
format_width_mm = 55.0
format_height_mm = 55.0
nominal_principal_distance_mm = 500.0
format_corners_as_fiducials = true

[camera.lens]
model = "brown-balanced"
source = "seed 000, Table 3 (self-calibration with positional constraints), balanced at r = 30 mm"
principal_distance_mm = 504.056
principal_point_x_mm = 0.0
principal_point_y_mm = 0.0

[camera.lens.coefficients]
k0 = -0.14144e-1
k1_per_mm2 = +0.15701e-4
k2_per_mm4 = 0.0
p1_per_mm = +0.6542e-6
p2_per_mm = -0.2063e-7

[camera.lens.sigmas]
principal_distance_mm = 1.503
k0 = 0.43e-4
k1_per_mm2 = 0.176e-6
k2_per_mm4 = 0.0
p1_per_mm = 0.2454e-5
p2_per_mm = 0.2739e-5
)toml";

}  // namespace platemeter::testing
