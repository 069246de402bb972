#pragma once
// What the calibrate commands do after writing an output set with an HTML
// report: remove an earlier run's plots the new report does not link, and say
// what was written (the plots counted, not listed).
#include <string>
#include <vector>

namespace platemeter::cli {

// Plots of an earlier run that this one did not write (more frames, another
// camera) would sit unlinked beside the new report.html: removed after the new set is in place.
void RemoveStalePlots(const std::string& dir, const std::vector<std::string>& written);

// "wrote PATH" per file, and one line for the plot files.
void PrintWritten(const std::string& dir, const std::vector<std::string>& written);

}  // namespace platemeter::cli
