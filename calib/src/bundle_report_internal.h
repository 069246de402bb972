#pragma once
// Shared by the bundle's output writers (bundle_report_*.cpp).
#include <string>
#include <vector>

#include "platemeter/calib/bundle_adjustment.h"

namespace platemeter {

// The camera's adjusted parameters (those with a sigma): their indices in
// result.adjustment.parameters, and their names in `names`.
std::vector<int> AdjustedCameraParameters(const BundleCameraResult& camera, std::vector<std::string>* names);

// The observations with the largest normalized residuals (rejected ones first), at most `count`.
std::vector<const ObservationResidual*> WorstObservations(const BundleResult& result, int count);

}  // namespace platemeter

#include "platemeter/calib/model_conversion.h"

namespace platemeter {
struct BundleReportOptions;
// The adjusted lens of a camera with the covariance of [c, k1..b2] (scaled).
LensEstimate BundleLensEstimate(const BundleResult& result, const BundleCameraResult& camera);
// Seed 000 Table 2 form: the balanced radial and the decentering profiles with
// propagated sigmas, and the phase angle (bundle_report_profile.cpp).
void AppendProfileTables(const BundleResult& result, const BundleCameraResult& camera,
                         const BundleReportOptions& options, std::string* out);
}  // namespace platemeter
