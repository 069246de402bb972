#pragma once
// A calibration certificate page (certificate.html), in the style of a camera
// calibration laboratory's report of calibration: the calibrated focal length,
// the principal point (and point of symmetry), the radial distortion by field
// angle referred to the calibrated focal length, the decentering, every value
// with its standard error, and the data the calibration used. The bundle's and
// the stellar calibration's HTML reports fill it (bundle_html_report.h,
// stellar_html_report.h); the full reports hold everything else.
#include <string>
#include <vector>

namespace platemeter::report {

struct CertificateElement {
  std::string name;   // e.g. "Calibrated focal length"
  double value = 0.0;
  double sigma = 0.0;  // standard error; 0: not estimated (fixed)
  std::string unit;    // e.g. "mm"
  int decimals = 3;
};

struct CertificateDistortionRow {
  double field_angle_deg = 0.0;
  double distance_mm = 0.0;          // from the point of symmetry: focal length x tan(field angle)
  double radial_um = 0.0, radial_sigma_um = 0.0;
  double decentering_um = 0.0, decentering_sigma_um = 0.0;  // the largest tangential component there
};

struct Certificate {
  std::string camera;                 // name and description
  std::string method;                 // the calibration's kind and source document
  std::vector<CertificateElement> elements;
  std::string distortion_words;       // what the radial column is referred to
  std::vector<CertificateDistortionRow> distortion;
  std::vector<std::string> data_used;  // the plates or frames, points, observations, sigma0 and its dof
  std::string issued_by;               // software and version
};

std::string FormatCertificateHtml(const Certificate& certificate);

// Field angles for the distortion table: every 5 degrees up to the angle of
// `max_distance_mm` at `focal_length_mm`, then that largest angle.
std::vector<double> CertificateFieldAngles_deg(double focal_length_mm, double max_distance_mm);

}  // namespace platemeter::report
