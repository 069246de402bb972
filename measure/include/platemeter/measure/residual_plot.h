#pragma once
// The reseau residual vector plot (PNG, cairo): each cross at its master-grid
// position with its residual (grid - F^-1(measured)) drawn as an arrow,
// magnified so that `scale_bar_um` spans a tenth of the plot; rejected crosses
// in red, crosses beyond the tolerance in orange, a scale bar and a title.
#include <string>
#include <vector>

#include "platemeter/measure/reseau_fit.h"

namespace platemeter {

struct ResidualPlotOptions {
  int size_px = 800;           // px; the square image's side
  double scale_bar_um = 0.0;   // um; the scale bar's length (0: about 2 x the largest used residual, rounded)
  double tolerance_um = 5.0;   // um; residuals beyond this are drawn orange
  std::string title;           // drawn at the top
  bool Check(std::string* why) const;
};

// Throws Error(path, reason) when the file cannot be written.
void WriteResidualPlotPng(const std::string& path, const std::vector<ReseauObservation>& observations,
                          const ReseauFit& fit, const ResidualPlotOptions& options = {});

}  // namespace platemeter
