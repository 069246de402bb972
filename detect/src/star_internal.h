#pragma once
// Internals of the star detector shared by its source files (not installed).
#include <vector>

#include <opencv2/core.hpp>

#include "platemeter/detect/star_width_model.h"

namespace platemeter::star_internal {

using ::platemeter::kFwhmPerSigma;

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

// Pure noise filtered by a Gaussian of sigma filter_sigma_px is a smooth random
// field; over area_px2 it has, above u of its own sigmas, on average
//   N(u) = area_px2 * lambda u exp(-u^2 / 2) / (2 pi)^(3/2),  lambda = 1 / (2 filter_sigma_px^2)
// peaks (the expected Euler characteristic of the excursion set; Adler 1981).
double ExpectedNoisePeaks(double area_px2, double filter_sigma_px, double level_sigma);
// The level (filtered noise sigmas) that pure noise exceeds expected_peaks times
// over the area: a peak below it cannot be told from noise.
double NoisePeakLevel(double area_px2, double filter_sigma_px, double expected_peaks);

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

// One fitted segment image: a circular Gaussian PSF swept uniformly along a
// straight segment of length length_px centred on (x_px, y_px) (a dash or a long
// dot of a duty-cycle trail; star_segment_fit.cpp).
struct FittedSegment {
  double x_px = 0, y_px = 0;            // absolute centre (mid-exposure for a uniform sweep)
  double angle_rad = 0;                 // direction of the segment, (-pi/2, pi/2]
  double length_px = 0;                 // full length of the sweep
  double flux_dn = 0, sigma_px = 1;     // total flux (positive contrast), PSF sigma
  double sigma_x_px = 0, sigma_y_px = 0, correlation_xy = 0, sigma_flux_dn = 0, sigma_length_px = 0;
};

// A point image fitted beside a segment (a faint dot on a bright dash's wing), the segment's width.
struct FittedPoint {
  double x_px = 0, y_px = 0, flux_dn = 0;
  double sigma_x_px = 0, sigma_y_px = 0, correlation_xy = 0, sigma_flux_dn = 0;
};

struct SegmentFitResult {
  bool ok = false, converged = false;
  FittedSegment segment;
  bool has_point = false;
  FittedPoint point;
  double offset_dn = 0, chi2 = 0, residual_sigma_dn = 0;
  int pixels = 0;
};

// Least-squares fit of one segment plus a constant; `start` holds the start values.
SegmentFitResult FitSegment(const std::vector<FitPixel>& pixels, const FittedSegment& start, double noise_sigma_dn);
// The same with one point image beside it (fitted jointly).
SegmentFitResult FitSegmentAndPoint(const std::vector<FitPixel>& pixels, const FittedSegment& start,
                                    const FittedPoint& point, double noise_sigma_dn);
// The same with the segment's shape known (angle_rad, length_px and sigma_px of `start`: a trail's dot
// where its track predicts it): only its centre, flux and the constant are fitted.
SegmentFitResult FitPlacedSegment(const std::vector<FitPixel>& pixels, const FittedSegment& start,
                                  double noise_sigma_dn);
// The segment's model value (contrast, without the offset) at a pixel centre.
double SegmentModel(const FittedSegment& segment, double x_px, double y_px);

// A connected component of the threshold mask: its label in the band's label
// image and its bounding box (band-relative pixels).
struct Component {
  int label = 0;
  int x = 0, y = 0, width = 0, height = 0;
  int area = 0;
  bool crowded = false;  // trail mode: a clump too long or too wide for one trail image; SplitComponents
                         // keeps it on the pieces it cuts such a clump into, clears it on what it leaves whole
  int clump = 0;         // the label of the component a piece was cut from (its own label if not cut)
};

// Trail mode: deblends the components longer than min_long_side_px
// (SExtractor-like): levels spaced exponentially between the detection level
// and the component's peak (matched-filtered values); where the pixels above
// a level fall apart into two or more significant pieces (area >= min_piece_area,
// flux >= min_contrast of the component's, peak >= level + min_rise), each piece
// is split again at higher levels; the remaining pixels go to the nearest final
// piece (8-connected flood within the component). Separates the leading dashes
// of a run (10 s gaps) and a faint dot from the bright dash next to it.
// `labels` is rewritten for the pieces (new labels from *next_label on).
// threshold[i] is the detection level of component in[i].
std::vector<Component> SplitComponents(cv::Mat* labels, const cv::Mat& filtered, const std::vector<Component>& in,
                                       const std::vector<float>& threshold, const std::vector<float>& min_rise,
                                       double min_long_side_px, int min_piece_area, double min_contrast,
                                       int* next_label);

}  // namespace platemeter::star_internal
