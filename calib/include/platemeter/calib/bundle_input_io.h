#pragma once
// Everything the self-calibrating bundle adjustment (bundle_adjustment.h) reads,
// checked before it runs (docs/bundle-job.md):
//   - the observations CSV  frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm
//   - the ground points CSV point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m
//   - observations taken from measurement files (one frame per file)
//   - the checks that clean a BundleInput (points seen once, thin frames, ...)
//   - the job file (TOML) that names all of it with the cameras, frames,
//     distances and the adjustment's options.
// Bad input throws platemeter::Error(file, "line N[, column C (name)]: what is
// wrong"); what the checks leave out is listed as BundleWarning (item, reason).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "platemeter/calib/bundle_input.h"
#include "platemeter/calib/bundle_options.h"
#include "platemeter/core/point_status.h"
#include "platemeter/grids/definitions.h"
#include "platemeter/measure/measurement_file.h"

namespace platemeter {

class DefinitionRegistry;

// Something the checks (or the job reader) left out or changed, for the CLI to
// print and the report to list. item: "point P17", "frame 9515", "ground point
// G4", "distance 9515-9535", "camera hasselblad"; reason: one sentence.
struct BundleWarning {
  std::string item;
  std::string reason;
};

// ---------------------------------------------------------------------------
// CSV files. Header line required (exactly the column names below); lines
// starting with '#' are comments anywhere; blank lines are skipped; spaces
// around a field are ignored; a trailing '\r' and a UTF-8 byte order mark
// are accepted. Numbers as
// std::from_chars reads them (a leading '+' is accepted), finite.

// Observations: frame,point_id,x_mm,y_mm,sigma_x_mm,sigma_y_mm. Camera frame, x
// right, y up, mm; sigmas > 0. (frame, point_id) unique. Each record's origin is
// "<origin>:<line>".
constexpr std::array<const char*, 6> kObservationColumns = {"frame",   "point_id",   "x_mm",
                                                           "y_mm",    "sigma_x_mm", "sigma_y_mm"};
std::vector<ImageObservation> ParseObservationsCsv(const std::string& text, const std::string& origin);
std::vector<ImageObservation> ReadObservationsCsv(const std::string& path);
// The file's text, numbers in their shortest exact form (std::to_chars), so
// reading it back gives the same doubles. Throws Error("observations", reason)
// for what the reader would refuse (empty ids, an id with a comma, quote or
// newline, surrounding spaces or a leading '#', non-finite numbers, sigmas not
// > 0, a duplicated (frame, point_id)).
std::string FormatObservationsCsv(const std::vector<ImageObservation>& observations);
// Written atomically (core/atomic_file.h); errors name `path`.
void WriteObservationsCsv(const std::string& path, const std::vector<ImageObservation>& observations);

// Ground points: point_id,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m. Object
// frame, m. Per axis sigma: empty = free (the coordinate is an approximation),
// 0 = fixed, > 0 = weighted. point_id unique.
constexpr std::array<const char*, 7> kGroundPointColumns = {"point_id",  "x_m",       "y_m",      "z_m",
                                                           "sigma_x_m", "sigma_y_m", "sigma_z_m"};
std::vector<GroundPoint> ParseGroundPointsCsv(const std::string& text, const std::string& origin);
std::vector<GroundPoint> ReadGroundPointsCsv(const std::string& path);
std::string FormatGroundPointsCsv(const std::vector<GroundPoint>& points);  // Error("ground points", ...)
void WriteGroundPointsCsv(const std::string& path, const std::vector<GroundPoint>& points);

// ---------------------------------------------------------------------------
// Observations from a measurement file (measure/measurement_file.h): one frame
// per file. Takes every point of the selected kinds with status `measured` and
// x_mm, y_mm, sigma_x_mm, sigma_y_mm all present; the point id is the file's
// id. Reseau crosses and fiducials are plate references (they define the plate
// frame the mm coordinates are in), not object points, so the default is
// passpoints only.
struct MeasurementObservationOptions {
  std::string frame_id;  // "" = the file's plate_id (an error if that is empty too)
  std::vector<PointKind> kinds = {PointKind::kPasspoint};
};
// `origin` names the file; with `text` (the file's text) each record's origin is
// "<origin>:<line>", else "<origin>". A selected point with a zero sigma is an
// error (file and line); measured points of a selected kind without plate
// coordinates or sigmas are left out with one warning per file in `warnings`
// (if given). Two selected kinds sharing an id is an error.
std::vector<ImageObservation> ObservationsFromMeasurementFile(const MeasurementFile& file,
                                                              const std::string& origin,
                                                              const MeasurementObservationOptions& options = {},
                                                              std::vector<BundleWarning>* warnings = nullptr,
                                                              const std::string* text = nullptr);
std::vector<ImageObservation> ReadObservationsFromMeasurementFile(const std::string& path,
                                                                  const MeasurementObservationOptions& options = {},
                                                                  std::vector<BundleWarning>* warnings = nullptr);

// ---------------------------------------------------------------------------
// The checks before the adjustment (docs/bundle-job.md, "Checks").
struct BundleInputCheckOptions {
  // A frame that is not fixed has 6 orientation unknowns; each point gives 2
  // equations, so fewer than 3 points cannot determine it (and 3 cannot check
  // it). Fixed frames have no unknowns and are exempt.
  int min_points_per_frame = 3;
  bool Check(std::string* why) const;
};

struct CheckedBundleInput {
  BundleInput input;                   // cleaned: what the adjustment should get
  std::vector<BundleWarning> warnings;  // what was left out, and why, in the order decided
};

// Errors (throw Error naming the record's file and line where it has an
// origin, else "bundle input"): empty or duplicated camera names, frame ids or
// ground point ids; a frame naming an unknown camera; an observation naming a
// frame no frame lists (when frames are listed); a duplicated (frame, point)
// observation; non-finite values; image sigmas not > 0; negative ground sigmas;
// a-priori sigmas without a-priori values; a fixed frame without position and
// angles; a position covariance that is not symmetric positive definite; a
// distance naming neither a frame nor a point, or both.
// With no frames listed and one camera, a frame per observed frame id is made
// (camera = that camera, no approximations); with no frames and several
// cameras it is an error.
// Then, repeated until nothing changes (leaving a frame out can leave a point
// seen once, and the other way round): a point seen in one frame only that is
// not a control point (no a-priori sigma on any axis) nor named by a distance
// is left out (warning); a frame that is not fixed and sees fewer than
// min_points_per_frame points is left out with its observations (warning); a
// fixed frame seeing no point and named by no distance is left out (warning).
// Afterwards: a ground point observed in no kept frame is left out (warning),
// unless a distance ties it to the network (a kept frame or observed point),
// which is the only way it still acts on the datum; a distance whose ends are
// not both kept is left out (warning); a camera no kept frame uses is left out
// (warning).
CheckedBundleInput CheckBundleInput(const BundleInput& input, const BundleInputCheckOptions& options = {});

// ---------------------------------------------------------------------------
// A camera definition (grids/) as the bundle's initial camera: c, xp, yp and
// BrownAffine's seven from its lens calibration where it has one, converted:
//   brown-affine: as published;
//   brown-balanced (seed 000 eq. 14): exact, c = c' / (1 + k0'), k_i = k_i' /
//     (1 + k0'), p_i = p_i' / (1 + k0') (the linear term is a scale of c);
//   smac-radial-decentering (seed 004): exact for K1..K3 and J1, theta0
//     (p1 = -J1 sin theta0, p2 = J1 cos theta0); J2 (an r^4 decentering profile
//     BrownAffine lacks) is dropped, with a warning giving its size at the
//     format corner when it is not zero;
//   other models (orbigon-11): a least-squares fit over the format (c, k1..b2),
//     with a warning giving the fit's RMS and largest residual.
// Without a lens: c = nominal principal distance, zero distortion. Every state
// is fixed (CameraSetup's default); the format comes from the definition.
// `name` is the CameraSetup's name (the definition's if empty).
CameraSetup CameraSetupFromDefinition(const CameraDefinition& definition, const std::string& name = "",
                                      std::vector<BundleWarning>* warnings = nullptr);

// ---------------------------------------------------------------------------
// The bundle job file (TOML, docs/bundle-job.md).
struct BundleOutputSettings {
  std::string title;                         // report title ("" = the job file's name)
  std::optional<double> balance_radius_mm;   // mm; radial distortion reported balanced (zero) at this radius
  std::optional<double> export_pixel_size_um;                // um; pixel camera export (with the image size)
  std::optional<std::array<int, 2>> export_image_size_px;  // px; width, height
};

struct BundleJob {
  std::string source;  // the job file
  BundleInput input;   // as read: not yet checked (CheckBundleInput)
  BundleOptions options;
  BundleInputCheckOptions check_options;
  BundleOutputSettings output;
  std::vector<BundleWarning> warnings;  // from reading (camera conversions, measurement files)
};

// Reads the job and every file it names (relative paths are relative to the
// job file's folder). Throws Error(file, "line N: ...") for unknown keys, wrong
// types, bad values, and for errors in the CSV and measurement files (naming
// those). Camera `from` names are looked up in `registry` (built-ins by default).
BundleJob ReadBundleJob(const std::string& path);
BundleJob ReadBundleJob(const std::string& path, const DefinitionRegistry& registry);

}  // namespace platemeter
