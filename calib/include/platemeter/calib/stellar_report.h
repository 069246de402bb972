#pragma once
// The outputs of a stellar calibration job (docs/stellar-job.md, "Outputs"):
//   calibration.json   every plate (seed 001 Table 2) and combination (Table 3),
//                      plate frame (and for orbigon-11 seed 001's printed
//                      frame), statistics, rank
//   report.md          Tables 2 and 3 in seed 001's form (orbigon-11: printed
//                      frame, um; other lens models: plate frame, own names)
//   residuals.csv      one row per image: plate, image, star, status, vx, vy (um), reason
//   identification.csv one row per detected star: plate, star key, catalog key, status
//   extra_files        e.g. report.html, certificate.html and plots/ (report/stellar_html_report.h)
//   camera-NAME-stellar.toml  per camera: the calibrated camera (its last
//                      combination, or its first plate) as a definition `measure` loads
// With plates of several cameras sharing exposures, calibration.json and
// report.md add the cameras' joint adjustment and interlock (seed 004).
// Every text is formatted before the first file is written.
#include <string>
#include <vector>

#include "platemeter/calib/stellar_job.h"
#include "platemeter/core/text_document.h"

namespace platemeter {

// The Table-2/3 row of a camera: seed 001's printed (left-handed) frame and
// units: C, xp, yp, xs, ys in um (xs, ys from the reseau centre), K1..K5 as
// printed, Phi_T in degrees.
struct PrintedCamera {
  std::array<double, kStellarCameraParams> value{};
  std::array<double, kStellarCameraParams> sigma{};
};
inline constexpr std::array<const char*, kStellarCameraParams> kPrintedCameraNames = {
    "C_um", "xp_um", "yp_um", "xs_um", "ys_um", "K1", "K2", "K3", "K4", "K5", "Phi_T_deg"};
PrintedCamera ToPrinted(const StellarCamera& values, const StellarCamera& sigmas);

// A camera as the reports print it: orbigon-11 in seed 001's printed frame
// and units (ToPrinted); another lens model in the plate frame with its own
// parameter names and units (seed 001's printed frame is seed 001's only).
struct ReportedCamera {
  std::string frame;                  // "seed 001's printed frame" or "plate frame"
  std::vector<std::string> names;
  std::vector<double> value, sigma;
  std::vector<bool> exponent;         // lens coefficients: mantissa and power of ten
  int decimals = 2;                   // the other rows' decimals
};
ReportedCamera ReportCamera(DistortionModelId lens, const StellarCamera& values, const StellarCamera& sigmas);

std::string FormatStellarJson(const StellarJob& job, const StellarJobResult& result);
// report.md's content as blocks (also the HTML report's tables, report/stellar_html_report.h).
TextDocument StellarReportDocument(const StellarJob& job, const StellarJobResult& result);
std::string FormatStellarMarkdown(const StellarJob& job, const StellarJobResult& result);
std::string FormatStellarResidualsCsv(const StellarJobResult& result);
std::string FormatIdentificationCsv(const StellarJobResult& result);
// Camera `camera` (index in job.cameras) calibrated: its definition with a new
// lens of the job's lens model (orbigon-11 in seed 001's printed frame, the
// others in the plate frame with the definition keys of docs/definitions.md)
// and sigmas, from its last combination or its first plate.
CameraDefinition StellarCameraDefinition(const StellarJob& job, const StellarJobResult& result, int camera);

// Writes the outputs into `dir` (created), with `extra_files` (relative path,
// bytes; e.g. the HTML report) in the same set; returns the paths written.
std::vector<std::string> WriteStellarOutputs(const std::string& dir, const StellarJob& job,
                                             const StellarJobResult& result,
                                             const std::vector<std::pair<std::string, std::string>>& extra_files = {});

}  // namespace platemeter
