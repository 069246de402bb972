#pragma once
// Internals of the star detector shared by its source files (not installed).
#include <vector>

namespace platemeter::star_internal {

// Background and noise of a band on a mesh of cells (absolute cell rows).
struct BackgroundMesh {
  int cell_px = 64;
  long nx = 0, ny = 0;          // cells across, down
  std::vector<float> level_dn;  // nx * ny, row-major
  std::vector<float> sigma_dn;  // nx * ny
  // Bilinear interpolation between cell centres (clamped at the borders).
  float LevelAt(double x_px, double y_px) const;
  float SigmaAt(double x_px, double y_px) const;  // the nearest cell's sigma
  // LevelAt for a whole row of width_px pixels (the same values, faster).
  void LevelRow(long y_px, long width_px, float* out) const;
};

// Sigma-clipped mode and sigma per cell (SExtractor's estimator), then a 3x3
// median over the mesh. Pixels at or outside [low_dn, high_dn] are ignored.
// Coordinates are relative to the buffer's first pixel.
BackgroundMesh ComputeBackgroundMesh(const float* values_dn, long width_px, long height_px, int cell_px,
                                     double clip_sigma, double low_dn, double high_dn);

// One fitted pixel-integrated circular Gaussian.
struct FittedGaussian {
  double x_px = 0, y_px = 0;          // absolute
  double flux_dn = 0, sigma_px = 1;   // total flux (positive contrast), Gaussian sigma
  double sigma_x_px = 0, sigma_y_px = 0, correlation_xy = 0, sigma_flux_dn = 0;
};

struct FitPixel {
  float x_px, y_px;  // absolute centre of the pixel
  float value_dn;    // contrast (positive for a star), background-subtracted by the mesh
};

struct GaussianFitResult {
  bool converged = false;
  std::vector<FittedGaussian> stars;
  double offset_dn = 0;   // fitted residual background
  double chi2 = 0;        // sum of squared residuals / noise variance
  double residual_sigma_dn = 0;
  int pixels = 0;
};

// Joint least-squares fit (Ceres) of stars.size() Gaussians plus a constant on
// the given pixels; `stars` holds the start values.
GaussianFitResult FitGaussians(const std::vector<FitPixel>& pixels, std::vector<FittedGaussian> stars,
                               double noise_sigma_dn, double min_sigma_px);

}  // namespace platemeter::star_internal
