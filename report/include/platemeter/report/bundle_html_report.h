#pragma once
// The bundle adjustment's HTML report (issue #25; docs/report.md): report.html
// with an index, seed 000 Tables 1-4 and the rest of report.md as HTML tables
// (the same document, bundle_report.h BundleReportDocument), and the plots it
// links, each as plots/NAME.png (shown) and plots/NAME.svg (linked):
//   residual vectors per frame (one plot per frame, or grids of small multiples
//   for many frames, one scale for all), the network in plan (X-Y) and side
//   (X-Z) view with the rays, the number of rays per point, the inner cone's
//   correlation heat map, the balanced radial and the decentering profiles with
//   their one-sigma envelopes, the distortion vector field over the format, and
//   the normalized residuals (x and y) over the normal curve N(0, sigma0).
// A self-contained page: inline CSS, relative links, no JavaScript.
#include <string>
#include <utility>
#include <vector>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_report.h"

namespace platemeter::report {

struct BundleHtmlOptions {
  int max_frame_plots = 12;     // up to this many frames: one residual plot each; beyond: grids
  int frames_per_grid = 36;     // small multiples per grid picture
  int max_vectors_per_panel = 3000;  // beyond: residuals aggregated into cells (vector_plot.h)
  int profile_samples = 60;     // radii of the profile curves, 0 to the format's corner
  bool Check(std::string* why) const;
};

// Every file of the report, formatted in memory: ("report.html", page),
// ("plots/NAME.png", bytes), ("plots/NAME.svg", bytes), ... for
// WriteBundleOutputs' extra_files (written with the rest of the set).
// `input` is the adjusted input (the measured image positions of the residuals).
std::vector<std::pair<std::string, std::string>> FormatBundleHtmlReport(const BundleResult& result,
                                                                        const BundleInput& input,
                                                                        const BundleReportOptions& report_options,
                                                                        const BundleHtmlOptions& options = {});

}  // namespace platemeter::report
