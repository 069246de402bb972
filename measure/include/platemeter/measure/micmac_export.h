#pragma once
// Export of measured image points to MicMac's MeasuresIm XML (the format of
// SaisieAppuisInit / ReducHom image measures):
//   <SetOfMesureAppuisFlottants>
//     <MesureAppuiFlottant1Im>
//       <NameIm>scan.tif</NameIm>
//       <OneMesureAF1I><NamePt>X1Y1</NamePt><PtIm>col row</PtIm></OneMesureAF1I> ...
// PtIm is in pixels, x = column, y = row, the centre of the top-left pixel at
// (0, 0) (core/pixel.h; MicMac's image convention).
#include <string>

#include "platemeter/measure/measurement_file.h"

namespace platemeter {

struct MicMacExportOptions {
  bool include_rejected = false;  // also points with status rejected (never missing/predicted ones)
  bool Check(std::string* why) const { return true; }
};

// The XML text for one image; points without pixel positions are skipped.
// NameIm is the file name of the header's scan_file (or `image_name` if given).
std::string FormatMicMacMeasures(const MeasurementFile& file, const std::string& image_name = "",
                                 const MicMacExportOptions& options = {});
void WriteMicMacMeasures(const std::string& path, const MeasurementFile& file, const std::string& image_name = "",
                         const MicMacExportOptions& options = {});

}  // namespace platemeter
