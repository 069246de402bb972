#pragma once
// The stellar calibration's HTML report (issue #25; docs/report.md): report.html
// with an index, seed 001 Tables 2 and 3 (and seed 004's A.4-A.6) as HTML
// tables (the same document as report.md, stellar_report.h
// StellarReportDocument), the plots of seed 001 Table 4 for every plate and
// every combination, and certificate.html (certificate.h).
//   histograms of the x, y and x-and-y residuals over the normal curve, per
//   plate and pooled per combination; the star images measured, one colour per
//   trail (per plate, and all plates of a combination together); the residual
//   vectors total, radial and tangential, one colour per trail, one vector per
//   subtrail of five images; the distortion fields total, radial symmetric and
//   decentering with the axis of maximum tangential distortion drawn through
//   the point of symmetry; the profiles (radial at the calibrated focal length,
//   transformed to equal lobes, decentering) with one-sigma envelopes. The
//   plate plots are keyed to the focal plane by the corner reseau numbers.
#include <string>
#include <utility>
#include <vector>

#include "platemeter/calib/stellar_job.h"
#include "platemeter/grids/definitions.h"

namespace platemeter::report {

struct StellarHtmlOptions {
  int subtrail_images = 5;      // images averaged into one residual vector (seed 001: five)
  int field_grid = 15;          // distortion vectors across the format
  int profile_samples = 60;     // distances of the profile curves, 0 to the format's corner
  int max_vectors_per_panel = 3000;
  bool Check(std::string* why) const;
};

// Every file of the report, formatted in memory: ("report.html", page),
// ("certificate.html", page), ("plots/NAME.png", bytes), ("plots/NAME.svg", bytes), ...
// for WriteStellarOutputs' extra_files. `grids` per camera (job.cameras order):
// its master grid for the corner reseau numbers, or nullptr.
std::vector<std::pair<std::string, std::string>> FormatStellarHtmlReport(
    const StellarJob& job, const StellarJobResult& result, const std::vector<const MasterGrid*>& grids,
    const StellarHtmlOptions& options = {});

}  // namespace platemeter::report
