// MicMac MeasuresIm XML export (micmac_export.h).
#include "platemeter/core/markup.h"
#include "platemeter/measure/micmac_export.h"

#include <filesystem>

#include <fmt/format.h>

#include "platemeter/core/atomic_file.h"

namespace platemeter {
namespace {

std::string Escape(const std::string& s) { return EscapeMarkup(s); }

}  // namespace

std::string FormatMicMacMeasures(const MeasurementFile& file, const std::string& image_name,
                                 const MicMacExportOptions& options) {
  const std::string name =
      image_name.empty() ? std::filesystem::path(file.header.scan_file).filename().string() : image_name;
  std::string xml = "<?xml version=\"1.0\" ?>\n<SetOfMesureAppuisFlottants>\n";
  xml += "  <MesureAppuiFlottant1Im>\n";
  xml += "    <NameIm>" + Escape(name) + "</NameIm>\n";
  for (const MeasuredPoint& p : file.points) {
    const bool usable = p.status == PointStatus::kMeasured || p.status == PointStatus::kTruth ||
                        (options.include_rejected && p.status == PointStatus::kRejected);
    if (!usable || !p.x_px || !p.y_px) continue;
    // Shortest exact form of the doubles, as in the measurement file.
    xml += fmt::format("    <OneMesureAF1I>\n      <NamePt>{}</NamePt>\n      <PtIm>{} {}</PtIm>\n    </OneMesureAF1I>\n",
                       Escape(p.id), *p.x_px, *p.y_px);
  }
  xml += "  </MesureAppuiFlottant1Im>\n</SetOfMesureAppuisFlottants>\n";
  return xml;
}

void WriteMicMacMeasures(const std::string& path, const MeasurementFile& file, const std::string& image_name,
                         const MicMacExportOptions& options) {
  WriteFileAtomically(path, FormatMicMacMeasures(file, image_name, options));
}

}  // namespace platemeter
