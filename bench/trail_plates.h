#pragma once
// The family of simulated duty-cycle plates bench_trails runs (#27): what real
// plates vary -- site and date (latitudes 25-50 N, spring and autumn, early and
// late in the night), the cone's roll and pointing off the zenith, PSF width,
// pixel size (10-20 um), noise, magnitude limit (V = 6-8), the break (7-10 min)
// and the leading-dash program. "tune" plates may be looked at while changing
// the decoder; "report" plates are held out: their figures are reported, never
// tuned on. A held-out plate that shows a failure becomes a tuning plate when it
// is looked into, and a new plate is held out in its place. The benchmark plate
// (Beltsville, seed 001) is the first.
#include <cmath>
#include <string>
#include <vector>

namespace platemeter::bench {

struct TrailPlate {
  std::string name;
  std::string role;                 // "tune" or "report"
  double latitude_deg = 0, longitude_deg = 0;
  std::string start_utc;            // the first shutter opening
  double roll_deg = 0;              // the cone's roll about its axis
  double axis_altitude_deg = 90;    // 90: pointed to the zenith
  double axis_azimuth_deg = 0;
  double pixel_um = 20;             // the scan's pixel
  double fwhm_um = 30;              // the lens's star image (before the scanner's blur)
  double blur_um = 8;               // the scanner's Gaussian blur sigma
  double sensor_dn = 30, grain_dn = 60;  // noise sigmas
  double mag_limit = 8;             // catalog stars to this V
  double break_s = 480;             // between trails
  std::vector<int> leading_dashes{2, 3, 4, 5};

  // The image's FWHM with the scanner's blur, px.
  double FwhmPx() const { return std::sqrt(fwhm_um * fwhm_um + std::pow(2.3548 * blur_um, 2)) / pixel_um; }
  std::string DashesText() const {  // "2,3,4,5"
    std::string text;
    for (int n : leading_dashes) text += (text.empty() ? "" : ",") + std::to_string(n);
    return text;
  }
};

// Every plate of the family, the benchmark plate first (header-only: every bench/*.cpp is its own program).
inline const std::vector<TrailPlate>& TrailPlateFamily() {
  // Local solar time = UTC + longitude / 15 h: "early" plates start about 20-21 h, "late" ones 3-4 h.
  static const std::vector<TrailPlate> family = {
      // name, role, lat, lon, start, roll, axis alt, az, pixel, fwhm, blur, sensor, grain, V, break, program
      {"beltsville-1972-05", "tune", 39.03, -76.93, "1972-05-12T05:30:00Z", 180, 90, 0, 20, 30, 8, 30, 60, 8.0, 480,
       {2, 3, 4, 5}},
      {"miami-1971-10-early", "tune", 25.8, -80.2, "1971-10-20T01:30:00Z", 35, 80, 120, 15, 26, 7, 30, 80, 7.0, 540,
       {3, 4, 5, 2}},
      {"seattle-1973-03-late", "tune", 47.6, -122.3, "1973-03-22T11:40:00Z", 275, 85, 300, 12.5, 34, 6, 40, 90, 6.5,
       420, {5, 4, 3, 2}},
      {"denver-1972-09-early", "tune", 39.7, -105.0, "1972-09-15T03:00:00Z", 60, 88, 10, 20, 36, 9, 25, 50, 7.5, 600,
       {2, 3, 4, 5}},
      {"tucson-1971-11-late", "report", 32.2, -110.9, "1971-11-03T10:50:00Z", 95, 76, 210, 10, 30, 6, 30, 70, 6.0, 600,
       {2, 4, 3, 5}},
      {"paris-1974-04-early", "tune", 48.8, 2.3, "1974-04-10T20:30:00Z", 140, 90, 0, 20, 40, 8, 30, 60, 7.5, 450,
       {4, 5, 2, 3}},
      {"cairo-1972-10-late", "tune", 30.0, 31.2, "1972-10-28T01:30:00Z", 320, 82, 45, 16, 28, 7, 20, 40, 8.0, 510,
       {3, 2, 5, 4}},
      {"quebec-1973-05-late", "report", 46.8, -71.2, "1973-05-25T08:00:00Z", 210, 78, 160, 12.5, 32, 7, 35, 100, 7.0,
       570, {2, 3, 4}},
      // Held out at stop 47, when Paris and Cairo (held out until then) became tuning plates; tuning plates
      // since stop 49, when their wrong tags were looked into.
      {"lisbon-1973-09-late", "tune", 38.7, -9.1, "1973-09-18T04:15:00Z", 250, 84, 75, 16, 32, 7, 30, 70, 7.5, 500,
       {3, 5, 2, 4}},
      {"houston-1974-03-early", "tune", 29.8, -95.4, "1974-03-16T03:00:00Z", 15, 87, 250, 20, 34, 8, 25, 60, 8.0,
       420, {4, 3, 2, 5}},
      // Held out from stop 49, when Lisbon and Houston became tuning plates; Munich a tuning plate since stop
      // 50, Delhi since stop 51, when their wrong tags were looked into.
      {"munich-1972-10-early", "tune", 48.1, 11.6, "1972-10-05T19:45:00Z", 300, 83, 20, 14, 30, 7, 30, 70, 7.0,
       480, {5, 2, 4, 3}},
      {"delhi-1973-04-late", "tune", 28.6, 77.2, "1973-04-14T22:20:00Z", 120, 86, 170, 18, 34, 8, 25, 55, 7.5,
       540, {2, 5, 3, 4}},
      // Held out from stop 50, when Munich became a tuning plate; a tuning plate since stop 51, when its wrong
      // tags were looked into.
      {"kyoto-1971-04-late", "tune", 35.0, 135.8, "1971-04-20T17:30:00Z", 165, 81, 230, 17, 33, 8, 28, 65, 7.5,
       450, {4, 2, 5, 3}},
      // Held out from stop 51, when Kyoto and Delhi became tuning plates.
      {"athens-1974-10-early", "report", 37.97, 23.72, "1974-10-08T18:30:00Z", 75, 84, 140, 13, 31, 7, 32, 75, 7.0,
       600, {5, 3, 4, 2}},
      {"madrid-1973-03-early", "report", 40.4, -3.7, "1973-03-10T20:45:00Z", 200, 88, 60, 15.5, 29, 7, 28, 70, 7.5,
       570, {4, 3, 5, 2}},
  };
  return family;
}

// The simulation spec of a plate (samples/specs/orbigon-stellar.toml's camera, film, thermal and emulsion
// effects; no reseau defects; the plate's site, time, pointing, program, image and noise).
inline std::string TrailPlateSpec(const TrailPlate& p, double reference_peak_dn) {
  std::string dashes = "[" + p.DashesText() + "]";
  auto num = [](double v) { return std::to_string(v); };
  return R"(
name = "orbigon-trails"
camera = "orbigon"
seed = 1
[output]
pixel_size_um = )" + num(p.pixel_um) + R"(
margin_mm = 3.0
bits = 16
[thermal]
temperature_degC = 22.0
[emulsion]
depth_um = 21.0
refractive_index = 1.65
[film]
affine_ppm = [3.0, 0.0, 0.0, 2.0]
[scanner]
non_orthogonality_arcsec = -4.3
rotation_deg = 0.1
orientation_deg = 180
mirrored = true
[marks.reseau]
polarity = "bright"
contrast_dn = 12000.0
[stars]
reference_magnitude = 5.0
reference_peak_dn = )" + num(reference_peak_dn) + R"(
fwhm_um = )" + num(p.fwhm_um) + R"(
[star_field]
latitude_deg = )" + num(p.latitude_deg) + R"(
longitude_deg = )" + num(p.longitude_deg) + R"(
height_m = 50.0
start_utc = ")" + p.start_utc + R"("
temperature_degC = 11.7
relative_humidity = 0.7
wavelength_um = 0.45
roll_deg = )" + num(p.roll_deg) + R"(
axis_altitude_deg = )" + num(p.axis_altitude_deg) + R"(
axis_azimuth_deg = )" + num(p.axis_azimuth_deg) + R"(
magnitude_limit = )" + num(p.mag_limit) + R"(
exposure = "duty_cycle"
leading_dashes = )" + dashes + R"(
break_s = )" + num(p.break_s) + R"(
reference_exposure_s = 10.0
[background]
level_dn = 40000.0
vignetting_fraction = 0.12
vignetting_radius_mm = 80.6
[noise]
blur_sigma_um = )" + num(p.blur_um) + R"(
sensor_sigma_dn = )" + num(p.sensor_dn) + R"(
grain_sigma_dn = )" + num(p.grain_dn) + R"(
)";
}

}  // namespace platemeter::bench
