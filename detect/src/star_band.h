#pragma once
// The star detector's measurement of a band of rows (star_band.cpp) and of its components' images:
// point images (star_point_report.cpp) and trail-mode segments (star_segment_report.cpp). Not installed.
#include <memory>
#include <string>
#include <vector>

#include "platemeter/detect/star_detector.h"
#include "star_internal.h"

namespace platemeter::star_internal {

struct Band {
  const float* raw = nullptr;
  long width = 0, rows = 0;
  long y0_abs = 0;                // absolute row of the buffer's first row
  long keep_y0 = 0, keep_y1 = 0;  // absolute rows whose components this band reports
  long image_height = 0;
  double high_dn = 0, low_dn = 0;  // clip levels
};

struct Box {
  double x0, x1, y0, y1;
};

// The pixels a component's images are fitted on: its fit window without other components' pixels,
// masked pixels, clipped pixels and known crosses' arms.
struct ComponentPixels {
  std::vector<FitPixel> pixels;
  std::vector<char> own;  // per pixel: 1 where it is the component's own (above the threshold), 0 in its margin
  int clipped = 0, masked = 0;
  double peak_contrast_dn = 0;  // the component's brightest kept pixel
};

// Where a component's point fits are reported from: its widths, noise, background and fit window.
struct PointFitPlace {
  double start_sigma_px = 0, image_sigma_px = 0, noise_dn = 0;  // the given start, the plate's model here
  std::shared_ptr<const BackgroundMesh> mesh;                    // the band's
  double sign = 1;
  long y0_abs = 0;
  Box window{};  // absolute px: a fit that left it is dropped
  bool clipped = false, truncated = false;
};

// A component whose pair test waits for the plate's width model (point mode, DetectStars): the single
// star's fit is reported provisionally (rows first_row.. of the star list: they count for the model),
// and replaced by ResolvePendingPairs once every band is measured.
struct PendingPair {
  ComponentPixels component;
  PointFitPlace place;
  FittedGaussian start;
  GaussianFitResult single;
  size_t first_row = 0, row_count = 0;
};

// A measured image at a fitted position: the fields every fit fills.
DetectedStar MeasuredImage(double x_px, double y_px, double sigma_x_px, double sigma_y_px, double correlation_xy,
                           double flux_dn, double sigma_flux_dn, double background_dn);
// A rejected image; `why` (line, cross, masked: near a known cross, masked_pixels: no values, shape)
// becomes its reason, the flag says defect.
DetectedStar Defect(double x_px, double y_px, const std::string& why);

// A second star is worth trying when the single one is too wide for its SNR against the width
// expected at its place, or leaves a chi^2 excess.
bool PairTestWanted(const GaussianFitResult& single, double image_sigma_px);
// The pair test (two starts; the better kept when chi^2 drops by pair_chi2_gain and both are images of
// the width expected here). True when *fit became the pair.
bool TryPair(const ComponentPixels& c, const FittedGaussian& start, double image_sigma_px, double noise_dn,
             double min_sigma_px, const StarDetectorOptions& o, GaussianFitResult* fit);
// The measured images of a component's fit (one star, or a blended pair): noise dropped, implausible
// widths rejected, the rest measured with their flags.
void ReportPointFits(const GaussianFitResult& fit, bool blended, const std::vector<FitPixel>& pixels,
                     const PointFitPlace& at, const StarDetectorOptions& o, std::vector<DetectedStar>* result);
// The waiting pair tests, with the width model of the whole plate: the provisional rows are replaced
// by what each component is (one star or a pair); defects counted in stats.
void ResolvePendingPairs(const StarDetectorOptions& o, const StarWidthModel& model, std::vector<PendingPair>* pending,
                         std::vector<DetectedStar>* stars, StarDetectionStats* stats);

// Trail mode: a component's sweep (centre, direction, length) from the second moments of its own pixels.
struct SweepMoments {
  double x = 0, y = 0, angle_rad = 0, length_px = 0, flux_dn = 0;
};
SweepMoments ComponentSweep(const ComponentPixels& c);
// Trail mode: fits one segment and reports it as a measured elongated image, or as a defect when it is
// too long (line) or too wide (dust, wide scratch) for a dash.
void MeasureSegment(const SweepMoments& m, const ComponentPixels& c, double noise, double psf_sigma,
                    bool truncated, const StarDetectorOptions& o, const BackgroundMesh& mesh, long y0_abs, double sign,
                    const Box& window, std::vector<DetectedStar>* result);

// Finds and measures the images of one band; `pending`, when given (point mode), takes the components
// whose pair test waits for the plate's width model.
void ProcessBand(const Band& b, const StarDetectorOptions& o, const StarWidthModel& width_model,
                 std::vector<DetectedStar>* out, StarDetectionStats* stats, std::vector<PendingPair>* pending);

}  // namespace platemeter::star_internal
