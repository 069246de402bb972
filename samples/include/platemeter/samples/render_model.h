#pragma once
// The noise-free image of one mark: what a perfect scan of the mark alone
// would record, area-integrated over each pixel (pixel (x, y) covers
// [x-0.5, x+0.5) x [y-0.5, y+0.5), DESIGN.md) and convolved with the scanner's
// Gaussian blur. The renderer sums these over a band; the Cramer-Rao bound and
// detector tests use them directly as the exact local model.
//
// How each mark is formed (shape in the mark's own um frame, mapped to pixels
// by SceneMark::px_from_um about centre_px):
// - kCross: two bars (size_um tip to tip, line_width_um wide) along u and v,
//   value = bar_u + bar_v - overlap square; damage_fraction removes that share of
//   the four arms' area (outside the centre square) as one gap per arm, sizes and
//   positions drawn from `seed`.
// - kDot: disk of diameter size_um. kRing: that disk minus the disk of diameter
//   size_um - 2 line_width_um. kCorner: an L of two arms (length size_um from the
//   corner point, width line_width_um) at corner_angle_rad +- 45 deg from u; the
//   corner point (where the arms' centre lines meet) is centre_px.
// - kPsf: Gaussian PSF (psf_fwhm_um on the plate, mapped through px_from_um, so
//   anisotropic if the map is) convolved with the scanner blur; total flux =
//   amplitude_dn in DN * px^2. kSegment: the same PSF swept uniformly along the
//   segment (segment_u_um, segment_v_um) centred on centre_px, same total flux.
// - kind kDust overrides the shape: a disk of diameter size_um with a soft edge
//   (Gaussian edge, sigma = RenderOptions::dust_edge_fraction * size_um).
// - kind kScratch overrides the shape: a bar size_um long and line_width_um wide
//   along the direction corner_angle_rad (from u toward v) in the mark frame.
// Rectangles and disks have contrast amplitude_dn inside (peak contrast for a
// shape wider than the blur).
//
// Exactness. A rectangle blurred by a Gaussian is a product of erf differences
// in its own axes. Over a pixel each rectangle coordinate is the sum of two
// uniform variables, so where only one factor varies (along a bar, away from
// its ends) or the rectangle is aligned with the pixel axes, the pixel mean is
// exact in closed form (second antiderivative of the normal CDF); likewise the
// inner part of a trail with an isotropic PSF (Gaussian across, 1 along).
// Elsewhere (bar ends, the cross's centre square, disks' rims, anisotropic
// PSFs) a composite Gauss-Legendre rule fine enough for the narrowest Gaussian
// integrates over the pixel (error ~1e-10 of the amplitude; the tests require
// < 1e-7 against finer rules and brute-force quadrature; Gaussians factor the
// rule's exponentials per pixel axis and take the normal CDF from a Taylor
// table good to 5e-16, render_geometry.h). A blurred disk's
// radial profile is tabulated per mark (exact integral, cubic Hermite). With
// no blur the pixel coverage is exact: polygon clipping (rectangles) or
// circle-polygon intersection (disks). The scanner blur, isotropic in pixels,
// is a Gaussian of covariance s^2 J^-1 J^-T in the mark frame (J = px_from_um);
// rectangles use its diagonal in their own axes and disks its mean variance:
// exact when J is a rotation and scale (possibly mirrored); for a slightly
// affine J the error is second order in the non-orthogonality and the mark
// stays point-symmetric, so its centre is unaffected.
#include <memory>
#include <string>
#include <vector>

#include "platemeter/core/pixel.h"
#include "platemeter/samples/scene.h"

namespace platemeter::sim {

struct RenderOptions {
  // Pixel quadrature: sub-cells of side <= max_cell_over_sigma x the narrowest
  // Gaussian sigma with quadrature_nodes^2 Gauss-Legendre nodes each, or the
  // cheaper of (nodes + 2, 2 x the side) and (nodes + 4, 3 x the side).
  int quadrature_nodes = 8;           // Gauss-Legendre nodes per axis in each pixel sub-cell
  double max_cell_over_sigma = 2.0;   // px/px; sub-cell side at most this times the narrowest Gaussian sigma
  int max_cells_per_axis = 24;        // cap on sub-cells per pixel axis (very small blur)
  double min_blur_sigma_px = 0.01;    // px; a blur below this is treated as none (exact coverage)
  double tail_sigmas = 8.5;           // a Gaussian edge is evaluated this many sigmas out; beyond, 0 or 1 (error < 1e-16)
  double dust_edge_fraction = 0.1;    // dust: sigma of the soft edge / diameter
  bool closed_form = true;            // exact box averages of blurred edges where they apply (false: quadrature only)
  bool Check(std::string* why) const;
};

// One mark's model, built once (tables, rectangles) and evaluated per pixel.
// Cheap to copy (shared immutable state); thread-safe to evaluate.
class MarkModel {
 public:
  MarkModel(const SceneMark& mark, double scanner_blur_sigma_px, const RenderOptions& options = {});

  // Pixels outside this rectangle get exactly 0 from this mark (not clipped to any image).
  const PixelRect& support() const { return support_; }
  const SceneMark& mark() const;

  // Mean over pixel (x_px, y_px)'s area of the mark's contribution in DN.
  double PixelValue(long x_px, long y_px) const { return PixelValueWithCentre(centre_px_, x_px, y_px); }
  // The same with the mark moved to centre_px (for derivatives and fits); the
  // support then grows by the shift.
  double PixelValueWithCentre(PixelPoint centre_px, long x_px, long y_px) const;
  // The pixel's value with the mark at its centre and moved by step_px along x
  // and y, for central differences: values = {centre, +x, -x, +y, -y}. The same
  // numbers as five PixelValueWithCentre calls (to rounding), at about half the
  // cost for trail images (the five share their quadrature's table look-ups).
  void PixelValuesShifted(double step_px, long x_px, long y_px, double values[5]) const;

  struct Impl;  // opaque: the mark's parts (rectangles, disks, Gaussians)

 private:
  std::shared_ptr<const Impl> impl_;
  PixelPoint centre_px_;
  PixelRect support_;
};

// The noise-free contribution (DN, no background) of one mark over a window,
// row-major window.width_px x window.height_px; centre_px overrides the mark's
// centre when given.
std::vector<double> MarkModelWindow(const MarkModel& model, const PixelRect& window);
std::vector<double> MarkModelWindow(const MarkModel& model, const PixelRect& window, PixelPoint centre_px);
// The same for a mark of a scene (the scene supplies the scanner blur).
std::vector<double> MarkModelWindow(const Scene& scene, const SceneMark& mark, const PixelRect& window,
                                    const RenderOptions& options = {});

}  // namespace platemeter::sim
