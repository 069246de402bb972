// RunValidate (measure_run.h): the reseau check alone, `platemeter validate`.
#include "measure_prepare.h"
#include "measure_report.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/output_set.h"
#include "platemeter/measure/residual_plot.h"
#include "platemeter/pipeline/measure_run.h"

namespace platemeter::pipeline {

void RunValidate(const MeasureRequest& request, const DefinitionRegistry& registry, std::ostream& console) {
  CheckMeasureOptions(request);
  const std::string stem = PlateStem(request.detect.scan);
  const std::string json_name = stem + ".validate.json", png_name = stem + ".residuals.png";
  OutputSet outputs(request.out_dir, {json_name, png_name});  // before any work: a bad folder fails at once
  std::string messages;
  PreparedMeasurement p = PrepareMeasurement(request, registry, false, &messages);
  console << messages;
  const PlateCorrectionReport report = CorrectPlate(&p.file, *p.grid, p.options);
  outputs.Write(json_name, [&](const std::string& path) {
    WriteFileAtomically(path, ValidationJson(report, request.tolerance_um).dump(2) + "\n");
  });
  ResidualPlotOptions plot;
  plot.tolerance_um = request.tolerance_um;
  outputs.Write(png_name, [&](const std::string& path) { WriteResidualPlotPng(path, report.observations, report.fit, plot); });
  outputs.Commit();
  const std::string json = outputs.FinalPath(json_name), png = outputs.FinalPath(png_name);
  const ReseauFit& f = report.fit;
  console << "reseau fit (" << ReseauFitModelName(f.model) << "): " << f.used << " crosses, " << f.rejected
          << " rejected, rms " << f.rms_mm * 1e3 << " um\n"
          << "scale x " << f.scale_x.value << " +- " << f.scale_x.sigma << ", y " << f.scale_y.value << " +- "
          << f.scale_y.sigma << ", non-orthogonality " << f.non_orthogonality_rad.value * kRadToArcsec << " +- "
          << f.non_orthogonality_rad.sigma * kRadToArcsec << " arcsec\n"
          << "scale discrepancy " << (f.mean_scale.value - 1.0) * 1e6 << " +- " << f.mean_scale.sigma * 1e6
          << " ppm, as emulsion depth " << report.emulsion_depth_reading_um.value << " +- "
          << report.emulsion_depth_reading_um.sigma << " um\n"
          << json << "\n" << png << "\n";
}

}  // namespace platemeter::pipeline
