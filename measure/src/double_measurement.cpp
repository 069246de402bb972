// The double measurement (double_measurement.h).
#include "platemeter/measure/double_measurement.h"

#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>

namespace platemeter {
namespace {

bool HasPlate(const MeasuredPoint& p) { return p.x_mm && p.y_mm && p.sigma_x_mm && p.sigma_y_mm; }

// Inverse-variance mean of one axis; returns the mean's sigma.
double Mean(double a, double sa, double b, double sb, double* mean) {
  const double wa = 1.0 / (sa * sa), wb = 1.0 / (sb * sb);
  *mean = (a * wa + b * wb) / (wa + wb);
  return std::sqrt(1.0 / (wa + wb));
}

}  // namespace

DoubleMeasurementReport MeanDoubleMeasurement(MeasurementFile* first, const MeasurementFile& second) {
  DoubleMeasurementReport report;
  std::map<std::pair<PointKind, std::string>, const MeasuredPoint*> by_id;
  for (const MeasuredPoint& p : second.points) {
    if (HasPlate(p)) by_id[{p.kind, p.id}] = &p;
  }
  double sum_d2 = 0.0, sum_n2 = 0.0;
  for (MeasuredPoint& p : first->points) {
    if (!HasPlate(p)) continue;
    const auto it = by_id.find({p.kind, p.id});
    if (it == by_id.end() || *p.sigma_x_mm <= 0 || *p.sigma_y_mm <= 0 || *it->second->sigma_x_mm <= 0 ||
        *it->second->sigma_y_mm <= 0) {
      p.flags.push_back("double_measurement:first_only");
      ++report.only_first;
      continue;
    }
    const MeasuredPoint& q = *it->second;
    by_id.erase(it);
    PointDiscrepancy d{p.id, p.kind, *p.x_mm - *q.x_mm, *p.y_mm - *q.y_mm, 0.0, 0.0};
    d.normalized_x = d.dx_mm / std::hypot(*p.sigma_x_mm, *q.sigma_x_mm);
    d.normalized_y = d.dy_mm / std::hypot(*p.sigma_y_mm, *q.sigma_y_mm);
    sum_d2 += d.dx_mm * d.dx_mm + d.dy_mm * d.dy_mm;
    sum_n2 += d.normalized_x * d.normalized_x + d.normalized_y * d.normalized_y;
    report.discrepancies.push_back(d);
    double x, y;
    p.sigma_x_mm = Mean(*p.x_mm, *p.sigma_x_mm, *q.x_mm, *q.sigma_x_mm, &x);
    p.sigma_y_mm = Mean(*p.y_mm, *p.sigma_y_mm, *q.y_mm, *q.sigma_y_mm, &y);
    p.x_mm = x;
    p.y_mm = y;
    for (const std::string& f : q.flags) {
      if (f.rfind("reseau_fit:", 0) == 0 || f.rfind("local_reseau:", 0) == 0) p.flags.push_back("second:" + f);
    }
  }
  report.paired = static_cast<int>(report.discrepancies.size());
  report.only_second = static_cast<int>(by_id.size());
  if (report.paired > 0) {
    report.rms_discrepancy_mm = std::sqrt(sum_d2 / (2 * report.paired));
    report.rms_normalized = std::sqrt(sum_n2 / (2 * report.paired));
  }
  AppliedCorrection record{"double_measurement", {}};
  // (Header values carry no spaces: the second scan is named by its hash.)
  if (!second.header.scan_sha256.empty()) record.parameters.push_back({"second_scan_sha256", second.header.scan_sha256});
  for (auto& kv : std::vector<std::pair<std::string, std::string>>{
        {"paired", std::to_string(report.paired)},
        {"first_only", std::to_string(report.only_first)},
        {"second_only", std::to_string(report.only_second)},
        {"rms_discrepancy_mm", fmt::format("{}", report.rms_discrepancy_mm)},
        {"rms_normalized", fmt::format("{}", report.rms_normalized)}}) {
    record.parameters.push_back(kv);
  }
  first->header.corrections.push_back(record);
  return report;
}

}  // namespace platemeter
