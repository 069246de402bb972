#pragma once
// Capping-shutter duty cycle of seed 001 (Orbigon stellar calibration), Table 1,
// and the exposure schedule of one star plate (four trails).
//
// Table 1 as implemented (open / closed / repetitions), one trail:
//   row 1   20 s dash  + 10 s closed   x N  (N = 2, 3, 4 or 5: numbers the trail)
//   row 2   0.6 s dot  + 39.4 s closed x 5  (dots  1..5,  group 1)
//   row 3   20 s dash  + 20 s closed   x 1  (separator after group 1)
//   row 4   1.2 s dot  + 38.8 s closed x 5  (dots  6..10, group 2)
//   row 5   20 s dash  + 20 s closed   x 1
//   row 6   3.2 s dot  + 96.8 s closed x 5  (dots 11..15, group 3; 100 s period as printed)
//   row 7   20 s dash  + 20 s closed   x 1
//   row 8   6.2 s dot  + 33.8 s closed x 5  (dots 16..20, group 4)
//   row 9   20 s dash  + 20 s closed   x 1
//   row 10  10 s dot   + 30 s closed   x 5  (dots 21..25, group 5)
// Every exposure opens at the start of its row slot and its closed interval
// follows it, so a trail lasts 30 N + 1460 s (1520 s for N = 2), the closed
// 30 s after the last dot included. The 7-10 minute break between trails is
// counted from the end of that closed interval to the next trail's first opening.
// With the defaults (N = 2,3,4,5, 8 min breaks) a plate spans 7700 s (2 h 08 min).
#include <string>
#include <vector>

namespace platemeter {

enum class ExposureKind { kDash, kDot };

// One row of the program: `repetitions` times (open, then closed).
struct DutyCycleRow {
  double open_s = 0.0;    // shutter open time per repetition
  double closed_s = 0.0;  // shutter closed time after each opening
  int repetitions = 1;    // ignored for the leading row (the trail's dash count replaces it)
  ExposureKind kind = ExposureKind::kDash;
};

// The shutter program of one trail; rows[0] is the leading dash row.
struct DutyCycleProgram {
  std::vector<DutyCycleRow> rows;

  // Seed 001 Table 1, rows in the order above.
  static DutyCycleProgram Table1();
  bool Check(std::string* why) const;
};

struct DutyCycleScheduleOptions {
  double start_s = 0.0;                       // first shutter opening, seconds on the caller's UTC scale
  std::vector<int> leading_dashes{2, 3, 4, 5};  // leading dash count per trail (1..4 trails), distinct, each 2..5
  double break_s = 480.0;                      // break between trails, s, 420..600 (7-10 min, seed 001)
  DutyCycleProgram program = DutyCycleProgram::Table1();  // one trail's program

  bool Check(std::string* why) const;
};

// One shutter opening. Times are on the same scale as `start_s`.
struct ShutterExposure {
  double open_s = 0.0;   // shutter opens
  double close_s = 0.0;  // shutter closes (open_s + duration_s)
  double mid_s = 0.0;    // (open_s + close_s) / 2
  double duration_s = 0.0;
  ExposureKind kind = ExposureKind::kDash;
  int trail = 0;       // 1..number of trails, in time order
  int table_row = 0;   // 1-based row of the program (Table 1 row)
  int group = 0;       // 0 = leading dashes; dot group 1..5; a separator dash carries the group it follows
  int dot_index = 0;   // 1..25 within the trail for dots, 0 for dashes
  int dash_index = 0;  // 1.. within the trail for dashes, 0 for dots
};

// Length of one trail with `leading_dashes` leading dashes, closed tail included, s.
double TrailDuration(const DutyCycleProgram& program, int leading_dashes);

// All exposures of a plate in time order. Throws platemeter::Error for bad options.
std::vector<ShutterExposure> BuildShutterSchedule(const DutyCycleScheduleOptions& options);

}  // namespace platemeter
