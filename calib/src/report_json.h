#pragma once
// JSON pieces every adjustment's calibration.json shares (docs/calibration-output.md).
#include <nlohmann/json.hpp>

#include "platemeter/calib/adjustment.h"

namespace platemeter {

// The rank report: ranks, condition, null and weak directions in words and shares.
nlohmann::ordered_json RankReportJson(const RankReport& rank);
// sigma0, degrees of freedom and the chi-square test of an adjustment.
nlohmann::ordered_json StatisticsJson(const AdjustmentResult& result);

}  // namespace platemeter
