#pragma once
// The emulsion-depth geometry (seed 001): the reseau, on the glass in contact
// with the emulsion, shadows the emulsion along the converging ray from the
// rear nodal point (height c above the emulsion surface, foot at the principal
// point). The ray meets the surface at radius r with incidence angle theta
// (tan theta = r / c), refracts into the emulsion of index n (sin theta' =
// sin theta / n), and the image centroid at depth d lies at
//   r' = r + d tan theta' = r + d sin(theta) / sqrt(n^2 - sin^2 theta).
// For small angles this is the scale 1 + d / (n c). Shared by the simulator
// (samples/geometry.h, forward) and the comparator corrections (inverse).
#include <vector>

namespace platemeter {

struct EmulsionDepthModel {
  double depth_um = 0.0;                // um; depth of the image centroid below the emulsion surface
  double refractive_index = 1.65;       // of the emulsion
  double principal_distance_mm = 80.2;  // mm; rear nodal point above the emulsion surface

  // r' - r in mm at the radius r_mm from the principal point.
  double RadialShiftMm(double r_mm) const;
  // d(r' - r)/dr at r_mm.
  double RadialShiftDerivative(double r_mm) const;
  // The image radius r' of the true radius r_mm, and back (Newton on r).
  double ImageRadiusMm(double r_mm) const { return r_mm + RadialShiftMm(r_mm); }
  double TrueRadiusMm(double image_radius_mm) const;
  // The small-angle scale 1 + d / (n c).
  double EquivalentScale() const;
  // The scale a least-squares fit (scale only, about the principal point) of
  // the displaced points at these radii (mm) to the undisplaced ones finds:
  // sum(r (r + g(r))) / sum(r^2). Smaller than EquivalentScale: the outer
  // points refract less than the small-angle scale says.
  double FittedScale(const std::vector<double>& radii_mm) const;
  // The depth (um) for which FittedScale(radii_mm) equals `scale` (the shift
  // is linear in the depth, so this is exact).
  double DepthUmFromFittedScale(double scale, const std::vector<double>& radii_mm) const;
  // The depth (um) whose small-angle scale is `scale`: (scale - 1) n c.
  static double DepthUmFromEquivalentScale(double scale, double refractive_index, double principal_distance_mm);
};

}  // namespace platemeter
