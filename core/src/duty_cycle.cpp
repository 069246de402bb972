#include "platemeter/core/duty_cycle.h"

#include <cmath>
#include <set>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "platemeter/core/why.h"

namespace platemeter {
namespace {

}  // namespace

DutyCycleProgram DutyCycleProgram::Table1() {
  using K = ExposureKind;
  DutyCycleProgram p;
  p.rows = {
      {20.0, 10.0, 2, K::kDash},  // repetitions set per trail (2, 3, 4 or 5)
      {0.6, 39.4, 5, K::kDot},   {20.0, 20.0, 1, K::kDash}, {1.2, 38.8, 5, K::kDot},
      {20.0, 20.0, 1, K::kDash}, {3.2, 96.8, 5, K::kDot},   {20.0, 20.0, 1, K::kDash},
      {6.2, 33.8, 5, K::kDot},   {20.0, 20.0, 1, K::kDash}, {10.0, 30.0, 5, K::kDot},
  };
  return p;
}

bool DutyCycleProgram::Check(std::string* why) const {
  if (rows.empty()) return Fail(why, "the duty-cycle program has no rows");
  if (rows[0].kind != ExposureKind::kDash)
    return Fail(why, "the first program row must be the leading dashes");
  for (size_t i = 0; i < rows.size(); ++i) {
    const DutyCycleRow& r = rows[i];
    if (!std::isfinite(r.open_s) || r.open_s <= 0.0)
      return Fail(why, fmt::format("program row {}: open time {} s must be > 0", i + 1, r.open_s));
    if (!std::isfinite(r.closed_s) || r.closed_s < 0.0)
      return Fail(why, fmt::format("program row {}: closed time {} s must be >= 0", i + 1, r.closed_s));
    if (i > 0 && r.repetitions < 1)
      return Fail(why, fmt::format("program row {}: repetitions {} must be >= 1", i + 1, r.repetitions));
  }
  return true;
}

bool DutyCycleScheduleOptions::Check(std::string* why) const {
  if (!std::isfinite(start_s)) return Fail(why, "start time is not finite");
  if (leading_dashes.empty() || leading_dashes.size() > 4)
    return Fail(why, fmt::format("{} trails requested; a plate has 1 to 4", leading_dashes.size()));
  std::set<int> seen;
  for (int n : leading_dashes) {
    if (n < 2 || n > 5)
      return Fail(why, fmt::format("{} leading dashes; Table 1 allows 2, 3, 4 or 5", n));
    if (!seen.insert(n).second)
      return Fail(why, fmt::format("two trails have {} leading dashes; the count must identify the trail", n));
  }
  if (!std::isfinite(break_s) || break_s < 420.0 || break_s > 600.0)
    return Fail(why, fmt::format("break of {} s between trails; seed 001 allows 420..600 s (7-10 min)", break_s));
  return program.Check(why);
}

double TrailDuration(const DutyCycleProgram& program, int leading_dashes) {
  double total = 0.0;
  for (size_t i = 0; i < program.rows.size(); ++i) {
    const DutyCycleRow& r = program.rows[i];
    const int reps = i == 0 ? leading_dashes : r.repetitions;
    total += reps * (r.open_s + r.closed_s);
  }
  return total;
}

std::vector<ShutterExposure> BuildShutterSchedule(const DutyCycleScheduleOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("duty-cycle schedule", why);
  std::vector<ShutterExposure> out;
  double trail_start = options.start_s;
  for (size_t t = 0; t < options.leading_dashes.size(); ++t) {
    double now = trail_start;
    int group = 0, dot = 0, dash = 0;
    const auto& rows = options.program.rows;
    for (size_t i = 0; i < rows.size(); ++i) {
      const DutyCycleRow& r = rows[i];
      if (r.kind == ExposureKind::kDot) ++group;
      const int reps = i == 0 ? options.leading_dashes[t] : r.repetitions;
      for (int k = 0; k < reps; ++k) {
        ShutterExposure e;
        e.open_s = now;
        e.duration_s = r.open_s;
        e.close_s = now + r.open_s;
        e.mid_s = now + 0.5 * r.open_s;
        e.kind = r.kind;
        e.trail = static_cast<int>(t) + 1;
        e.table_row = static_cast<int>(i) + 1;
        e.group = group;
        if (r.kind == ExposureKind::kDot) e.dot_index = ++dot;
        else e.dash_index = ++dash;
        out.push_back(e);
        now += r.open_s + r.closed_s;
      }
    }
    trail_start = now + options.break_s;
  }
  return out;
}

}  // namespace platemeter
