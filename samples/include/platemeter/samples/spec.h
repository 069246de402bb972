#pragma once
// The simulator's spec: one TOML file describing a simulated plate (camera,
// output, geometry chain, marks, sky, background, noise, defects). Every key,
// its unit and its meaning are in docs/simulator.md. Unknown keys are errors,
// so a typo never passes silently. toml++ stays inside samples/src.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/samples/geometry.h"

namespace platemeter::sim {

struct SpecOutput {
  double pixel_size_um = 25.0;                     // um; nominal (CI-sized) scan pixel
  std::optional<double> full_size_pixel_size_um;   // um; used instead with --full-size
  double margin_mm = 3.0;                          // mm; around the format, grid and fiducials
  std::optional<long> width_px, height_px;         // px; explicit size (else derived)
  int bits = 16;                                   // 8 or 16
  int tile_size_px = 256;                          // px; TIFF tile side (0: strips)
  std::string compression = "zip";                 // none, lzw, zip
};

struct SpecThermal {
  std::optional<double> temperature_degC;              // degC; glass temperature (default: no thermal effect)
  std::optional<double> calibration_temperature_degC;  // degC; default the camera's or the grid's
  std::optional<double> expansion_per_degC;            // 1/degC; default the camera's
};

struct SpecEmulsion {
  double depth_um = 0.0;                               // um; image centroid below the emulsion surface
  double refractive_index = 1.65;                      // of the emulsion
  std::optional<double> principal_distance_mm;         // mm; default the camera's calibrated or nominal
};

struct SpecScanner {
  double pixel_aspect = 1.0;              // pixel height / width
  double rotation_deg = 0.0;              // deg; counter-clockwise
  double non_orthogonality_arcsec = 0.0;  // arcsec
  int orientation_deg = 0;                // 0, 90, 180, 270
  bool mirrored = false;                  // emulsion-down scan
  double offset_px[2] = {0.0, 0.0};       // px; plate origin relative to the image centre
};

// How a family of marks looks on the scan.
struct SpecMarkLook {
  bool dark = true;                      // polarity: dark (negative plate) or bright
  double contrast_dn = 12000.0;          // DN; against the local background
  std::optional<double> line_width_um;   // um; default the definition's
  std::optional<double> size_um;         // um; cross arm tip to tip / dot, ring diameter / corner arm (default the definition's)
};

// A point given in plate millimetres (passpoints, explicit stars).
struct SpecPoint {
  std::string id;
  double x_mm = 0.0;
  double y_mm = 0.0;
  double magnitude = 0.0;  // stars only
};

struct SpecPasspoints {
  std::string shape = "dot";           // dot or ring
  double diameter_um = 300.0;          // um; outer diameter
  double line_width_um = 40.0;         // um; ring line width
  bool dark = true;
  double contrast_dn = 10000.0;        // DN
  int count = 0;                       // random passpoints inside the format (in addition to `points`)
  double clearance_mm = 1.5;           // mm; random ones keep this far from reseau crosses and each other
  std::vector<SpecPoint> points;       // explicit passpoints
};

// The sky marks hook: star images at plate positions. Random stars for now;
// catalog stars (calib/star_catalog.h + apparent places + a lens model) will
// fill the same list later (docs/simulator.md, "Stars").
struct SpecStars {
  int count = 0;                       // random stars inside the format
  double magnitude_min = 3.0;          // brightest random magnitude
  double magnitude_max = 8.0;          // faintest
  double reference_magnitude = 6.0;    // magnitude whose image has reference_peak_dn
  double reference_peak_dn = 8000.0;   // DN; peak contrast of a reference star (before scanner blur)
  double fwhm_um = 15.0;               // um; Gaussian PSF FWHM on the plate
  bool dark = true;                    // negative plate: dark stars
  std::vector<SpecPoint> points;       // explicit stars (id, x_mm, y_mm, magnitude)
};

// [star_field]: catalog stars seen from a site through the camera's lens, one
// image per star and exposure of the shutter program (star_field.h). Angles in
// degrees here, radians inside.
struct SpecStarField {
  bool enabled = false;                  // the table is present
  double latitude_deg = 32.0 + 32.0 / 60.0;     // deg; geodetic, north positive (default seed 004's camera mount)
  double longitude_deg = -(106.0 + 36.0 / 60.0);// deg; east positive
  double height_m = 1501.0;              // m; above the ellipsoid
  std::string start_utc;                 // ISO 8601 UTC of the first shutter opening (required)
  std::optional<double> pressure_hpa;    // hPa at the site; default the standard atmosphere at height_m
  double temperature_degC = 10.0;        // degC; ambient
  double relative_humidity = 0.5;        // 0..1
  double wavelength_um = 0.55;           // um; effective wavelength
  bool refraction = true;                // false: unrefracted directions
  double ut1_minus_utc_s = 0.0;          // s; UT1-UTC (0: see apparent_place.h)
  double axis_azimuth_deg = 0.0;         // deg; optical axis, from north through east
  double axis_altitude_deg = 90.0;       // deg; optical axis altitude (90: zenith)
  double roll_deg = 0.0;                 // deg; kappa (star_field.h)
  std::string catalog;                   // star file (empty: /usr/share/kstars/stars.dat)
  double magnitude_limit = 6.0;          // mag; faintest V simulated
  std::string exposure = "duty_cycle";   // "duty_cycle" (seed 001 Table 1) or "single"
  std::vector<int> leading_dashes{2, 3, 4, 5};  // leading dashes per trail (one entry per trail)
  double break_s = 480.0;                // s; break between trails (420..600)
  double exposure_s = 1.0;               // s; the single exposure
  double reference_exposure_s = 10.0;    // s; exposure in which a reference-magnitude star has reference_peak_dn
};

struct SpecBackground {
  double level_dn = 30000.0;           // DN
  double terrain_amplitude_dn = 0.0;   // DN RMS; 0 for a flat sky
  double terrain_scale_mm = 10.0;      // mm; typical terrain feature size
  double vignetting_fraction = 0.0;    // fall-off at vignetting_radius_mm
  double vignetting_radius_mm = 80.0;  // mm; from the principal point
};

struct SpecNoise {
  double blur_sigma_um = 0.0;          // um; Gaussian scanner blur (on the plate)
  double sensor_sigma_dn = 0.0;        // DN
  double grain_sigma_dn = 0.0;         // DN
  bool quantize = true;
};

struct SpecFalseMark {
  std::string near;                    // a reseau cross id
  double offset_um[2] = {0.0, 0.0};    // um; from that cross, plate frame
};

struct SpecDefects {
  int dust_count = 0;
  double dust_diameter_min_um = 50.0, dust_diameter_max_um = 300.0;  // um
  double dust_contrast_dn = 8000.0;    // DN; sign from dust_dark
  bool dust_dark = true;
  int scratch_count = 0;
  double scratch_length_mm = 20.0;     // mm
  double scratch_width_um = 15.0;      // um
  double scratch_contrast_dn = 6000.0; // DN
  bool scratch_dark = false;           // scratches through the emulsion show bright on a negative
  std::vector<std::string> missing_crosses;   // reseau ids not rendered (still in the truth file, flagged)
  std::vector<std::string> damaged_crosses;   // reseau ids rendered with part of the arms removed
  double damage_fraction = 0.3;               // 0..1 of the arms' area removed
  std::vector<SpecFalseMark> false_marks;     // cross-like marks not in any definition
  std::optional<double> saturation_dn;        // DN; clip level below full scale
};

struct SimulationSpec {
  std::string origin;       // the file (for messages)
  std::string name;         // output base name
  std::string description;
  std::string camera;       // camera definition name
  uint64_t seed = 1;        // every random choice derives from it
  SpecOutput output;
  SpecThermal thermal;
  SpecEmulsion emulsion;
  FilmDeformationStep film;  // (normalization_mm defaults to half the format's larger side)
  bool film_normalization_given = false;
  SpecScanner scanner;
  SpecMarkLook reseau;
  SpecMarkLook fiducials;
  SpecPasspoints passpoints;
  SpecStars stars;
  SpecStarField star_field;
  SpecBackground background;
  SpecNoise noise;
  SpecDefects defects;
};

// Parses spec text; `origin` names it in errors: Error(origin, "line N: what is wrong").
SimulationSpec ParseSimulationSpec(const std::string& text, const std::string& origin);
// Reads a spec file (an unreadable file is an Error naming it).
SimulationSpec ReadSimulationSpec(const std::string& path);

}  // namespace platemeter::sim
