#pragma once
// The model of a cross fit's pixels: the blurred cross on a plane background
// (the formula is in platemeter/detect/cross_fit.h), plus the foreign images
// lying on it, each an elliptical Gaussian (a star image, or a trail's dot
// drawn out by the star's motion, on an arm), so that they are fitted with the
// cross rather than cut out of it, and the missing pieces of its arms (a
// damaged cross: the line etched or scratched away over a stretch). Also the
// least-squares cost of it for Ceres.
#include <ceres/ceres.h>

#include <vector>

namespace platemeter::internal {

// The cross's parameters, first in every parameter vector.
enum CrossParam { kX0, kY0, kTheta, kWidthH, kWidthV, kLength, kSigma, kGain, kB0, kBx, kBy, kNumCrossParams };
// Each foreign image adds these after the cross's (and the images' before it):
// its centre (px), flux (DN summed over the image, signed) and the Cholesky
// factor L (px) of its covariance L L^T, integrated over the pixel's area.
enum ImageParam { kImageX, kImageY, kImageFlux, kImageL11, kImageL21, kImageL22, kNumImageParams };

// Each missing piece of an arm adds these after the images': the middle of the
// piece (px from the cross's centre along its arm) and its length (px). The arm
// keeps its profile across; the piece is that profile over the stretch, taken out.
enum GapParam { kGapMiddle, kGapLength, kNumGapParams };

// What follows the cross's parameters: the foreign images, then the missing pieces.
struct SceneLayout {
  int images = 0;
  std::vector<int> gap_arms;  // per missing piece its arm: 0 along +u, 1 +v, 2 -u, 3 -v (u: kTheta's direction)
  int gaps() const { return static_cast<int>(gap_arms.size()); }
  int Params() const { return kNumCrossParams + kNumImageParams * images + kNumGapParams * gaps(); }
  int FirstGapParam() const { return kNumCrossParams + kNumImageParams * images; }
};

struct CrossSample {
  double x_px;
  double y_px;
  double value_dn;
};

// The cross alone at one pixel and, if gradient != nullptr, its kNumCrossParams
// derivatives; (xc, yc) is the background plane's reference point.
double CrossModel(const double* p, double xc, double yc, const CrossSample& s, double* gradient);

// The cross, its foreign images and its missing pieces at one pixel, with
// layout.Params() derivatives when gradient != nullptr.
double SceneModel(const double* p, const SceneLayout& layout, double xc, double yc, const CrossSample& s,
                  double* gradient);

// Residuals SceneModel - value over the samples; one parameter block of
// layout.Params() values.
class CrossCost : public ceres::CostFunction {
 public:
  CrossCost(const std::vector<CrossSample>* samples, SceneLayout layout, double xc, double yc);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const std::vector<CrossSample>* samples_;
  SceneLayout layout_;
  double xc_, yc_;
};

}  // namespace platemeter::internal
