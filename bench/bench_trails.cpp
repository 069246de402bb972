// Duty-cycle trails on a simulated Orbigon star plate (seed 001): the shipped
// `platemeter detect --stars --trails-start-utc ...` run as its own process on
// a plate of catalog stars to V = 8 (kstars-data), scored against the
// simulator's truth: the share of trail dots found, assigned to the right star
// and trail and time-tagged correctly, wrong assignments, the dots' position
// error, the reseau crosses among the trails (measured, within 3 formal sigmas),
// wall time and peak RSS; SEP's extraction (bench_stars' child mode) on
// the same image for the throughput comparison.
//
//   bench_trails [--pixel-um 20] [--mag-limit 8] [--rows N] [--min-snr 20] [--keep DIR [--reuse]] [--no-sep]
//                [--crosses-only]   (detect and score the reseau crosses only, in seconds)
//   --rows N renders only N rows through the middle of the plate (trails cut by
//   the band's edges are not counted); default the whole plate.
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_process.h"
#include "platemeter/calib/apparent_place.h"
#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/image_writer.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/render.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace {

using platemeter::bench::RunProcess;
using platemeter::bench::ToolRun;

using namespace platemeter;
namespace fs = std::filesystem;

constexpr const char* kStartUtc = "1972-05-12T05:30:00Z";

// samples/specs/orbigon-stellar.toml with the magnitude limit and pixel size of the run; no reseau
// defects (they are reseau matters), the same star field, thermal and emulsion effects, noise.
std::string SpecText(double pixel_um, double mag_limit, double ref_peak_dn, double sensor_dn, double grain_dn) {
  return R"(
name = "orbigon-trails"
camera = "orbigon"
seed = 1
[output]
pixel_size_um = )" + std::to_string(pixel_um) + R"(
margin_mm = 3.0
bits = 16
[thermal]
temperature_degC = 22.0
[emulsion]
depth_um = 21.0
refractive_index = 1.65
[film]
affine_ppm = [3.0, 0.0, 0.0, 2.0]
[scanner]
non_orthogonality_arcsec = -4.3
rotation_deg = 0.1
orientation_deg = 180
mirrored = true
[marks.reseau]
polarity = "bright"
contrast_dn = 12000.0
[stars]
reference_magnitude = 5.0
reference_peak_dn = )" + std::to_string(ref_peak_dn) + R"(
fwhm_um = 30.0
[star_field]
latitude_deg = 39.03
longitude_deg = -76.93
height_m = 50.0
start_utc = ")" + kStartUtc + R"("
temperature_degC = 11.7
relative_humidity = 0.7
wavelength_um = 0.45
roll_deg = 180.0
magnitude_limit = )" + std::to_string(mag_limit) + R"(
exposure = "duty_cycle"
leading_dashes = [2, 3, 4, 5]
break_s = 480.0
reference_exposure_s = 10.0
[background]
level_dn = 40000.0
vignetting_fraction = 0.12
vignetting_radius_mm = 80.6
[noise]
blur_sigma_um = 8.0
sensor_sigma_dn = )" + std::to_string(sensor_dn) + R"(
grain_sigma_dn = )" + std::to_string(grain_dn) + R"(
)";
}


double Seconds(const std::string& iso) {
  const calib::UtcInstant t = calib::ParseUtcIso8601(iso), t0 = calib::ParseUtcIso8601(kStartUtc);
  return ((t.jd1 - t0.jd1) + (t.jd2 - t0.jd2)) * 86400.0;
}

// A truth trail image, reduced to what the score needs.
struct TruthImage {
  double x_px = 0, y_px = 0;
  bool dot = true;   // dot or dash
  int trail = 0, index = 0, star = 0;
  double mid_s = 0;  // s after kStartUtc
  double snr = 0;    // matched-filter SNR of a point image of the same flux
  double length_px = 0;  // length of the swept segment
  bool isolated = false;
};

// Truth trail images by position (spatial hash; a search reaches one cell around).
class TruthIndex {
 public:
  TruthIndex(const std::vector<TruthImage>& points, double cell_px) : points_(points), cell_px_(cell_px) {
    for (size_t i = 0; i < points.size(); ++i) cells_[Key(points[i].x_px, points[i].y_px)].push_back(i);
  }
  const TruthImage* Nearest(double x, double y, double radius) const {
    const TruthImage* best = nullptr;
    double bd = radius;
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells_.find(Pack(Cell(x) + dx, Cell(y) + dy));
        if (it == cells_.end()) continue;
        for (size_t i : it->second) {
          const double d = std::hypot(points_[i].x_px - x, points_[i].y_px - y);
          if (d < bd) bd = d, best = &points_[i];
        }
      }
    return best;
  }
  template <class F>
  void ForNear(double x, double y, F f) const {
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells_.find(Pack(Cell(x) + dx, Cell(y) + dy));
        if (it != cells_.end())
          for (size_t i : it->second) f(points_[i]);
      }
  }

 private:
  long Cell(double v) const { return static_cast<long>(std::floor(v / cell_px_)); }
  static long long Pack(long x, long y) { return (static_cast<long long>(x) << 32) ^ (y & 0xffffffffLL); }
  long long Key(double x, double y) const { return Pack(Cell(x), Cell(y)); }
  const std::vector<TruthImage>& points_;
  double cell_px_;
  std::unordered_map<long long, std::vector<size_t>> cells_;
};

// A reseau cross of the truth, inside the scanned rows.
struct TruthCross {
  std::string id;
  double x_px = 0, y_px = 0;
};

// The crosses among the trails (#26: crosses that star images lie on): how many
// measured, their errors against their formal sigmas, and the others' reasons.
void ScoreCrosses(const std::vector<TruthCross>& crosses, const MeasurementFile& measured) {
  std::map<std::string, const TruthCross*> truth;
  for (const TruthCross& c : crosses) truth[c.id] = &c;
  long count = 0, within = 0;
  double norm2 = 0, worst = 0;
  std::map<std::string, long> reasons;
  for (const MeasuredPoint& p : measured.points) {
    if (p.kind != PointKind::kReseau || !truth.count(p.id)) continue;
    if (p.status != PointStatus::kMeasured) {
      for (const std::string& flag : p.flags) ++reasons[flag];
      continue;
    }
    const TruthCross& t = *truth[p.id];
    const double zx = (*p.x_px - t.x_px) / *p.sigma_x_px, zy = (*p.y_px - t.y_px) / *p.sigma_y_px;
    ++count;
    within += std::abs(zx) <= 3.0 && std::abs(zy) <= 3.0;
    if (std::abs(zx) > 3.0 || std::abs(zy) > 3.0)
      std::printf("  cross %s beyond 3 sigma: error (%.3f, %.3f) px, sigma (%.3f, %.3f) px\n", p.id.c_str(),
                  *p.x_px - t.x_px, *p.y_px - t.y_px, *p.sigma_x_px, *p.sigma_y_px);
    norm2 += zx * zx + zy * zy;
    worst = std::max({worst, std::abs(zx), std::abs(zy)});
  }
  std::printf("reseau crosses in the scan: %zu; measured %ld, of which within 3 formal sigmas %ld; RMS(error / sigma) "
              "%.2f, largest |error| / sigma %.1f; not measured:",
              crosses.size(), count, within, std::sqrt(norm2 / std::max(1L, 2 * count)), worst);
  for (const auto& [reason, n] : reasons) std::printf(" %s=%ld", reason.c_str(), n);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  double pixel_um = 20.0, mag_limit = 8.0, min_snr = 10.0, ref_peak_dn = 60000.0, sensor_dn = 30.0, grain_dn = 60.0;
  double isolation_fwhm = 3.0;
  long band_rows = 0;
  std::string keep, lost_file;  // --lost FILE: every measurable dot not right, and every image of its star (time, SNR, length, measurable, right: for debugging)
  bool sep = true, reuse = false, crosses_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_trails: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--pixel-um") pixel_um = std::stod(next());
    else if (a == "--mag-limit") mag_limit = std::stod(next());
    else if (a == "--rows") band_rows = std::stol(next());
    else if (a == "--min-snr") min_snr = std::stod(next());
    else if (a == "--ref-peak-dn") ref_peak_dn = std::stod(next());
    else if (a == "--sensor-dn") sensor_dn = std::stod(next());
    else if (a == "--grain-dn") grain_dn = std::stod(next());
    else if (a == "--isolation-fwhm") isolation_fwhm = std::stod(next());
    else if (a == "--keep") keep = next();
    else if (a == "--crosses-only") crosses_only = true;
    else if (a == "--no-sep") sep = false;
    else if (a == "--reuse") reuse = true;
    else if (a == "--lost") lost_file = next();
    else {
      std::fprintf(stderr, "usage: bench_trails [--pixel-um 20] [--mag-limit 8] [--rows N] [--min-snr 20] [--keep DIR [--reuse]] [--no-sep] [--lost FILE] [--crosses-only]\n");
      return 2;
    }
  }
  FILE* lost_out = lost_file.empty() ? nullptr : std::fopen(lost_file.c_str(), "w");  // before the long run
  if (!lost_file.empty() && !lost_out) {
    std::fprintf(stderr, "bench_trails: cannot write %s\n", lost_file.c_str());
    return 2;
  }
  if (!fs::exists(calib::DefaultStarCatalogPath())) {
    std::fprintf(stderr, "bench_trails: %s is missing (scripts/setup installs kstars-data)\n",
                 calib::DefaultStarCatalogPath().c_str());
    return 2;
  }
  const std::string dir = keep.empty() ? (fs::temp_directory_path() / ("bench_trails." + std::to_string(getpid()))).string() : keep;
  fs::create_directories(dir);

  // ---- the plate: built, rendered and reduced to the truth the score needs, then freed, so that the
  // children's peak RSS (which counts the parent's resident pages at fork) is their own.
  std::vector<TruthImage> truth_images;
  std::vector<TruthCross> truth_crosses;
  std::vector<std::string> star_names;
  long width = 0, height = 0;
  char scan_name[96];
  std::snprintf(scan_name, sizeof scan_name, "orbigon-trails-%gum-v%g-rows%ld", pixel_um, mag_limit, band_rows);
  const std::string scan = dir + "/" + scan_name + ".tif";
  {
    auto t0 = std::chrono::steady_clock::now();
    sim::SimulatedPlate plate = sim::BuildSimulatedPlate(
        sim::ParseSimulationSpec(SpecText(pixel_um, mag_limit, ref_peak_dn, sensor_dn, grain_dn), "bench_trails"), DefinitionRegistry());
    const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    long y_begin = 0, y_end = plate.scene.height_px;
    if (band_rows > 0 && band_rows < plate.scene.height_px) {
      y_begin = (plate.scene.height_px - band_rows) / 2;
      y_end = y_begin + band_rows;
    }
    width = plate.scene.width_px;
    height = y_end - y_begin;
    t0 = std::chrono::steady_clock::now();
    if (!(reuse && fs::exists(scan))) {  // the render is deterministic: --reuse keeps a kept scan
      ImageWriterOptions image = plate.image;
      image.height_px = height;
      const sim::SceneRenderer renderer(plate.scene);
      ImageWriter writer(scan, image);
      const long band = image.tile_size_px > 0 ? writer.band_height_px() : 64;
      std::vector<float> values(static_cast<size_t>(band * width));
      for (long y = 0; y < height; y += band) {
        const long rows = std::min(band, height - y);
        renderer.RenderBand(y_begin + y, rows, values.data());
        writer.WriteBand(y, rows, values.data());
      }
      writer.Finish();
    }
    const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const sim::SceneNoise& noise = plate.scene.noise;
    const double sigma_dn = std::hypot(noise.sensor_sigma_dn, noise.grain_sigma_dn);
    std::map<std::string, int> star_index;
    for (const MeasuredPoint& t : plate.truth) {
      const bool inside = t.x_px && *t.y_px > static_cast<double>(y_begin) + 40 && *t.y_px < static_cast<double>(y_end) - 40;
      if (t.kind == PointKind::kReseau && t.flags.empty() && inside)
        truth_crosses.push_back({t.id, *t.x_px, *t.y_px - static_cast<double>(y_begin)});
    }
    for (size_t i = 0; i < plate.truth.size(); ++i) {
      const MeasuredPoint& t = plate.truth[i];
      if ((t.kind != PointKind::kTrailDot && t.kind != PointKind::kTrailDash) || plate.truth_mark[i] < 0) continue;
      const sim::SceneMark& mark = plate.scene.marks[static_cast<size_t>(plate.truth_mark[i])];
      TruthImage r;
      r.x_px = *t.x_px;
      r.y_px = *t.y_px - static_cast<double>(y_begin);
      r.dot = t.kind == PointKind::kTrailDot;
      r.trail = std::stoi(t.trail.substr(1));
      r.index = static_cast<int>(*t.dot);
      r.mid_s = Seconds(t.mid_time_utc);
      auto [it, added] = star_index.insert({t.star_id, static_cast<int>(star_names.size())});
      if (added) star_names.push_back(t.star_id);
      r.star = it->second;
      // Matched-filter SNR of a point image of this flux (an upper bound for a swept one).
      const double um_per_px = 1.0 / std::sqrt(std::abs(mark.px_from_um[0] * mark.px_from_um[3] -
                                                        mark.px_from_um[1] * mark.px_from_um[2]));
      const double s_px = std::hypot(mark.psf_fwhm_um / 2.3548 / um_per_px, noise.scanner_blur_sigma_px);
      r.snr = std::abs(mark.amplitude_dn) / (sigma_dn * std::sqrt(4.0 * M_PI) * s_px);
      r.length_px = std::hypot(mark.px_from_um[0] * mark.segment_u_um + mark.px_from_um[1] * mark.segment_v_um,
                               mark.px_from_um[2] * mark.segment_u_um + mark.px_from_um[3] * mark.segment_v_um);
      truth_images.push_back(r);
    }
    std::printf("plate: %ld x %ld px at %.1f um (%.0f Mpx), catalog stars to V = %.1f: %zu stars, %zu trail images; "
                "build %.1f s, render %.1f s\n",
                width, height, pixel_um, width * height * 1e-6, mag_limit, star_names.size(), truth_images.size(),
                build_s, render_s);
  }
  malloc_trim(0);

  // The dots counted: those of trails lying wholly inside the scan (5 px margin) with a point-source SNR of
  // at least min_snr (seed 001: "up to 25 measurable images" a trail; a V = 8 star's 0.6 s dots are not).
  std::map<std::pair<int, int>, bool> trail_inside;  // (star, trail) -> every image inside
  for (const TruthImage& t : truth_images) {
    const bool in = t.x_px > 5 && t.y_px > 5 && t.x_px < width - 6 && t.y_px < height - 6;
    auto [it, added] = trail_inside.insert({{t.star, t.trail}, in});
    if (!added) it->second = it->second && in;
  }
  const double blur_um = 8.0, fwhm_um = std::sqrt(30.0 * 30.0 + std::pow(2.3548 * blur_um, 2));
  const double fwhm_px_value = fwhm_um / pixel_um;
  {
    double longest_px = 0;
    for (const TruthImage& t : truth_images) longest_px = std::max(longest_px, t.length_px);
    const TruthIndex near(truth_images, isolation_fwhm * fwhm_px_value + 0.5 * longest_px + 1.0);
    for (TruthImage& t : truth_images) {
      t.isolated = true;
      near.ForNear(t.x_px, t.y_px, [&](const TruthImage& o) {
        if (&o != &t && o.snr >= 3.0 &&
            std::hypot(o.x_px - t.x_px, o.y_px - t.y_px) < isolation_fwhm * fwhm_px_value + 0.5 * o.length_px)
          t.isolated = false;
      });
    }
  }
  auto whole = [&](const TruthImage& t) { return t.dot && trail_inside[{t.star, t.trail}]; };
  // Complete trails: every dash and dot exposed on the format (a trail entering it after its leading run has
  // no number of its own; only its siblings can tell it). The spec above: trail t has t + 1 leading dashes.
  std::map<std::pair<int, int>, int> images_of_trail;
  for (const TruthImage& t : truth_images) ++images_of_trail[{t.star, t.trail}];
  auto complete = [&](const TruthImage& t) { return images_of_trail[{t.star, t.trail}] == 25 + (t.trail + 1) + 4; };
  auto counted = [&](const TruthImage& t) { return whole(t) && t.snr >= min_snr && t.isolated; };
  long whole_dots = 0, counted_dots = 0;
  for (const TruthImage& t : truth_images) {
    whole_dots += whole(t);
    counted_dots += counted(t);
  }
  std::printf("dots of whole trails: %ld; measurable (SNR >= %.0f, isolated by %.1f FWHM): %ld\n", whole_dots, min_snr,
              isolation_fwhm, counted_dots);

  // ---- platemeter detect
  char fwhm_px[32];
  std::snprintf(fwhm_px, sizeof fwhm_px, "%.2f", fwhm_px_value);
  const std::string out = dir + "/out";
  std::vector<std::string> detect_args = {PLATEMETER_BIN, "detect", scan, "--camera", "orbigon", "--orientation", "180m", "-o", out};
  if (!crosses_only) detect_args.insert(detect_args.end(), {"--stars", "--star-fwhm-px", fwhm_px, "--trails-start-utc", kStartUtc});
  const ToolRun run = RunProcess(detect_args, dir + "/detect.log");
  if (!run.ok) {
    std::fprintf(stderr, "bench_trails: platemeter detect failed, see %s/detect.log\n", dir.c_str());
    return 1;
  }
  const MeasurementFile measured = ReadMeasurementFile(out + "/" + scan_name + ".measurements.csv");
  if (crosses_only) {  // the reseau crosses do not depend on the star images' detection
    ScoreCrosses(truth_crosses, measured);
    if (keep.empty()) fs::remove_all(dir);
    return 0;
  }

  // ---- score
  const TruthIndex index(truth_images, 4.0);
  std::set<const TruthImage*> right;
  long wrong = 0, no_truth = 0, tagged = 0, blend_right = 0, flagged_bad = 0;
  std::map<std::string, std::set<int>> truth_stars_of;  // found star -> truth stars
  std::map<int, std::set<std::string>> found_stars_of;  // truth star -> found stars
  std::map<std::string, std::map<std::pair<int, int>, int>> truth_images_of;  // found star -> (truth star, trail)
                                                                            // -> images tagged right
  std::map<const TruthImage*, std::string> found_star_of_dot;
  std::set<int> wrong_stars;  // truth stars with a wrong tag (--lost lists their dashes)
  double err2 = 0, norm2 = 0;
  long n_err = 0;
  for (const MeasuredPoint& m : measured.points) {
    if (m.kind != PointKind::kTrailDot && m.kind != PointKind::kTrailDash) continue;
    // A tagged image the track fit flagged bad (displaced: a blend, a defect on it) is its trail's, but its
    // measured position is not: counted apart.
    if (m.status != PointStatus::kMeasured) {
      ++flagged_bad;
      continue;
    }
    ++tagged;
    const TruthImage* t = index.Nearest(*m.x_px, *m.y_px, 1.5);
    if (!t) {
      if (++no_truth <= 5) std::printf("  no truth image within 1.5 px: %s at %.2f %.2f\n", m.id.c_str(), *m.x_px, *m.y_px);
      continue;
    }
    auto tag_of = [&](const TruthImage& u) {
      return u.dot == (m.kind == PointKind::kTrailDot) && "T" + std::to_string(u.trail) == m.trail && u.index == m.dot &&
             std::abs(u.mid_s - Seconds(m.mid_time_utc)) < 0.002;
    };
    const bool ok = tag_of(*t);
    // Two images within half a FWHM are one detection (a blend): a tag right for the other one is reported
    // apart, neither right nor wrong.
    bool blend_ok = false;
    if (!ok)
      index.ForNear(*m.x_px, *m.y_px, [&](const TruthImage& u) {
        blend_ok = blend_ok || (std::hypot(u.x_px - *m.x_px, u.y_px - *m.y_px) < 0.5 * fwhm_px_value && tag_of(u));
      });
    if (blend_ok) {
      ++blend_right;
      continue;
    }
    if (!ok) {
      ++wrong;
      wrong_stars.insert(t->star);
      if (lost_out)
        std::fprintf(lost_out, "wrong %s T%d %c%d %.3f %.3f tagged %s %s\n", star_names[t->star].c_str(), t->trail,
                     t->dot ? 'D' : 'L', t->index, t->x_px, t->y_px, m.id.c_str(), m.mid_time_utc.c_str());
      if (lost_out)
        index.ForNear(*m.x_px, *m.y_px, [&](const TruthImage& u) {
          const double d_px = std::hypot(u.x_px - *m.x_px, u.y_px - *m.y_px);
          if (d_px < 3.0)
            std::fprintf(lost_out, "  near %s T%d %c%d at %.3f %.3f: %.2f px (measured %.3f %.3f)\n",
                         star_names[u.star].c_str(), u.trail, u.dot ? 'D' : 'L', u.index, u.x_px, u.y_px, d_px, *m.x_px,
                         *m.y_px);
        });
      if (wrong <= 10)
        std::printf("  wrong: %s-T%d-%c%d tagged %s %s\n", star_names[t->star].c_str(), t->trail, t->dot ? 'D' : 'L',
                    t->index, m.id.c_str(), m.mid_time_utc.c_str());
      continue;
    }
    // The star: counted from rightly tagged images only (a blend is reported above).
    truth_stars_of[m.star_id].insert(t->star);
    found_stars_of[t->star].insert(m.star_id);
    ++truth_images_of[m.star_id][{t->star, t->trail}];
    if (!whole(*t)) continue;
    right.insert(t);
    found_star_of_dot[t] = m.star_id;
    const double ex = *m.x_px - t->x_px, ey = *m.y_px - t->y_px;
    err2 += ex * ex + ey * ey;
    if (m.sigma_x_px && m.sigma_y_px && *m.sigma_x_px > 0)
      norm2 += ex * ex / (*m.sigma_x_px * *m.sigma_x_px) + ey * ey / (*m.sigma_y_px * *m.sigma_y_px);
    ++n_err;
  }
  long mixed = 0, split = 0;
  for (const auto& [found, truths] : truth_stars_of) {
    if (truths.size() < 2) continue;
    if (++mixed > 5) continue;
    std::printf("  found star %s holds right tags of", found.c_str());
    for (const auto& [truth, count] : truth_images_of[found])
      std::printf(" %s-T%d (%d)", star_names[truth.first].c_str(), truth.second, count);
    std::printf("\n");
  }
  for (const auto& [t, founds] : found_stars_of) split += founds.size() > 1;
  // The right star: the found star holds this truth star's images only.
  long right_measurable = 0, right_measurable_star = 0, right_whole_star = 0;
  for (const TruthImage* t : right) {
    const bool one_star = truth_stars_of[found_star_of_dot[t]].size() == 1;
    right_whole_star += one_star;
    right_measurable += counted(*t);
    right_measurable_star += counted(*t) && one_star;
  }
  std::printf("platemeter detect: %.1f s wall, %.1f s CPU, peak RSS %.0f MB, %.1f Mpx/s\n", run.seconds,
              run.cpu_seconds, run.peak_rss_mb, width * height * 1e-6 / run.seconds);
  std::printf("trail images tagged: %ld (and %ld flagged bad by the track fit); without a truth image within 1.5 px: "
              "%ld; wrong trail/dot/time: %ld; blends (another star's image within FWHM/2) tagged right for the other "
              "image: %ld\n",
              tagged, flagged_bad, no_truth, wrong, blend_right);
  std::printf("found stars mixing truth stars: %ld; truth stars split over several found stars: %ld\n", mixed, split);
  auto pct = [](long a, long b) { return 100.0 * a / std::max(1L, b); };
  std::printf("MEASURABLE DOTS (V <= %.1f): %ld of %ld right (trail, dot, time) = %.2f %%; also in a found star "
              "holding one truth star: %ld = %.2f %%\n",
              mag_limit, right_measurable, counted_dots, pct(right_measurable, counted_dots), right_measurable_star,
              pct(right_measurable_star, counted_dots));
  std::printf("ALL DOTS of whole trails: %zu of %ld right = %.2f %%; with the right star: %ld = %.2f %%\n", right.size(),
              whole_dots, pct(static_cast<long>(right.size()), whole_dots), right_whole_star,
              pct(right_whole_star, whole_dots));
  // The measurable dots not right: the detection's reason (`trail:<reason>` on an unassigned image), and
  // whether another trail of the star, or another dot of the same trail, was tagged right.
  {
    std::set<std::pair<int, int>> trails_right;
    std::set<int> stars_right;
    for (const TruthImage* t : right) trails_right.insert({t->star, t->trail}), stars_right.insert(t->star);
    std::vector<const MeasuredPoint*> points;
    std::vector<TruthImage> at;  // the measured points as a searchable set (index = position in `points`)
    for (const MeasuredPoint& m : measured.points)
      if (m.x_px && m.y_px && (m.kind == PointKind::kStar || m.kind == PointKind::kTrailDot || m.kind == PointKind::kTrailDash)) {
        TruthImage u;
        u.x_px = *m.x_px, u.y_px = *m.y_px, u.star = static_cast<int>(points.size());
        points.push_back(&m);
        at.push_back(u);
      }
    const TruthIndex found_index(at, 4.0);
    std::map<std::string, long> lost;
    std::set<int> lost_stars;
    for (const TruthImage& t : truth_images) {
      if (!counted(t) || right.count(&t)) continue;
      const TruthImage* f = found_index.Nearest(t.x_px, t.y_px, 1.5);
      std::string why = "not detected";
      if (f) {
        const MeasuredPoint& m = *points[f->star];
        why = m.kind != PointKind::kStar ? "tagged as another image" : "no reason";
        for (const std::string& flag : m.flags)
          if (m.kind == PointKind::kStar && flag.rfind("trail:", 0) == 0) why = flag.substr(6);
      }
      why += trails_right.count({t.star, t.trail}) ? " (trail partly right)" : stars_right.count(t.star) ? " (another trail of the star right)" : " (nothing of the star right)";
      ++lost[why];
      if (lost_out) {
        std::fprintf(lost_out, "dot %s T%d %d %.3f %.3f %s [snr %.0f]\n", star_names[t.star].c_str(), t.trail, t.index,
                     t.x_px, t.y_px, why.c_str(), t.snr);
        lost_stars.insert(t.star);
      }
    }
    if (lost_out) {
      for (const TruthImage& t : truth_images)
        if (lost_stars.count(t.star) || wrong_stars.count(t.star))
          std::fprintf(lost_out, "%s %s T%d %d %.3f %.3f t=%.1f snr=%.0f len=%.1f%s%s\n", t.dot ? "img_dot" : "dash",
                       star_names[t.star].c_str(), t.trail, t.index, t.x_px, t.y_px, t.mid_s, t.snr, t.length_px,
                       counted(t) ? " measurable" : "", right.count(&t) ? " right" : "");
      std::fclose(lost_out);
    }
    std::printf("measurable dots not right, by the detection's reason:\n");
    std::vector<std::pair<long, std::string>> rows;
    for (const auto& [why, n] : lost) rows.push_back({n, why});
    std::sort(rows.rbegin(), rows.rend());
    for (const auto& [n, why] : rows) std::printf("  %6ld %s\n", n, why.c_str());
  }
  // All dots of whole trails by SNR bin (what is lost, and where).
  const double edges[] = {5, 10, 20, 50, 100, 1e300};
  for (int b = 0; b + 1 < 6; ++b) {
    long n = 0, ok = 0;
    for (const TruthImage& t : truth_images) {
      if (!whole(t) || t.snr < edges[b] || t.snr >= edges[b + 1]) continue;
      ++n;
      ok += right.count(&t) > 0;
    }
    if (b + 2 < 6) std::printf("  SNR %3.0f-%-3.0f: %6ld dots, %6.2f %% right\n", edges[b], edges[b + 1], n, 100.0 * ok / std::max(1L, n));
    else std::printf("  SNR %3.0f+   : %6ld dots, %6.2f %% right\n", edges[b], n, 100.0 * ok / std::max(1L, n));
  }
  {
    long n = 0, ok = 0;
    for (const TruthImage& t : truth_images)
      if (counted(t) && complete(t)) ++n, ok += right.count(&t) > 0;
    std::printf("  of complete trails (every dash and dot on the format): %ld of %ld right = %.2f %%\n", ok, n,
                pct(ok, n));
  }
  // Measurable dots by the star's speed (its 20 s dash's length): slow stars near the pole merge their dashes.
  {
    std::map<int, double> dash_px_of_star;
    for (const TruthImage& t : truth_images)
      if (!t.dot) dash_px_of_star[t.star] = t.length_px;
    const double dash_edges_px[] = {0, 3, 6, 9, 12, 1e300};
    for (int b = 0; b + 1 < 6; ++b) {
      long n = 0, ok = 0;
      for (const TruthImage& t : truth_images) {
        const double dash_px = dash_px_of_star[t.star];
        if (!counted(t) || dash_px < dash_edges_px[b] || dash_px >= dash_edges_px[b + 1]) continue;
        ++n;
        ok += right.count(&t) > 0;
      }
      std::printf("  dash %2.0f-%-3.0f px: %6ld measurable dots, %6.2f %% right\n", dash_edges_px[b],
                  std::min(99.0, dash_edges_px[b + 1]), n, pct(ok, n));
    }
  }
  if (n_err > 0)
    // The rows' positions: each image's own measurement (the track's until 2026-11-26: docs/detect.md).
    std::printf("right dots' position error (own measurement): RMS %.4f px per axis, RMS(error / sigma) %.2f\n",
                std::sqrt(err2 / (2.0 * n_err)), std::sqrt(norm2 / (2.0 * n_err)));

  ScoreCrosses(truth_crosses, measured);

  // ---- SEP on the same image (bench_stars' child mode), for the throughput
  const std::string bench_stars = (fs::path(argv[0]).parent_path() / "bench_stars").string();
  if (sep && fs::exists(bench_stars)) {
    for (const char* which : {"ours", "sep"}) {
      const std::string result = dir + "/" + which + ".txt";
      const ToolRun r = RunProcess({bench_stars, "--detect", which, scan, result, fwhm_px}, dir + "/" + which + ".log");
      std::ifstream in(result);
      double total_s = 0, detect_s = 0;
      long rows_written = 0;  // bench_stars' child: the header holds the rows the detector wrote
      in >> total_s >> detect_s >> rows_written;
      long n = 0;
      for (double x, y, f; in >> x >> y >> f;) ++n;
      std::printf("%s star extraction on the same image: %ld sources, %.1f s (%.1f Mpx/s), peak RSS %.0f MB%s\n",
                  which, n, total_s, width * height * 1e-6 / std::max(1e-9, total_s), r.peak_rss_mb, r.ok ? "" : " (FAILED)");
    }
  }
  if (keep.empty()) fs::remove_all(dir);
  return 0;
}
