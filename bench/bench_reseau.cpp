// Reseau-cross detection on simulator plates with exact truth: accuracy against
// the Cramer-Rao bound, honesty of the formal sigmas, ids, false points, speed
// and memory; and, on the same crosses of the same scans, the method of the
// public tools (ISIS findrx, MicMac, HIPP, spymicmac): OpenCV matchTemplate
// (TM_CCOEFF_NORMED) with a paraboloid fit of the peak.
//
//   bench_reseau [--cases a,b,...] [--large PX] [--keep DIR]
//
// Each case renders an SN-004 terrain plate (Ikogon B, calibrated values) with
// the simulator, then runs the shipped `platemeter detect` on it as its own
// process, so the time and peak RSS printed are the tool's alone.
// --large PX adds a PX x PX 16-bit plate (e.g. 16000).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench_process.h"
#include "platemeter/core/image.h"
#include "platemeter/detect/reseau_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace {

using platemeter::bench::RunProcess;
using platemeter::bench::ToolRun;

using namespace platemeter;

struct Case {
  std::string name;
  double pixel_um = 10.0;
  int bits = 16;
  int orientation_deg = 0;
  bool mirrored = false;
  bool bright = false;       // bright crosses (a negative scan)
  double noise_scale = 1.0;  // sensor and grain sigmas times this
  bool degraded = false;     // dust, scratches, three damaged crosses, a false '+' 3 mm from one
  long size_px = 0;          // explicit square size (large case)
  // > 0: the crosses' contrast is this many noise sigmas (a faint grid); dust and
  // scratches keep the usual contrast, so they are stronger than the crosses.
  double contrast_to_noise = 0.0;
};

std::string SpecText(const Case& c) {
  const double level = c.bits == 8 ? 160.0 : 26000.0;
  const double usual_contrast = c.bits == 8 ? 70.0 : 12000.0;
  const double sensor = (c.bits == 8 ? 1.2 : 120.0) * c.noise_scale;
  const double grain = (c.bits == 8 ? 1.5 : 200.0) * c.noise_scale;
  const double contrast = c.contrast_to_noise > 0 ? c.contrast_to_noise * std::hypot(sensor, grain) : usual_contrast;
  std::ostringstream s;
  s << "name = \"bench-" << c.name << "\"\ncamera = \"sn004-terrain\"\nseed = 11\n"
    << "[output]\npixel_size_um = " << c.pixel_um << "\nbits = " << c.bits << "\nmargin_mm = 1.0\n";
  if (c.size_px > 0) s << "width_px = " << c.size_px << "\nheight_px = " << c.size_px << "\n";
  s << "[thermal]\ntemperature_degC = 22.0\ncalibration_temperature_degC = 20.0\n"
    << "[emulsion]\ndepth_um = 8.0\nrefractive_index = 1.65\n"
    << "[film]\naffine_ppm = [45.0, 6.0, -4.0, -30.0]\nshift_um = [1.5, -2.0]\n"
    << "[[film.wave]]\namplitude_um = [1.2, -0.8]\nwavelength_mm = 60.0\ndirection_deg = 30.0\nphase_deg = 10.0\n"
    << "[scanner]\nrotation_deg = 0.3\nnon_orthogonality_arcsec = 12.0\noffset_px = [3.3, -2.7]\n"
    << "orientation_deg = " << c.orientation_deg << "\nmirrored = " << (c.mirrored ? "true" : "false") << "\n"
    << "[marks.reseau]\npolarity = \"" << (c.bright ? "bright" : "dark") << "\"\ncontrast_dn = " << contrast << "\n"
    << "[marks.fiducials]\npolarity = \"bright\"\ncontrast_dn = " << contrast << "\n"
    << "[background]\nlevel_dn = " << level << "\nterrain_amplitude_dn = " << 0.15 * level
    << "\nterrain_scale_mm = 15.0\nvignetting_fraction = 0.08\nvignetting_radius_mm = 80.0\n"
    << "[noise]\nblur_sigma_um = 6.0\nsensor_sigma_dn = " << sensor << "\ngrain_sigma_dn = " << grain << "\n";
  if (c.degraded) {
    s << "[defects]\ndust_count = 400\ndust_contrast_dn = " << 0.5 * usual_contrast << "\nscratch_count = 25\n"
      << "scratch_contrast_dn = " << 0.4 * usual_contrast << "\n"
      << "damaged_crosses = [\"X3Y9\", \"X7Y4\", \"X10Y2\"]\ndamage_fraction = 0.3\n"
      // Crosses never exposed: their predicted places hold noise (and dust) that must not be measured.
      << (c.contrast_to_noise > 0 ? "missing_crosses = [\"X2Y2\", \"X5Y7\", \"X9Y3\", \"X11Y10\", \"X6Y1\", \"X1Y6\"]\n" : "")
      << "[[defects.false_mark]]\nnear = \"X3Y9\"\noffset_um = [3000.0, 0.0]\n";
  }
  return s.str();
}

// Is a cross within reach of a dust blob or scratch (its support box grown by the defect)?
bool Touched(const sim::SimulatedPlate& plate, const sim::SceneMark& cross) {
  const double px_per_um = std::sqrt(std::abs(cross.px_from_um[0] * cross.px_from_um[3] -
                                              cross.px_from_um[1] * cross.px_from_um[2]));
  const double half_px = 0.5 * cross.size_um * px_per_um + 3.0;
  for (int index : plate.dust) {
    const sim::SceneMark& d = plate.scene.marks[index];
    const double r = 0.6 * d.size_um * px_per_um + 3.0;
    if (std::abs(d.centre_px.x_px - cross.centre_px.x_px) < half_px + r &&
        std::abs(d.centre_px.y_px - cross.centre_px.y_px) < half_px + r)
      return true;
  }
  for (int index : plate.scratches) {
    const sim::SceneMark& s = plate.scene.marks[index];
    // Scratch direction in pixels: the mark-frame direction mapped by its local map.
    const double u = std::cos(s.corner_angle_rad), v = std::sin(s.corner_angle_rad);
    double dx = s.px_from_um[0] * u + s.px_from_um[1] * v, dy = s.px_from_um[2] * u + s.px_from_um[3] * v;
    const double norm = std::hypot(dx, dy);
    dx /= norm;
    dy /= norm;
    const double half_length = 0.5 * s.size_um * px_per_um;
    const double ex = cross.centre_px.x_px - s.centre_px.x_px, ey = cross.centre_px.y_px - s.centre_px.y_px;
    const double along = std::clamp(ex * dx + ey * dy, -half_length, half_length);
    const double distance = std::hypot(ex - along * dx, ey - along * dy);
    if (distance < half_px * std::sqrt(2.0) + s.line_width_um * px_per_um) return true;
  }
  return false;
}

// The public tools' method: normalized correlation with an ideal cross template
// around the expected place, then a parabola through the peak in x and in y.
// Like those tools, it works on the whole image in memory.
PixelPoint CorrelationPeak(const cv::Mat& image, PixelPoint around, double line_px, double arm_px, bool bright,
                           bool* ok) {
  const int half = static_cast<int>(std::ceil(0.5 * arm_px + line_px));
  const int size = 2 * half + 1;
  cv::Mat templ(size, size, CV_32F);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      auto coverage = [](double t, double hw) { return std::clamp(std::min(t + 0.5, hw) - std::max(t - 0.5, -hw), 0.0, 1.0); };
      const double h = coverage(r - half, 0.5 * line_px) * coverage(c - half, 0.5 * arm_px);
      const double v = coverage(c - half, 0.5 * line_px) * coverage(r - half, 0.5 * arm_px);
      templ.at<float>(r, c) = static_cast<float>((bright ? 1 : -1) * (h + v - h * v));
    }
  const int search = 8;
  const cv::Rect rect(static_cast<int>(std::lround(around.x_px)) - half - search,
                      static_cast<int>(std::lround(around.y_px)) - half - search, size + 2 * search, size + 2 * search);
  *ok = rect.x >= 0 && rect.y >= 0 && rect.x + rect.width <= image.cols && rect.y + rect.height <= image.rows;
  if (!*ok) return around;
  cv::Mat patch;
  image(rect).convertTo(patch, CV_32F);
  cv::Mat score;
  cv::matchTemplate(patch, templ, score, cv::TM_CCOEFF_NORMED);
  cv::Point peak;
  cv::minMaxLoc(score, nullptr, nullptr, nullptr, &peak);
  double ox = 0, oy = 0;
  if (peak.x > 0 && peak.x + 1 < score.cols) {
    const double a = score.at<float>(peak.y, peak.x - 1), b = score.at<float>(peak.y, peak.x), e = score.at<float>(peak.y, peak.x + 1);
    if (a - 2 * b + e < 0) ox = 0.5 * (a - e) / (a - 2 * b + e);
  }
  if (peak.y > 0 && peak.y + 1 < score.rows) {
    const double a = score.at<float>(peak.y - 1, peak.x), b = score.at<float>(peak.y, peak.x), e = score.at<float>(peak.y + 1, peak.x);
    if (a - 2 * b + e < 0) oy = 0.5 * (a - e) / (a - 2 * b + e);
  }
  return {rect.x + half + peak.x + ox, rect.y + half + peak.y + oy};
}

// The baseline as its own process (this program run with --baseline-child):
// reads the whole scan with OpenCV, measures the listed crosses, writes
// "x y ok" lines. Arguments: scan, positions file, output file, line px, arm px, bright (0/1).
int BaselineChild(char** argv) {
  const cv::Mat image = cv::imread(argv[0], cv::IMREAD_UNCHANGED);
  if (image.empty()) return 3;
  std::FILE* in = std::fopen(argv[1], "r");
  std::FILE* out = std::fopen(argv[2], "w");
  if (!in || !out) return 4;
  double x, y;
  while (std::fscanf(in, "%lf %lf", &x, &y) == 2) {
    bool ok = false;
    const PixelPoint peak = CorrelationPeak(image, {x, y}, std::atof(argv[3]), std::atof(argv[4]), argv[5][0] == '1', &ok);
    std::fprintf(out, "%.9f %.9f %d\n", peak.x_px, peak.y_px, ok ? 1 : 0);
  }
  std::fclose(in);
  std::fclose(out);
  return 0;
}

// A clean cross this precise must be measured (#26: faint crosses down to the noise limit).
constexpr double kMeasurableCrbPx = 0.05;

struct Stats {
  std::vector<double> ex, ey, crb, sigma;
  void Add(double dx, double dy, double crb_px, double sigma_px) {
    ex.push_back(dx);
    ey.push_back(dy);
    crb.push_back(crb_px);
    sigma.push_back(sigma_px);
  }
  static double Mean(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0 : s / v.size();
  }
  static double Median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  double Rms() const {  // per axis, both axes pooled
    double s = 0;
    for (size_t i = 0; i < ex.size(); ++i) s += ex[i] * ex[i] + ey[i] * ey[i];
    return ex.empty() ? 0 : std::sqrt(s / (2.0 * ex.size()));
  }
  double Max() const {
    double m = 0;
    for (size_t i = 0; i < ex.size(); ++i) m = std::max({m, std::abs(ex[i]), std::abs(ey[i])});
    return m;
  }
};


// Scores the tool's measurement file against the truth and prints one line.
void Score(const Case& c, const sim::SimulatedPlate& plate, const std::string& scan, const MasterGrid& grid,
           const ToolRun& run, const MeasurementFile& measured, const std::string& self, const std::string& dir) {
  const Image image = Image::Open(scan);
  std::vector<std::pair<double, double>> baseline_targets;  // truth positions of the clean crosses
  std::map<std::string, const MeasuredPoint*> truth;
  std::map<std::string, int> mark_of;
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    if (plate.truth[i].kind != PointKind::kReseau) continue;
    truth[plate.truth[i].id] = &plate.truth[i];
    mark_of[plate.truth[i].id] = plate.truth_mark[i];
  }
  auto has_flag = [](const MeasuredPoint& p, const char* flag) {
    return std::find(p.flags.begin(), p.flags.end(), flag) != p.flags.end();
  };
  Stats clean, baseline;
  int wrong_ids = 0, false_points = 0, lost = 0, touched_rejected = 0, touched_within = 0, touched_beyond = 0;
  std::map<std::string, int> reasons;
  int measured_count = 0, rejected_count = 0, missing_count = 0;
  for (const MeasuredPoint& p : measured.points) {
    if (p.kind != PointKind::kReseau) continue;
    measured_count += p.status == PointStatus::kMeasured;
    rejected_count += p.status == PointStatus::kRejected;
    missing_count += p.status == PointStatus::kMissing;
    for (const std::string& flag : p.flags) reasons[flag]++;
    const MeasuredPoint* t = truth.count(p.id) ? truth[p.id] : nullptr;
    const bool absent = !t || has_flag(*t, "absent");
    if (p.status != PointStatus::kMeasured) {
      if (t && !absent && mark_of[p.id] >= 0) {
        if (has_flag(*t, "damaged") || Touched(plate, plate.scene.marks[mark_of[p.id]])) {
          ++touched_rejected;
        } else if (std::hypot(t->crb_x_px.value_or(0), t->crb_y_px.value_or(0)) / std::sqrt(2.0) < kMeasurableCrbPx) {
          ++lost;
        }
      }
      continue;
    }
    if (absent) {
      ++false_points;
      continue;
    }
    const double dx = *p.x_px - *t->x_px, dy = *p.y_px - *t->y_px;
    if (std::hypot(dx, dy) > 3.0) {
      ++wrong_ids;
      continue;
    }
    const bool touched = has_flag(*t, "damaged") || Touched(plate, plate.scene.marks[mark_of[p.id]]);
    if (touched) {
      (std::abs(dx) <= 3 * *p.sigma_x_px && std::abs(dy) <= 3 * *p.sigma_y_px ? touched_within : touched_beyond)++;
      continue;
    }
    clean.Add(dx, dy, std::hypot(t->crb_x_px.value_or(0), t->crb_y_px.value_or(0)) / std::sqrt(2.0),
              std::hypot(*p.sigma_x_px, *p.sigma_y_px) / std::sqrt(2.0));
    baseline_targets.push_back({*t->x_px, *t->y_px});
  }
  // Baseline on the same crosses, searched around the truth (its best case).
  const std::string targets = dir + "/baseline.in", results = dir + "/baseline.out";
  {
    std::FILE* f = std::fopen(targets.c_str(), "w");
    for (const auto& [x, y] : baseline_targets) std::fprintf(f, "%.9f %.9f\n", x, y);
    std::fclose(f);
  }
  const double px_per_um = 1.0 / plate.pixel_size_um;
  const ToolRun baseline_run = RunProcess({self, "--baseline-child", scan, targets, results,
                                           std::to_string(grid.mark.line_width_um * px_per_um),
                                           std::to_string(grid.mark.arm_length_um * px_per_um), c.bright ? "1" : "0"},
                                          dir + "/baseline.log");
  if (std::FILE* f = std::fopen(results.c_str(), "r"); f && baseline_run.ok) {
    double x, y;
    int ok;
    for (size_t k = 0; k < baseline_targets.size() && std::fscanf(f, "%lf %lf %d", &x, &y, &ok) == 3; ++k) {
      if (ok) baseline.Add(x - baseline_targets[k].first, y - baseline_targets[k].second, clean.crb[k], 0);
    }
    std::fclose(f);
  }
  const double megapixels = image.info().width_px * static_cast<double>(image.info().height_px) / 1e6;
  std::printf("%-22s %6.1f %5d %4ld %4d %4d %4d %3d %3d %3d | %8.4f %8.4f %7.4f %7.4f %7.4f %6.2f %6.2f | %7.4f %6.2f %6.2f %6.0f MB | %3d %3d %3d | %6.2f %7.1f %6.1f",
              c.name.c_str(), plate.pixel_size_um, c.bits, image.info().width_px, measured_count, rejected_count,
              missing_count, lost, wrong_ids, false_points, Stats::Mean(clean.ex), Stats::Mean(clean.ey), clean.Rms(),
              clean.Max(), Stats::Median(clean.crb), clean.Rms() / Stats::Median(clean.crb),
              clean.Rms() / Stats::Median(clean.sigma), baseline.Rms(), baseline.Rms() / Stats::Median(baseline.crb),
              baseline_run.seconds, baseline_run.peak_rss_mb,
              touched_rejected, touched_within, touched_beyond, run.seconds, megapixels / run.seconds,
              measured_count / run.seconds);
  std::printf(" %6.0f MB  cpu %.1f s ", run.peak_rss_mb, run.cpu_seconds);
  for (const auto& [reason, count] : reasons) std::printf(" %s=%d", reason.c_str(), count);
  std::printf("\n");
  std::fflush(stdout);
}

std::vector<Case> AllCases() {
  std::vector<Case> cases;
  auto add = [&](Case c) { cases.push_back(c); };
  add({.name = "clean-10um"});
  add({.name = "clean-5um", .pixel_um = 5.0});
  add({.name = "clean-20um", .pixel_um = 20.0});
  add({.name = "noisy-10um", .noise_scale = 4.0});
  add({.name = "8bit-10um", .bits = 8});
  add({.name = "rot90-10um", .orientation_deg = 90});
  add({.name = "rot270-mirrored-10um", .orientation_deg = 270, .mirrored = true});
  add({.name = "bright-crosses-10um", .bright = true});
  add({.name = "degraded-10um", .degraded = true});
  add({.name = "degraded-rot180m-8bit", .bits = 8, .orientation_deg = 180, .mirrored = true, .degraded = true});
  // Faint grids on 8-bit negative scans (bright crosses), dust and scratches stronger than the crosses.
  add({.name = "faint4-rot90m-8bit", .bits = 8, .orientation_deg = 90, .mirrored = true, .bright = true,
       .degraded = true, .contrast_to_noise = 4.0});
  add({.name = "faint6-rot180-8bit", .bits = 8, .orientation_deg = 180, .bright = true, .degraded = true,
       .contrast_to_noise = 6.0});
  add({.name = "faint8-rot270m-8bit", .bits = 8, .orientation_deg = 270, .mirrored = true, .bright = true,
       .degraded = true, .contrast_to_noise = 8.0});
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 8 && std::string(argv[1]) == "--baseline-child") return BaselineChild(argv + 2);
  std::vector<Case> cases = AllCases();
  std::string keep;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (arg == "--cases") {
      std::vector<Case> chosen;
      std::stringstream list(next());
      for (std::string name; std::getline(list, name, ',');)
        for (const Case& c : AllCases())
          if (c.name == name) chosen.push_back(c);
      cases = chosen;
    } else if (arg == "--large") {
      Case large{.name = "large", .pixel_um = 7.5, .size_px = std::stol(next())};
      cases.push_back(large);
    } else if (arg == "--keep") {
      keep = next();
    } else {
      std::fprintf(stderr, "usage: %s [--cases a,b,...] [--large PX] [--keep DIR]\n", argv[0]);
      return 2;
    }
  }
  const std::string dir = keep.empty() ? (std::filesystem::temp_directory_path() / ("bench_reseau_" + std::to_string(getpid()))).string() : keep;
  std::filesystem::create_directories(dir);
  const DefinitionRegistry registry;
  const MasterGrid& grid = registry.Grid("ikogon-b");
  std::printf("columns: case, pixel um, bits, width px, measured, rejected, missing, lost (clean crosses with\n"
              "  CRB < %.2f px not measured), wrong ids, false points |\n"
              "  clean crosses: bias x, bias y, RMS (px, per axis), max |error|, median CRB, RMS/CRB, RMS/median sigma |\n"
              "  baseline (OpenCV imread + matchTemplate + paraboloid, own process) on the same crosses: RMS, RMS/CRB,\n"
              "    wall s, peak RSS |\n"
              "  crosses touched by dust/scratches/damage: rejected, measured within 3 sigma, beyond |\n"
              "  platemeter detect: wall s, Mpixel/s, crosses/s, peak RSS, CPU s (user+system); statuses with reasons\n",
              kMeasurableCrbPx);
  for (const Case& c : cases) {
    sim::SimulatedPlate plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(SpecText(c), c.name), registry);
    sim::ComputeCramerRaoBounds(&plate);
    const sim::SimulatedPlate kept = plate;
    const sim::SimulateOutputs outputs = sim::WriteSimulatedPlate(plate, dir);
    const ToolRun run = RunProcess({PLATEMETER_BIN, "detect", outputs.image_path, "--camera", "sn004-terrain", "-o", dir},
                                   dir + "/detect.log");
    if (!run.ok) {
      std::printf("%-22s platemeter detect FAILED (see %s/detect.log)\n", c.name.c_str(), dir.c_str());
      continue;
    }
    const std::string stem = std::filesystem::path(outputs.image_path).stem().string();
    Score(c, kept, outputs.image_path, grid, run, ReadMeasurementFile(dir + "/" + stem + ".measurements.csv"),
          std::filesystem::canonical("/proc/self/exe").string(), dir);
    if (keep.empty()) {
      std::filesystem::remove(outputs.image_path);
      std::filesystem::remove(outputs.truth_path);
      std::filesystem::remove(outputs.chain_path);
    }
  }
  if (keep.empty()) std::filesystem::remove_all(dir);
  return 0;
}
