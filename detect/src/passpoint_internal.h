#pragma once
// Pieces of the passpoint detector shared by its files: the correlation
// template and peaks (passpoint_search.cpp), the full-resolution fit of one
// candidate and its verdict (passpoint_fit.cpp).
#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "platemeter/core/image.h"
#include "platemeter/detect/passpoint_detector.h"

namespace platemeter::internal {

// The mark at 1/factor resolution, signed so that a match correlates positively.
struct PasspointTemplate {
  cv::Mat image;            // CV_32F
  double anchor_x = 0.0;    // template pixel coordinates of the mark's centre
  double anchor_y = 0.0;
  int factor = 1;
};
PasspointTemplate MakePasspointTemplate(const PasspointDetectorOptions& options, int factor);
// The look-alike of the other shape and the same diameter: a filled disk for a
// ring, a ring of a fifth of the diameter for a dot. A peak that correlates
// better with it than with the mark's own template is not the mark.
PasspointTemplate MakeLookAlikeTemplate(const PasspointDetectorOptions& options, int factor);
// Block averaging that keeps the mark about 12 px across (and a ring's line 2 px wide).
int PasspointSearchFactor(const PasspointDetectorOptions& options);

struct PasspointPeak {
  PixelPoint position_px;  // full-resolution scan position of the template's centre
  double score = 0.0;      // normalized correlation
  double look_alike_score = -1.0;  // best correlation of the look-alike template within 1 block of the peak
};
// Local maxima of the correlation of `image` (a block-averaged window whose
// pixel (0, 0) covers scan pixels from (x0_px, y0_px)) above min_score,
// strongest first, at least separation_px (scan px) apart, at most max_peaks.
// With look_alike, each kept peak's look_alike_score is filled.
std::vector<PasspointPeak> FindPasspointPeaks(const cv::Mat& image, long x0_px, long y0_px,
                                              const PasspointTemplate& templ, double min_score,
                                              double separation_px, int max_peaks,
                                              const PasspointTemplate* look_alike = nullptr);

bool InPasspointMask(const std::vector<PasspointMask>& mask, const PixelPoint& p);

// The whole scan, tile by tile: every unmasked peak (automatic mode).
std::vector<PasspointPeak> SearchWholeScan(const Image& image, const PasspointDetectorOptions& options,
                                           int* tiles, int* masked);

// One candidate fitted at full resolution and judged.
struct CandidateFit {
  MarkFitResult fit;
  PixelPoint start_px;
  bool is_mark = false;  // right shape, size, polarity and sharpness: this is a passpoint
  std::string reason;    // not a mark: why (not_converged, polarity, off_start, size, line_width, blur);
                         // a mark: "" (measured), low_contrast or defect (rejected)
  bool clipped = false;  // the fit window was cut by the scan's edge
};
CandidateFit FitPasspointCandidate(const Image& image, const PasspointDetectorOptions& options, const PixelPoint& start);

}  // namespace platemeter::internal
