// Duty-cycle trails on a simulated Orbigon star plate (seed 001): the shipped
// `platemeter detect --stars --trails-start-utc ...` run as its own process on
// a plate of catalog stars to V = 8 (kstars-data), scored against the
// simulator's truth: the share of trail dots found, assigned to the right star
// and trail and time-tagged correctly, wrong assignments, the dots' position
// error, the reseau crosses among the trails (measured, within 3 formal sigmas),
// wall time and peak RSS; SEP's extraction (bench_stars' child mode) on
// the same image for the throughput comparison.
//
//   bench_trails [--plate NAME | --family tune|report|all] [--pixel-um 20] [--mag-limit 8] [--rows N]
//                [--min-snr 10] [--keep DIR [--reuse | --rescore]] [--no-sep] [--lost FILE] [--crosses-only]
//                [--platemeter PATH] [--truth-near X,Y[;X,Y...]] [--list]
//   --reuse keeps a kept scan (the render is deterministic); --rescore also a kept detection (scores it again).
//   --plate NAME runs one plate of the family (trail_plates.h; --list shows them), default the benchmark plate
//   (Beltsville, 12 May 1972); --family runs the tuning plates, the held-out ones or all, and prints a summary.
//   --pixel-um, --mag-limit, --sensor-dn and --grain-dn override the plate's.
//   --platemeter PATH detects with that binary (a copy of another build: two builds compared on the same scans)
//   --truth-near X,Y;... lists the simulator's images within 6 px of those scan places (with --rescore: what
//   lies where a decoding went wrong)
//   --crosses-only detects and scores the reseau crosses only, in seconds.
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
#include <tuple>
#include <unordered_map>
#include <vector>

#include "bench_process.h"
#include "trail_plates.h"
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

constexpr double kTruthNear_px = 6.0;  // --truth-near's reach

// Seconds of `iso` after `start_utc`.
double Seconds(const std::string& iso, const std::string& start_utc) {
  const calib::UtcInstant t = calib::ParseUtcIso8601(iso), t0 = calib::ParseUtcIso8601(start_utc);
  return ((t.jd1 - t0.jd1) + (t.jd2 - t0.jd2)) * 86400.0;
}

// A truth trail image, reduced to what the score needs.
struct TruthImage {
  double x_px = 0, y_px = 0;
  bool dot = true;   // dot or dash
  int trail = 0, index = 0, star = 0;
  double mid_s = 0;  // s after the plate's start_utc
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

// What a run is asked for (the command line).
struct RunSettings {
  double min_snr = 10.0, isolation_fwhm = 3.0, ref_peak_dn = 60000.0;
  long band_rows = 0;
  std::string keep;  // keep the scan and the detection here (else a temporary directory)
  bool reuse = false, crosses_only = false, sep = true;
  bool rescore = false;      // --rescore: score a kept detection again (no detection run)
  FILE* lost_out = nullptr;  // --lost FILE
  std::string bench_stars;   // bench_stars' path (SEP's child mode)
  std::string platemeter = PLATEMETER_BIN;  // --platemeter PATH: another build's binary (a copy, to compare builds)
  std::vector<PixelPoint> truth_near;        // --truth-near X,Y[;X,Y...]: list the truth images about these places
};

// The plate's truth, reduced to what the score needs.
struct PlateTruth {
  std::vector<TruthImage> images;
  std::vector<TruthCross> crosses;
  std::vector<std::string> star_names;
  long width = 0, height = 0;
};

// One plate's figures (the family's summary).
struct PlateScore {
  bool ran = false;
  long measurable = 0, measurable_right = 0, wrong = 0, mixed = 0;
  double rms_norm = 0;  // RMS(error / sigma) of the measurable dots tagged right
  double detect_s = 0, rss_mb = 0;
  double RightPct() const { return 100.0 * measurable_right / std::max(1L, measurable); }
};

// Builds and renders the plate (the scan written band by band), and keeps its truth; the simulated plate is
// freed before detection so that the children's peak RSS (which counts the parent's resident pages at fork) is
// their own.
PlateTruth RenderPlate(const bench::TrailPlate& p, const RunSettings& run, const std::string& scan) {
  PlateTruth truth;
  auto t0 = std::chrono::steady_clock::now();
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(
      sim::ParseSimulationSpec(bench::TrailPlateSpec(p, run.ref_peak_dn), "bench_trails"), DefinitionRegistry());
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  long y_begin = 0, y_end = plate.scene.height_px;
  if (run.band_rows > 0 && run.band_rows < plate.scene.height_px) {
    y_begin = (plate.scene.height_px - run.band_rows) / 2;
    y_end = y_begin + run.band_rows;
  }
  truth.width = plate.scene.width_px;
  truth.height = y_end - y_begin;
  t0 = std::chrono::steady_clock::now();
  if (!(run.reuse && fs::exists(scan))) {  // the render is deterministic: --reuse keeps a kept scan
    ImageWriterOptions image = plate.image;
    image.height_px = truth.height;
    const sim::SceneRenderer renderer(plate.scene);
    ImageWriter writer(scan, image);
    const long band = image.tile_size_px > 0 ? writer.band_height_px() : 64;
    std::vector<float> values(static_cast<size_t>(band * truth.width));
    for (long y = 0; y < truth.height; y += band) {
      const long rows = std::min(band, truth.height - y);
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
      truth.crosses.push_back({t.id, *t.x_px, *t.y_px - static_cast<double>(y_begin)});
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
    r.mid_s = Seconds(t.mid_time_utc, p.start_utc);
    auto [it, added] = star_index.insert({t.star_id, static_cast<int>(truth.star_names.size())});
    if (added) truth.star_names.push_back(t.star_id);
    r.star = it->second;
    // Matched-filter SNR of a point image of this flux (an upper bound for a swept one).
    const double um_per_px = 1.0 / std::sqrt(std::abs(mark.px_from_um[0] * mark.px_from_um[3] -
                                                      mark.px_from_um[1] * mark.px_from_um[2]));
    const double s_px = std::hypot(mark.psf_fwhm_um / 2.3548 / um_per_px, noise.scanner_blur_sigma_px);
    r.snr = std::abs(mark.amplitude_dn) / (sigma_dn * std::sqrt(4.0 * M_PI) * s_px);
    r.length_px = std::hypot(mark.px_from_um[0] * mark.segment_u_um + mark.px_from_um[1] * mark.segment_v_um,
                             mark.px_from_um[2] * mark.segment_u_um + mark.px_from_um[3] * mark.segment_v_um);
    truth.images.push_back(r);
  }
  std::printf("plate %s: %ld x %ld px at %.1f um (%.0f Mpx), catalog stars to V = %.1f: %zu stars, %zu trail images; "
              "build %.1f s, render %.1f s\n",
              p.name.c_str(), truth.width, truth.height, p.pixel_um, truth.width * truth.height * 1e-6, p.mag_limit,
              truth.star_names.size(), truth.images.size(), build_s, render_s);
  return truth;
}

// Which truth dots count. Whole: of a trail lying wholly inside the scan (5 px margin). Measurable: whole, with
// a point-source SNR of at least min_snr (seed 001: "up to 25 measurable images" a trail; a V = 8 star's 0.6 s
// dots are not) and no other image of SNR >= 3 within isolation_fwhm FWHM (plus half its length). Complete:
// every dash and dot of the trail exposed on the format (a trail entering it after its leading run has no
// number of its own; only its siblings can tell it).
class DotCounting {
 public:
  DotCounting(std::vector<TruthImage>& images, const PlateTruth& truth, const bench::TrailPlate& plate,
              const RunSettings& run)
      : min_snr_(run.min_snr) {
    for (const TruthImage& t : images) {
      const bool in = t.x_px > 5 && t.y_px > 5 && t.x_px < truth.width - 6 && t.y_px < truth.height - 6;
      auto [it, added] = trail_inside_.insert({{t.star, t.trail}, in});
      if (!added) it->second = it->second && in;
      ++images_of_trail_[{t.star, t.trail}];
    }
    for (size_t t = 0; t < plate.leading_dashes.size(); ++t)
      complete_count_.push_back(25 + plate.leading_dashes[t] + 4);  // Table 1: 25 dots, 4 separators
    const double fwhm_px = plate.FwhmPx();
    double longest_px = 0;
    for (const TruthImage& t : images) longest_px = std::max(longest_px, t.length_px);
    const TruthIndex near(images, run.isolation_fwhm * fwhm_px + 0.5 * longest_px + 1.0);
    for (TruthImage& t : images) {
      t.isolated = true;
      near.ForNear(t.x_px, t.y_px, [&](const TruthImage& o) {
        if (&o != &t && o.snr >= 3.0 &&
            std::hypot(o.x_px - t.x_px, o.y_px - t.y_px) < run.isolation_fwhm * fwhm_px + 0.5 * o.length_px)
          t.isolated = false;
      });
    }
  }
  bool Whole(const TruthImage& t) const { return t.dot && trail_inside_.at({t.star, t.trail}); }
  bool Counted(const TruthImage& t) const { return Whole(t) && t.snr >= min_snr_ && t.isolated; }
  bool Complete(const TruthImage& t) const {
    return images_of_trail_.at({t.star, t.trail}) == complete_count_.at(static_cast<size_t>(t.trail - 1));
  }

 private:
  double min_snr_;
  std::map<std::pair<int, int>, bool> trail_inside_;    // (star, trail) -> every image inside
  std::map<std::pair<int, int>, int> images_of_trail_;  // (star, trail) -> images on the format
  std::vector<int> complete_count_;                     // images of a complete trail t (index t - 1)
};

// The tags of the measurement file against the truth.
struct TagScore {
  std::set<const TruthImage*> right;  // dots of whole trails tagged right
  std::map<const TruthImage*, std::string> found_star_of_dot;
  std::map<std::string, std::set<int>> truth_stars_of;  // found star -> truth stars
  std::set<int> wrong_stars;                            // truth stars with a wrong tag
  long wrong = 0, no_truth = 0, tagged = 0, blend_right = 0, flagged_bad = 0, mixed = 0, split = 0, n_err = 0;
  long coincident = 0;  // found stars holding a few images of a second star, or a close pair's (blends)
  double err2 = 0, norm2 = 0;
  // The right measurable dots' errors, all and by the dot's point-source SNR (kSnrEdges): a sigma honest at
  // every flux (#27's bar; the dots with a neighbour within 3 FWHM are not measurable).
  static constexpr double kSnrEdges[] = {0, 20, 50, 100, 300, 1000, 1e300};
  struct ErrorBin {
    long n = 0;
    double err2 = 0, norm2 = 0, sigma2 = 0;
    double RmsNorm() const { return std::sqrt(norm2 / std::max(1.0, 2.0 * n)); }
  };
  ErrorBin measurable, bins[6];
};

TagScore ScoreTags(const PlateTruth& truth, const DotCounting& counting, const MeasurementFile& measured,
                   const bench::TrailPlate& plate, double isolation_px, FILE* lost_out) {
  TagScore s;
  const TruthIndex index(truth.images, 4.0);
  const double fwhm_px = plate.FwhmPx();
  std::map<int, std::set<std::string>> found_stars_of;  // truth star -> found stars
  std::map<std::string, std::map<std::pair<int, int>, int>> truth_images_of;  // found star -> (truth star, trail)
                                                                            // -> images tagged right
  const std::vector<std::string>& names = truth.star_names;
  for (const MeasuredPoint& m : measured.points) {
    if (m.kind != PointKind::kTrailDot && m.kind != PointKind::kTrailDash) continue;
    // A tagged image the track fit flagged bad (displaced: a blend, a defect on it) is its trail's, but its
    // measured position is not: counted apart.
    if (m.status != PointStatus::kMeasured) {
      ++s.flagged_bad;
      continue;
    }
    ++s.tagged;
    const TruthImage* t = index.Nearest(*m.x_px, *m.y_px, 1.5);
    if (!t) {
      if (++s.no_truth <= 5) std::printf("  no truth image within 1.5 px: %s at %.2f %.2f\n", m.id.c_str(), *m.x_px, *m.y_px);
      continue;
    }
    const double m_mid_s = Seconds(m.mid_time_utc, plate.start_utc);
    auto tag_of = [&](const TruthImage& u) {
      return u.dot == (m.kind == PointKind::kTrailDot) && "T" + std::to_string(u.trail) == m.trail && u.index == m.dot &&
             std::abs(u.mid_s - m_mid_s) < 0.002;
    };
    // Two images within half a FWHM are one detection (a blend): a tag right for the other one is reported
    // apart, neither right nor wrong.
    bool blend_ok = false;
    const bool ok = tag_of(*t);
    if (!ok)
      index.ForNear(*m.x_px, *m.y_px, [&](const TruthImage& u) {
        blend_ok = blend_ok || (std::hypot(u.x_px - *m.x_px, u.y_px - *m.y_px) < 0.5 * fwhm_px && tag_of(u));
      });
    if (blend_ok) {
      ++s.blend_right;
      continue;
    }
    if (!ok) {
      ++s.wrong;
      s.wrong_stars.insert(t->star);
      if (lost_out) {
        std::fprintf(lost_out, "wrong %s T%d %c%d %.3f %.3f tagged %s %s\n", names[t->star].c_str(), t->trail,
                     t->dot ? 'D' : 'L', t->index, t->x_px, t->y_px, m.id.c_str(), m.mid_time_utc.c_str());
        index.ForNear(*m.x_px, *m.y_px, [&](const TruthImage& u) {
          const double d_px = std::hypot(u.x_px - *m.x_px, u.y_px - *m.y_px);
          if (d_px < 3.0)
            std::fprintf(lost_out, "  near %s T%d %c%d at %.3f %.3f: %.2f px (measured %.3f %.3f)\n",
                         names[u.star].c_str(), u.trail, u.dot ? 'D' : 'L', u.index, u.x_px, u.y_px, d_px, *m.x_px,
                         *m.y_px);
        });
      }
      if (s.wrong <= 10)
        std::printf("  wrong: %s-T%d-%c%d tagged %s %s\n", names[t->star].c_str(), t->trail, t->dot ? 'D' : 'L',
                    t->index, m.id.c_str(), m.mid_time_utc.c_str());
      continue;
    }
    // The star: counted from rightly tagged images only (a blend is reported above).
    s.truth_stars_of[m.star_id].insert(t->star);
    found_stars_of[t->star].insert(m.star_id);
    ++truth_images_of[m.star_id][{t->star, t->trail}];
    if (!counting.Whole(*t)) continue;
    s.right.insert(t);
    s.found_star_of_dot[t] = m.star_id;
    const double ex = *m.x_px - t->x_px, ey = *m.y_px - t->y_px;
    s.err2 += ex * ex + ey * ey;
    double norm2 = 0;
    if (m.sigma_x_px && m.sigma_y_px && *m.sigma_x_px > 0)
      norm2 = ex * ex / (*m.sigma_x_px * *m.sigma_x_px) + ey * ey / (*m.sigma_y_px * *m.sigma_y_px);
    s.norm2 += norm2;
    ++s.n_err;
    if (!counting.Counted(*t)) continue;
    int b = 0;
    while (b + 1 < 6 && t->snr >= TagScore::kSnrEdges[b + 1]) ++b;
    for (TagScore::ErrorBin* bin : {&s.measurable, &s.bins[b]}) {
      ++bin->n;
      bin->err2 += ex * ex + ey * ey;
      bin->norm2 += norm2;
      if (m.sigma_x_px && m.sigma_y_px) bin->sigma2 += *m.sigma_x_px * *m.sigma_x_px + *m.sigma_y_px * *m.sigma_y_px;
    }
  }
  // A found star mixes truth stars when it holds a trail of a second star (at least kMixedImages of that trail's
  // images tagged right) whose images lie further than the isolation radius from the first star's of the same
  // exposures: two stars closer than that make blended images (a pair on the sky), counted apart.
  constexpr int kMixedImages = 3;
  std::map<std::tuple<int, int, bool, int>, const TruthImage*> by_exposure;  // (star, trail, dot, index)
  std::vector<std::vector<const TruthImage*>> images_of_star(names.size());
  for (const TruthImage& t : truth.images) {
    by_exposure[{t.star, t.trail, t.dot, t.index}] = &t;
    images_of_star[static_cast<size_t>(t.star)].push_back(&t);
  }
  const auto apart = [&](int a, int b) {  // the nearest the two stars' images of one exposure come
    double nearest_px = 1e300;
    for (const TruthImage* image : images_of_star[static_cast<size_t>(a)]) {
      const TruthImage& t = *image;
      auto it = by_exposure.find({b, t.trail, t.dot, t.index});
      if (it != by_exposure.end()) nearest_px = std::min(nearest_px, std::hypot(it->second->x_px - t.x_px, it->second->y_px - t.y_px));
    }
    return nearest_px > isolation_px;
  };
  for (const auto& [found, truths] : s.truth_stars_of) {
    if (truths.size() < 2) continue;
    std::map<int, int> largest_trail;  // truth star -> its trail with the most images in this found star
    for (const auto& [truth_trail, count] : truth_images_of[found])
      largest_trail[truth_trail.first] = std::max(largest_trail[truth_trail.first], count);
    int major = largest_trail.begin()->first;
    for (const auto& [truth_star, count] : largest_trail)
      if (count > largest_trail[major]) major = truth_star;
    int stars_with_trail = 1;
    for (const auto& [truth_star, count] : largest_trail)
      stars_with_trail += truth_star != major && count >= kMixedImages && apart(major, truth_star);
    if (stars_with_trail < 2) {
      ++s.coincident;
      continue;
    }
    if (++s.mixed > 5) continue;
    std::printf("  found star %s holds right tags of", found.c_str());
    for (const auto& [truth_trail, count] : truth_images_of[found])
      std::printf(" %s-T%d (%d)", names[truth_trail.first].c_str(), truth_trail.second, count);
    std::printf("\n");
  }
  for (const auto& [t, founds] : found_stars_of) s.split += founds.size() > 1;
  return s;
}

// The measurable dots not right: the detection's reason (`trail:<reason>` on an unassigned image), and whether
// another trail of the star, or another dot of the same trail, was tagged right; --lost lists them.
void ReportLost(const PlateTruth& truth, const DotCounting& counting, const MeasurementFile& measured,
                const TagScore& s, FILE* lost_out) {
  std::set<std::pair<int, int>> trails_right;
  std::set<int> stars_right;
  for (const TruthImage* t : s.right) trails_right.insert({t->star, t->trail}), stars_right.insert(t->star);
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
  for (const TruthImage& t : truth.images) {
    if (!counting.Counted(t) || s.right.count(&t)) continue;
    const TruthImage* f = found_index.Nearest(t.x_px, t.y_px, 1.5);
    std::string why = "not detected";
    if (f) {
      const MeasuredPoint& m = *points[f->star];
      why = m.kind != PointKind::kStar ? "tagged as another image" : "no reason";
      for (const std::string& flag : m.flags)
        if (m.kind == PointKind::kStar && flag.rfind("trail:", 0) == 0) why = flag.substr(6);
    }
    why += trails_right.count({t.star, t.trail}) ? " (trail partly right)"
           : stars_right.count(t.star)           ? " (another trail of the star right)"
                                                 : " (nothing of the star right)";
    ++lost[why];
    if (lost_out) {
      std::fprintf(lost_out, "dot %s T%d %d %.3f %.3f %s [snr %.0f]\n", truth.star_names[t.star].c_str(), t.trail,
                   t.index, t.x_px, t.y_px, why.c_str(), t.snr);
      lost_stars.insert(t.star);
    }
  }
  if (lost_out)
    for (const TruthImage& t : truth.images)
      if (lost_stars.count(t.star) || s.wrong_stars.count(t.star))
        std::fprintf(lost_out, "%s %s T%d %d %.3f %.3f t=%.1f snr=%.0f len=%.1f%s%s\n", t.dot ? "img_dot" : "dash",
                     truth.star_names[t.star].c_str(), t.trail, t.index, t.x_px, t.y_px, t.mid_s, t.snr, t.length_px,
                     counting.Counted(t) ? " measurable" : "", s.right.count(&t) ? " right" : "");
  std::printf("measurable dots not right, by the detection's reason:\n");
  std::vector<std::pair<long, std::string>> rows;
  for (const auto& [why, n] : lost) rows.push_back({n, why});
  std::sort(rows.rbegin(), rows.rend());
  for (const auto& [n, why] : rows) std::printf("  %6ld %s\n", n, why.c_str());
}

// All dots of whole trails by SNR bin, the complete trails', and the measurable dots by the star's speed (its
// 20 s dash's length: slow stars near the pole merge their dashes).
void ReportBins(const PlateTruth& truth, const DotCounting& counting, const TagScore& s) {
  auto pct = [](long a, long b) { return 100.0 * a / std::max(1L, b); };
  const double edges[] = {5, 10, 20, 50, 100, 1e300};
  for (int b = 0; b + 1 < 6; ++b) {
    long n = 0, ok = 0;
    for (const TruthImage& t : truth.images) {
      if (!counting.Whole(t) || t.snr < edges[b] || t.snr >= edges[b + 1]) continue;
      ++n;
      ok += s.right.count(&t) > 0;
    }
    if (b + 2 < 6) std::printf("  SNR %3.0f-%-3.0f: %6ld dots, %6.2f %% right\n", edges[b], edges[b + 1], n, pct(ok, n));
    else std::printf("  SNR %3.0f+   : %6ld dots, %6.2f %% right\n", edges[b], n, pct(ok, n));
  }
  long n = 0, ok = 0;
  for (const TruthImage& t : truth.images)
    if (counting.Counted(t) && counting.Complete(t)) ++n, ok += s.right.count(&t) > 0;
  std::printf("  of complete trails (every dash and dot on the format): %ld of %ld right = %.2f %%\n", ok, n, pct(ok, n));
  std::map<int, double> dash_px_of_star;
  for (const TruthImage& t : truth.images)
    if (!t.dot) dash_px_of_star[t.star] = t.length_px;
  const double dash_edges_px[] = {0, 3, 6, 9, 12, 1e300};
  for (int b = 0; b + 1 < 6; ++b) {
    long count = 0, right = 0;
    for (const TruthImage& t : truth.images) {
      const double dash_px = dash_px_of_star[t.star];
      if (!counting.Counted(t) || dash_px < dash_edges_px[b] || dash_px >= dash_edges_px[b + 1]) continue;
      ++count;
      right += s.right.count(&t) > 0;
    }
    std::printf("  dash %2.0f-%-3.0f px: %6ld measurable dots, %6.2f %% right\n", dash_edges_px[b],
                std::min(99.0, dash_edges_px[b + 1]), count, pct(right, count));
  }
}

// SEP's extraction and ours alone on the same image (bench_stars' child mode), for the throughput.
void CompareWithSep(const RunSettings& run, const std::string& dir, const std::string& scan, const std::string& fwhm_px,
                    long pixels) {
  if (!run.sep || run.bench_stars.empty() || !fs::exists(run.bench_stars)) return;
  for (const char* which : {"ours", "sep"}) {
    const std::string result = dir + "/" + which + ".txt";
    const ToolRun r = RunProcess({run.bench_stars, "--detect", which, scan, result, fwhm_px}, dir + "/" + which + ".log");
    std::ifstream in(result);
    double total_s = 0, detect_s = 0;
    long rows_written = 0;  // bench_stars' child: the header holds the rows the detector wrote
    in >> total_s >> detect_s >> rows_written;
    long n = 0;
    for (double x, y, f; in >> x >> y >> f;) ++n;
    std::printf("%s star extraction on the same image: %ld sources, %.1f s (%.1f Mpx/s), peak RSS %.0f MB%s\n", which,
                n, total_s, pixels * 1e-6 / std::max(1e-9, total_s), r.peak_rss_mb, r.ok ? "" : " (FAILED)");
  }
}

// Renders, detects and scores one plate; prints its figures.
PlateScore RunPlate(const bench::TrailPlate& plate, const RunSettings& run) {
  PlateScore score;
  const std::string dir = run.keep.empty()
                              ? (fs::temp_directory_path() / ("bench_trails." + std::to_string(getpid()))).string()
                              : run.keep + "/" + plate.name;
  fs::create_directories(dir);
  char scan_name[160];
  std::snprintf(scan_name, sizeof scan_name, "%s-%gum-v%g-rows%ld", plate.name.c_str(), plate.pixel_um,
                plate.mag_limit, run.band_rows);
  const std::string scan = dir + "/" + scan_name + ".tif";
  PlateTruth truth = RenderPlate(plate, run, scan);
  malloc_trim(0);
  const DotCounting counting(truth.images, truth, plate, run);
  // (what lies at a place a decoding went wrong at, when the detections do not say: another star's dash, a dot)
  for (const PixelPoint& q : run.truth_near)
    for (const TruthImage& t : truth.images)
      if (std::hypot(t.x_px - q.x_px, t.y_px - q.y_px) < kTruthNear_px)
        std::printf("truth near %.1f %.1f: %s T%d %c%d at %.3f %.3f, t = %.1f s, SNR %.0f, %.1f px long\n", q.x_px,
                    q.y_px, truth.star_names[t.star].c_str(), t.trail, t.dot ? 'D' : 'L', t.index, t.x_px, t.y_px,
                    t.mid_s, t.snr, t.length_px);
  long whole_dots = 0;
  for (const TruthImage& t : truth.images) whole_dots += counting.Whole(t), score.measurable += counting.Counted(t);
  std::printf("dots of whole trails: %ld; measurable (SNR >= %.0f, isolated by %.1f FWHM): %ld\n", whole_dots,
              run.min_snr, run.isolation_fwhm, score.measurable);

  char fwhm_px[32];
  std::snprintf(fwhm_px, sizeof fwhm_px, "%.2f", plate.FwhmPx());
  const std::string out = dir + "/out";
  std::vector<std::string> args = {run.platemeter, "detect", scan, "--camera", "orbigon", "--orientation", "180m", "-o", out};
  if (!run.crosses_only)
    args.insert(args.end(), {"--stars", "--star-fwhm-px", fwhm_px, "--trails-start-utc", plate.start_utc,
                             "--trail-dashes", plate.DashesText(), "--trail-break-s", std::to_string(plate.break_s)});
  const std::string measurements = out + "/" + scan_name + ".measurements.csv";
  const ToolRun detect = run.rescore && fs::exists(measurements) ? ToolRun{true, 0, 0.0, 0.0, 0.0} : RunProcess(args, dir + "/detect.log");
  if (!detect.ok) {
    std::fprintf(stderr, "bench_trails: platemeter detect failed, see %s/detect.log\n", dir.c_str());
    return score;
  }
  score.ran = true;
  score.detect_s = detect.seconds;
  score.rss_mb = detect.peak_rss_mb;
  const MeasurementFile measured = ReadMeasurementFile(measurements);
  if (!run.crosses_only) {
    const TagScore s = ScoreTags(truth, counting, measured, plate, run.isolation_fwhm * plate.FwhmPx(), run.lost_out);
    score.wrong = s.wrong;
    score.mixed = s.mixed;
    score.rms_norm = s.measurable.RmsNorm();
    long right_star = 0, right_whole_star = 0;
    for (const TruthImage* t : s.right) {
      const bool one_star = s.truth_stars_of.at(s.found_star_of_dot.at(t)).size() == 1;
      right_whole_star += one_star;
      score.measurable_right += counting.Counted(*t);
      right_star += counting.Counted(*t) && one_star;
    }
    auto pct = [](long a, long b) { return 100.0 * a / std::max(1L, b); };
    std::printf("platemeter detect: %.1f s wall, %.1f s CPU, peak RSS %.0f MB, %.1f Mpx/s\n", detect.seconds,
                detect.cpu_seconds, detect.peak_rss_mb, truth.width * truth.height * 1e-6 / detect.seconds);
    std::printf("trail images tagged: %ld (and %ld flagged bad by the track fit); without a truth image within 1.5 px: "
                "%ld; wrong trail/dot/time: %ld; blends (another star's image within FWHM/2) tagged right for the "
                "other image: %ld\n",
                s.tagged, s.flagged_bad, s.no_truth, s.wrong, s.blend_right);
    std::printf("found stars mixing truth stars (a trail of each, apart on the sky): %ld; holding a second star's "
                "image or two, or a close pair (blends): %ld; truth stars split over several found stars: %ld\n",
                s.mixed, s.coincident, s.split);
    std::printf("MEASURABLE DOTS (V <= %.1f): %ld of %ld right (trail, dot, time) = %.2f %%; also in a found star "
                "holding one truth star: %ld = %.2f %%\n",
                plate.mag_limit, score.measurable_right, score.measurable, score.RightPct(), right_star,
                pct(right_star, score.measurable));
    std::printf("ALL DOTS of whole trails: %zu of %ld right = %.2f %%; with the right star: %ld = %.2f %%\n",
                s.right.size(), whole_dots, pct(static_cast<long>(s.right.size()), whole_dots), right_whole_star,
                pct(right_whole_star, whole_dots));
    ReportLost(truth, counting, measured, s, run.lost_out);
    ReportBins(truth, counting, s);
    if (s.n_err > 0)
      // The rows' positions: each image's own measurement (the track's until 2026-11-26: docs/detect.md).
      std::printf("right dots' position error (own measurement): RMS %.4f px per axis, RMS(error / sigma) %.2f; "
                  "the measurable ones': RMS(error / sigma) %.2f\n",
                  std::sqrt(s.err2 / (2.0 * s.n_err)), std::sqrt(s.norm2 / (2.0 * s.n_err)), score.rms_norm);
    for (int b = 0; b < 6; ++b) {
      const TagScore::ErrorBin& bin = s.bins[b];
      if (bin.n == 0) continue;
      std::printf("  measurable dots of SNR %4.0f-%-5.0f: %6ld, error RMS %.4f px, sigma RMS %.4f px, RMS(error / sigma) %.2f\n",
                  TagScore::kSnrEdges[b], std::min(99999.0, TagScore::kSnrEdges[b + 1]), bin.n,
                  std::sqrt(bin.err2 / (2.0 * bin.n)), std::sqrt(bin.sigma2 / (2.0 * bin.n)),
                  std::sqrt(bin.norm2 / (2.0 * bin.n)));
    }
  }
  ScoreCrosses(truth.crosses, measured);
  if (!run.crosses_only) CompareWithSep(run, dir, scan, fwhm_px, truth.width * truth.height);
  if (run.keep.empty()) fs::remove_all(dir);
  return score;
}

// The family's summary: one row per plate, the bars (#27) beside.
void PrintFamilySummary(const std::vector<bench::TrailPlate>& plates, const std::vector<PlateScore>& scores) {
  std::printf("\n%-22s %-6s %8s %8s %6s %6s %11s %8s %8s\n", "plate", "role", "measur.", "right %", "wrong", "mixed",
              "RMS(e/sig)", "detect s", "RSS MB");
  for (size_t i = 0; i < plates.size(); ++i) {
    const PlateScore& s = scores[i];
    if (!s.ran) {
      std::printf("%-22s %-6s FAILED\n", plates[i].name.c_str(), plates[i].role.c_str());
      continue;
    }
    std::printf("%-22s %-6s %8ld %8.2f %6ld %6ld %11.2f %8.1f %8.0f\n", plates[i].name.c_str(), plates[i].role.c_str(),
                s.measurable, s.RightPct(), s.wrong, s.mixed, s.rms_norm, s.detect_s, s.rss_mb);
  }
  std::printf("bars (#27): right >= 95 %%, wrong 0, mixed 0, RMS(error / sigma) in [0.8, 1.25]\n");
}

[[noreturn]] void Usage() {
  std::fprintf(stderr,
               "usage: bench_trails [--plate NAME | --family tune|report|all] [--pixel-um UM] [--mag-limit V] [--rows N] "
               "[--min-snr 10] [--isolation-fwhm 3] [--ref-peak-dn DN] [--sensor-dn DN] [--grain-dn DN] "
               "[--keep DIR [--reuse | --rescore]] [--no-sep] [--lost FILE] [--crosses-only] [--platemeter PATH] "
               "[--truth-near X,Y[;X,Y...]] [--list]\n");
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  RunSettings run;
  std::string plate_name = bench::TrailPlateFamily().front().name, family, lost_file;
  bench::TrailPlate overrides;  // -1: not given
  overrides.pixel_um = overrides.mag_limit = overrides.sensor_dn = overrides.grain_dn = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_trails: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--plate") plate_name = next();
    else if (a == "--family") family = next();
    else if (a == "--pixel-um") overrides.pixel_um = std::stod(next());
    else if (a == "--mag-limit") overrides.mag_limit = std::stod(next());
    else if (a == "--sensor-dn") overrides.sensor_dn = std::stod(next());
    else if (a == "--grain-dn") overrides.grain_dn = std::stod(next());
    else if (a == "--rows") run.band_rows = std::stol(next());
    else if (a == "--min-snr") run.min_snr = std::stod(next());
    else if (a == "--ref-peak-dn") run.ref_peak_dn = std::stod(next());
    else if (a == "--isolation-fwhm") run.isolation_fwhm = std::stod(next());
    else if (a == "--keep") run.keep = next();
    else if (a == "--crosses-only") run.crosses_only = true;
    else if (a == "--no-sep") run.sep = false;
    else if (a == "--reuse") run.reuse = true;
    else if (a == "--rescore") run.reuse = run.rescore = true;
    else if (a == "--lost") lost_file = next();
    else if (a == "--platemeter") run.platemeter = next();
    else if (a == "--truth-near") {
      const std::string places = next();
      for (size_t from = 0; from < places.size();) {
        const size_t to = std::min(places.find(';', from), places.size());
        PixelPoint q;
        if (std::sscanf(places.substr(from, to - from).c_str(), "%lf,%lf", &q.x_px, &q.y_px) != 2) {
          std::fprintf(stderr, "bench_trails: --truth-near takes X,Y[;X,Y...] in scan pixels, not %s\n", places.c_str());
          return 2;
        }
        run.truth_near.push_back(q);
        from = to + 1;
      }
    }
    else if (a == "--list") {
      for (const bench::TrailPlate& p : bench::TrailPlateFamily())
        std::printf("%-22s %-6s lat %5.1f start %s roll %5.0f axis alt %4.0f az %4.0f pixel %4.1f um FWHM %.2f px "
                    "noise %g/%g DN V <= %.1f break %.0f s dashes %s\n",
                    p.name.c_str(), p.role.c_str(), p.latitude_deg, p.start_utc.c_str(), p.roll_deg,
                    p.axis_altitude_deg, p.axis_azimuth_deg, p.pixel_um, p.FwhmPx(), p.sensor_dn, p.grain_dn,
                    p.mag_limit, p.break_s, p.DashesText().c_str());
      return 0;
    } else Usage();
  }
  std::vector<bench::TrailPlate> plates;
  for (const bench::TrailPlate& p : bench::TrailPlateFamily())
    if (family.empty() ? p.name == plate_name : (family == "all" || p.role == family)) plates.push_back(p);
  if (plates.empty()) {
    std::fprintf(stderr, "bench_trails: no plate %s%s (--list names them; --family takes tune, report or all)\n",
                 family.empty() ? "named " : "in family ", family.empty() ? plate_name.c_str() : family.c_str());
    return 2;
  }
  for (bench::TrailPlate& p : plates) {
    if (overrides.pixel_um > 0) p.pixel_um = overrides.pixel_um;
    if (overrides.mag_limit > 0) p.mag_limit = overrides.mag_limit;
    if (overrides.sensor_dn >= 0) p.sensor_dn = overrides.sensor_dn;
    if (overrides.grain_dn >= 0) p.grain_dn = overrides.grain_dn;
  }
  if (!lost_file.empty() && !(run.lost_out = std::fopen(lost_file.c_str(), "w"))) {  // before the long run
    std::fprintf(stderr, "bench_trails: cannot write %s\n", lost_file.c_str());
    return 2;
  }
  if (!fs::exists(calib::DefaultStarCatalogPath())) {
    std::fprintf(stderr, "bench_trails: %s is missing (scripts/setup installs kstars-data)\n",
                 calib::DefaultStarCatalogPath().c_str());
    return 2;
  }
  run.bench_stars = (fs::path(argv[0]).parent_path() / "bench_stars").string();
  if (plates.size() > 1) run.sep = false;  // the family measures the decoder; SEP's comparison is the benchmark plate's
  std::vector<PlateScore> scores;
  for (const bench::TrailPlate& p : plates) {
    scores.push_back(RunPlate(p, run));
    std::fflush(stdout);
  }
  if (run.lost_out) std::fclose(run.lost_out);
  if (plates.size() > 1 || !family.empty()) PrintFamilySummary(plates, scores);
  for (const PlateScore& s : scores)
    if (!s.ran) return 1;
  return 0;
}
