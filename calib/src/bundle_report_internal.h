#pragma once
// Shared by the bundle's output writers (bundle_report_*.cpp).
#include <string>
#include <vector>

#include "platemeter/calib/bundle_adjustment.h"
#include "platemeter/calib/model_conversion.h"
#include "platemeter/core/text_document.h"

namespace platemeter {

struct BundleReportOptions;

// The observations with the largest normalized residuals (rejected ones first), at most `count`.
std::vector<const ObservationResidual*> WorstObservations(const BundleResult& result, int count);

// The adjusted lens of a camera with the covariance of [c, k1..b2] (scaled).
LensEstimate BundleLensEstimate(const BundleResult& result, const BundleCameraResult& camera);
// Seed 000 Table 2 form: the balanced radial and the decentering profiles with
// propagated sigmas, and the phase angle (bundle_report_profile.cpp).
void AppendProfileTables(const BundleResult& result, const BundleCameraResult& camera,
                         const BundleReportOptions& options, TextDocument* doc);

}  // namespace platemeter
