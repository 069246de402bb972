#pragma once
// The model of a cross fit's pixels: the blurred cross on a plane background
// (the formula is in platemeter/detect/cross_fit.h), plus the foreign images
// lying on it, each an elliptical Gaussian (a star image, or a trail's dot
// drawn out by the star's motion, on an arm), so that they are fitted with the
// cross rather than cut out of it. Also the least-squares cost of it for Ceres.
#include <ceres/ceres.h>

#include <vector>

namespace platemeter::internal {

// The cross's parameters, first in every parameter vector.
enum CrossParam { kX0, kY0, kTheta, kWidthH, kWidthV, kLength, kSigma, kGain, kB0, kBx, kBy, kNumCrossParams };
// Each foreign image adds these after the cross's (and the images' before it):
// its centre (px), flux (DN summed over the image, signed) and the Cholesky
// factor L (px) of its covariance L L^T, integrated over the pixel's area.
enum ImageParam { kImageX, kImageY, kImageFlux, kImageL11, kImageL21, kImageL22, kNumImageParams };

inline int NumSceneParams(int images) { return kNumCrossParams + kNumImageParams * images; }

struct CrossSample {
  double x_px;
  double y_px;
  double value_dn;
};

// The cross alone at one pixel and, if gradient != nullptr, its kNumCrossParams
// derivatives; (xc, yc) is the background plane's reference point.
double CrossModel(const double* p, double xc, double yc, const CrossSample& s, double* gradient);

// The cross and `images` foreign images at one pixel, with NumSceneParams(images)
// derivatives when gradient != nullptr.
double SceneModel(const double* p, int images, double xc, double yc, const CrossSample& s, double* gradient);

// Residuals SceneModel - value over the samples; one parameter block of
// NumSceneParams(images) values.
class CrossCost : public ceres::CostFunction {
 public:
  CrossCost(const std::vector<CrossSample>* samples, int images, double xc, double yc);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const std::vector<CrossSample>* samples_;
  int images_;
  double xc_, yc_;
};

}  // namespace platemeter::internal
