#pragma once
// The simulator's true geometry chain (docs/simulator.md, "Geometry chain"):
// where a point of the master grid (or any point given in plate millimetres)
// lands on the scan. Each step is a small struct with its parameters and
// Forward / Inverse / Jacobian; GeometryChain composes them:
//
//   master grid (mm, at the calibration temperature)
//     -> ThermalStep        scale 1 + alpha (T - T_cal) about the grid origin
//     -> EmulsionDepthStep  exact refraction of the converging ray into the emulsion
//     -> FilmDeformationStep affine + smooth non-linear displacement (um)
//     -> ScannerStep        mirror, orientation, rotation, non-orthogonality, pixel size, offset
//   scan pixels (core/pixel.h: x = column, y = row down, top-left pixel centre at (0, 0))
//
// Plate coordinates are millimetres, x right, y up (DESIGN.md).
#include <string>
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/measure/emulsion_depth.h"

namespace platemeter::sim {

struct PlatePoint {
  double x_mm = 0.0;
  double y_mm = 0.0;
};

// A 2x2 matrix, row-major: {a00, a01, a10, a11}; as a Jacobian d(out)/d(in).
struct Matrix2 {
  double a[4] = {1.0, 0.0, 0.0, 1.0};
  double operator()(int row, int col) const { return a[2 * row + col]; }
  Matrix2 operator*(const Matrix2& b) const;
  Matrix2 operator*(double s) const;
  double Determinant() const { return a[0] * a[3] - a[1] * a[2]; }
  Matrix2 Inverse() const;  // of a non-singular matrix
};

// The reseau glass (and the photographic glass plate in contact with it)
// expands uniformly about the grid origin.
struct ThermalStep {
  double temperature_degC = 20.0;              // degC; temperature of the glass
  double calibration_temperature_degC = 20.0;  // degC; where the master-grid values hold
  double expansion_per_degC = 8.1e-6;          // 1/degC; linear expansion of the glass (camera definition)
  double Scale() const { return 1.0 + expansion_per_degC * (temperature_degC - calibration_temperature_degC); }
  PlatePoint Forward(PlatePoint p) const;
  PlatePoint Inverse(PlatePoint p) const;
  Matrix2 Jacobian(PlatePoint p) const;
  bool Check(std::string* why) const;
};

// The reseau, on the glass in contact with the emulsion, shadows the emulsion
// along the converging ray from the rear nodal point (height c above the
// emulsion surface, foot at the principal point). The ray meets the surface at
// radius r with incidence angle theta (tan theta = r / c), refracts into the
// emulsion of index n (sin theta' = sin theta / n, the air-glass-emulsion
// faces being parallel), and the image centroid at depth d lies at
//   r' = r + d tan theta' = r + d sin(theta) / sqrt(n^2 - sin^2 theta).
// For small angles this is the scale 1 + d / (n c) (EquivalentScale).
struct EmulsionDepthStep {
  double depth_um = 0.0;                // um; depth of the image centroid below the emulsion surface
  double refractive_index = 1.65;       // of the emulsion
  double principal_distance_mm = 80.2;  // mm; rear nodal point above the emulsion surface
  PlatePoint principal_point_mm;        // mm; foot of the perpendicular from the rear nodal point

  // The radial model (measure/emulsion_depth.h) with these parameters.
  EmulsionDepthModel Model() const;

  // r' - r in mm at the radius r_mm from the principal point.
  double RadialShiftMm(double r_mm) const;
  // The small-angle scale 1 + d / (n c).
  double EquivalentScale() const;
  // The depth (um) whose small-angle scale is `scale`: (scale - 1) n c.
  static double DepthUmFromEquivalentScale(double scale, double refractive_index, double principal_distance_mm);
  // The scale a least-squares fit (scale only, about the principal point) of
  // the displaced points to `points` finds: sum(p . f(p)) / sum(|p|^2).
  double FittedScale(const std::vector<PlatePoint>& points) const;
  // The depth (um) for which FittedScale(points) equals `scale` (the shift is
  // linear in the depth, so this is exact).
  double DepthUmFromFittedScale(double scale, const std::vector<PlatePoint>& points) const;

  PlatePoint Forward(PlatePoint p) const;
  PlatePoint Inverse(PlatePoint p) const;  // Newton on the radius
  Matrix2 Jacobian(PlatePoint p) const;
  bool Check(std::string* why) const;
};

// displacement (um) = (amplitude_x_um, amplitude_y_um) * sin(2 pi s / wavelength_mm + phase),
// s = the plate position projected on the direction direction_deg (from +x toward +y).
struct FilmWave {
  double amplitude_x_um = 0.0;
  double amplitude_y_um = 0.0;
  double wavelength_mm = 100.0;
  double direction_deg = 0.0;
  double phase_deg = 0.0;
};

// displacement (um) = (amplitude_x_um, amplitude_y_um) * (x / R)^power_x * (y / R)^power_y,
// R = FilmDeformationStep::normalization_mm.
struct FilmPolynomialTerm {
  int power_x = 0;
  int power_y = 0;
  double amplitude_x_um = 0.0;
  double amplitude_y_um = 0.0;
};

// Film (or emulsion) deformation between exposure and scanning:
//   p' = p + 1e-6 A p + 1e-3 (shift_um + sum of waves + sum of polynomial terms)   [mm]
struct FilmDeformationStep {
  double affine_ppm[4] = {0.0, 0.0, 0.0, 0.0};  // ppm (um per m); A row-major: {xx, xy, yx, yy}
  double shift_um[2] = {0.0, 0.0};              // um
  double normalization_mm = 57.0;               // mm; R of the polynomial terms (half the format)
  std::vector<FilmWave> waves;
  std::vector<FilmPolynomialTerm> polynomial;

  // The displacement at p in um.
  PlatePoint DisplacementUm(PlatePoint p) const;
  PlatePoint Forward(PlatePoint p) const;
  PlatePoint Inverse(PlatePoint p) const;  // Newton
  Matrix2 Jacobian(PlatePoint p) const;
  bool Check(std::string* why) const;
};

// How the plate lies on the scanner and how the scanner samples it. In order:
// mirror (emulsion-down scan: the plate seen from the back, plate x reversed),
// orientation (the plate's image appears rotated counter-clockwise by
// orientation_deg in the scan: 90 puts plate +x toward the top of the scan),
// a small counter-clockwise rotation, then the scanner's oblique axes: its y
// axis makes the angle 90 deg + eps with its x axis (eps =
// non_orthogonality_arcsec), so a rotated point a has the scanner coordinates
// X = a_x + tan(eps) a_y, Y = a_y / cos(eps), and
//   column = origin_px.x + X / pixel_width, row = origin_px.y - Y / pixel_height
// (rows grow downward, plate y up).
struct ScannerStep {
  double pixel_size_um = 25.0;          // um; pixel width (along the rows, scanner x)
  double pixel_aspect = 1.0;            // pixel height / pixel width
  double rotation_deg = 0.0;            // deg; counter-clockwise, after the orientation
  double non_orthogonality_arcsec = 0.0;  // arcsec; eps, the scanner y axis's deviation from 90 deg
  int orientation_deg = 0;              // 0, 90, 180 or 270
  bool mirrored = false;                // emulsion-down scan
  PixelPoint origin_px;                 // px; where the plate origin lands

  // d(pixel)/d(plate mm); the step is linear.
  Matrix2 PixelPerMm() const;
  PixelPoint Forward(PlatePoint p) const;
  PlatePoint Inverse(PixelPoint q) const;
  bool Check(std::string* why) const;
};

struct GeometryChain {
  ThermalStep thermal;
  EmulsionDepthStep emulsion;
  FilmDeformationStep film;
  ScannerStep scanner;

  // Master-grid (plate) millimetres -> scan pixels, and back.
  PixelPoint PixelFromPlate(PlatePoint p) const;
  PlatePoint PlateFromPixel(PixelPoint q) const;
  // d(pixel)/d(plate mm) at p (the product of the steps' Jacobians).
  Matrix2 PixelFromPlateJacobian(PlatePoint p) const;
  // The local map of a mark's own um frame (u right, v up on the plate) to
  // pixels at p: PixelFromPlateJacobian(p) / 1000 (sim::SceneMark::px_from_um).
  Matrix2 PxFromUm(PlatePoint p) const;

  bool Check(std::string* why) const;
  // Every step's parameters as JSON (docs/simulator.md, "The chain file"),
  // and back (throws Error(origin, reason) on malformed text).
  std::string ToJson() const;
  static GeometryChain FromJson(const std::string& text, const std::string& origin);
};

}  // namespace platemeter::sim
