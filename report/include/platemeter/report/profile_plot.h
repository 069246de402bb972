#pragma once
// Profile curves y(x) with a one-sigma envelope: the band y - sigma .. y + sigma
// shaded under each curve (the distortion profiles over the radius with their
// propagated sigmas), axes titled with their units.
#include <string>
#include <vector>

#include "platemeter/report/plot.h"

namespace platemeter::report {

struct ProfileSeries {
  std::string name;            // legend
  std::vector<double> x;       // increasing
  std::vector<double> value;   // y at each x
  std::vector<double> sigma;   // one sigma at each x (>= 0; empty: no band)
  unsigned rgb = 0x1f4e9a;     // the curve's colour; the band is a pale version of it
};

struct ProfilePlotOptions {
  std::string title;
  std::string x_label = "r (mm)";
  std::string y_label = "distortion (µm)";
  int width_px = 640;
  int height_px = 420;
};

struct ProfilePlot {
  RenderedPlot files;
  PlotFrame frame;
  // Per series and sample: the band's half height as drawn, px (= sigma x frame.PxPerY()).
  std::vector<std::vector<double>> band_half_height_px;
};

ProfilePlot DrawProfilePlot(const std::vector<ProfileSeries>& series, const ProfilePlotOptions& options);

}  // namespace platemeter::report
