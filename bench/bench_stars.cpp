// Star detection on a simulator star plate with exact truth, against SEP (the
// SExtractor engine as a C library) on the same image in the same program:
// completeness, false detections, centroid RMS / Cramer-Rao bound per SNR bin
// for isolated stars, close pairs (3..6 px), saturated stars, throughput and
// peak RSS. The plate: SN-004 stellar format (24 mm) with dark Ikotar B reseau
// crosses, dark dust and scratches, random stars over a wide magnitude range
// and explicit close pairs.
//
//   bench_stars [--pixel-um 10] [--stars 2000] [--width-px A:B] [--given-fwhm-px F] [--keep DIR] [--no-sep]
//   --width-px A:B: star images whose Gaussian sigma grows from A px at the plate's centre to B px at
//   the farthest star (a wide-angle lens, focus and tilt; issue #26), scored per width bin too; the
//   detectors are given the centre's width, or F (--given-fwhm-px: a user's guess, e.g. the default 2.5).
//   (BENCH_STARS_VERBOSE=1 lists every pair star)
//   bench_stars --detect ours|sep IMAGE OUT.csv FWHM_PX   (child mode)
//
// Each detector runs as its own process (fork + exec), so its time and peak
// RSS are its own; both read the scan through platemeter's Image.
#include <cstddef>  // sep.h uses size_t without including it

extern "C" {
#include <sep.h>
}
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "platemeter/core/image.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/render_crb.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"

namespace {

using namespace platemeter;

bool Verbose() {
  const char* v = std::getenv("BENCH_STARS_VERBOSE");
  return v && *v && std::string(v) != "0";
}

struct Detection {
  double x = 0, y = 0;
  unsigned flags = 0;
};

// ---- child mode: one detector on one image, results to a CSV
int RunDetector(const std::string& which, const std::string& path, const std::string& out, double fwhm_px) {
  const auto t0 = std::chrono::steady_clock::now();
  const Image image = Image::Open(path);
  std::vector<Detection> found;
  double detect_s = 0;
  long rows = 0;  // what the detector writes: ours also rejected rows, SEP its catalogue
  if (which == "ours") {
    StarDetectorOptions o;
    o.psf_fwhm_px = fwhm_px;
    const auto t1 = std::chrono::steady_clock::now();
    for (const DetectedStar& s : DetectStars(image, o)) {
      ++rows;
      if (s.point.status == PointStatus::kMeasured)
        found.push_back({s.point.position_px.x_px, s.point.position_px.y_px, s.flags});
    }
    detect_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  } else {
    const long w = image.info().width_px, h = image.info().height_px;
    std::vector<float> data(static_cast<size_t>(w * h));
    image.ReadRowsDirect(0, h, data.data());
    for (float& v : data) v = -v;  // dark stars on a negative: SEP finds positive sources
    const auto t1 = std::chrono::steady_clock::now();
    sep_image im{};
    im.data = data.data();
    im.dtype = SEP_TFLOAT;
    im.w = static_cast<int>(w);
    im.h = static_cast<int>(h);
    sep_bkg* bkg = nullptr;
    if (sep_background(&im, 64, 64, 3, 3, 0.0, &bkg) != 0) return 2;
    const float rms = sep_bkg_globalrms(bkg);
    sep_bkg_subarray(bkg, data.data(), SEP_TFLOAT);
    sep_set_extract_pixstack(1000000);
    const float conv[9] = {1, 2, 1, 2, 4, 2, 1, 2, 1};
    sep_catalog* cat = nullptr;
    const int status = sep_extract(&im, 1.5f * rms, SEP_THRESH_ABS, 5, conv, 3, 3, SEP_FILTER_CONV, 32, 0.005, 1, 1.0, &cat);
    if (status != 0) {
      char msg[128];
      sep_get_errmsg(status, msg);
      std::fprintf(stderr, "sep_extract: %s\n", msg);
      return 2;
    }
    im.noiseval = rms;
    im.noise_type = SEP_NOISE_STDDEV;
    const double sig = fwhm_px / 2.3548;
    for (int i = 0; i < cat->nobj; ++i) {
      double xw = cat->x[i], yw = cat->y[i];
      int niter = 0;
      short flag = 0;
      sep_windowed(&im, cat->x[i], cat->y[i], sig, 0, 0, &xw, &yw, &niter, &flag);
      found.push_back({xw, yw, static_cast<unsigned>(cat->flag[i])});
    }
    sep_catalog_free(cat);
    sep_bkg_free(bkg);
    detect_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  }
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::FILE* f = std::fopen(out.c_str(), "w");
  if (!f) return 3;
  if (which != "ours") rows = static_cast<long>(found.size());
  std::fprintf(f, "%.4f %.4f %ld\n", total_s, detect_s, rows);
  for (const Detection& d : found) std::fprintf(f, "%.5f %.5f %u\n", d.x, d.y, d.flags);
  std::fclose(f);
  return 0;
}

struct Run {
  bool ok = false;
  double wall_s = 0, total_s = 0, detect_s = 0, peak_rss_mb = 0;
  long rows = 0;
  std::vector<Detection> found;
};

Run RunChild(const std::string& self, const std::string& which, const std::string& image, const std::string& out,
             double fwhm_px) {
  Run run;
  std::fflush(stdout);
  std::fflush(stderr);
  const auto start = std::chrono::steady_clock::now();
  const std::string fwhm = std::to_string(fwhm_px);
  const pid_t child = fork();
  if (child == 0) {
    const char* argv[] = {self.c_str(), "--detect", which.c_str(), image.c_str(), out.c_str(), fwhm.c_str(), nullptr};
    execv(argv[0], const_cast<char**>(argv));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(child, &status, 0, &usage);
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.peak_rss_mb = usage.ru_maxrss / 1024.0;
  run.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  std::ifstream in(out);
  in >> run.total_s >> run.detect_s >> run.rows;
  Detection d;
  while (in >> d.x >> d.y >> d.flags) run.found.push_back(d);
  return run;
}

// Joint Cramer-Rao bound of a pair: Fisher information of
// b + F1 g(x - x1, y - y1) + F2 g(x - x2, y - y2), g the pixel-integrated
// Gaussian of the true sigma, white noise; returns the variance of each star's
// position along the pair axis (written here independently of the detector).
std::pair<double, double> PairAxisCrb(double x1, double y1, double f1, double x2, double y2, double f2, double s,
                                      double variance) {
  auto g1 = [s](double u, double c) {
    return 0.5 * (std::erf((u + 0.5 - c) / (std::sqrt(2.0) * s)) - std::erf((u - 0.5 - c) / (std::sqrt(2.0) * s)));
  };
  auto model = [&](double u, double v, const double* q) {
    return q[0] + q[3] * g1(u, q[1]) * g1(v, q[2]) + q[6] * g1(u, q[4]) * g1(v, q[5]);
  };
  const double q0[7] = {0, x1, y1, f1, x2, y2, f2};
  Eigen::Matrix<double, 7, 7> fisher = Eigen::Matrix<double, 7, 7>::Zero();
  const long u0 = long(std::floor(std::min(x1, x2) - 6 * s - 3)), u1 = long(std::ceil(std::max(x1, x2) + 6 * s + 3));
  const long v0 = long(std::floor(std::min(y1, y2) - 6 * s - 3)), v1 = long(std::ceil(std::max(y1, y2) + 6 * s + 3));
  for (long v = v0; v <= v1; ++v)
    for (long u = u0; u <= u1; ++u) {
      Eigen::Matrix<double, 7, 1> d;
      for (int k = 0; k < 7; ++k) {
        double qp[7], qm[7];
        std::copy(q0, q0 + 7, qp), std::copy(q0, q0 + 7, qm);
        const double h = (k == 3 || k == 6 || k == 0) ? 1.0 : 1e-4;
        qp[k] += h, qm[k] -= h;
        d(k) = (model(u, v, qp) - model(u, v, qm)) / (2 * h);
      }
      fisher += d * d.transpose() / variance;
    }
  const Eigen::Matrix<double, 7, 7> cov = fisher.inverse();
  const double sep = std::hypot(x2 - x1, y2 - y1), nx = (x2 - x1) / sep, ny = (y2 - y1) / sep;
  auto axis = [&](int i) { return nx * nx * cov(i, i) + 2 * nx * ny * cov(i, i + 1) + ny * ny * cov(i + 1, i + 1); };
  return {axis(1), axis(4)};
}

struct TruthStar {
  double x = 0, y = 0, snr = 0, crb_x = 0, crb_y = 0;
  double sigma_px = 0;  // the image's true Gaussian sigma (PSF and scanner blur)
  bool saturated = false, isolated = true, pair = false;
  double pair_sep = 0, nx = 0, ny = 0;  // pair: separation, unit vector to the neighbour
  double pair_crb_axis = 0;             // pair: joint CRB along the pair axis (px)
  std::string id;
};

const double kBins[] = {10, 30, 100, 300, 1000, 3000, 1e9};
const double kWidthBins[] = {0, 1.3, 1.5, 1.7, 1.9, 1e9};  // true sigma, px

void Score(const char* name, const Run& run, const std::vector<TruthStar>& truth,
           const std::vector<std::pair<double, double>>& marks, long pixels) {
  std::printf("\n== %s: %zu detections (%ld rows written), %.2f s total (%.2f s detection), %.1f Mpixel/s, peak RSS %.0f MB%s\n",
              name, run.found.size(), run.rows, run.total_s, run.detect_s, pixels / 1e6 / run.total_s, run.peak_rss_mb,
              run.ok ? "" : "  (FAILED)");
  auto nearest = [&](double x, double y, double r) {
    int best = -1;
    for (size_t i = 0; i < run.found.size(); ++i) {
      const double d = std::hypot(run.found[i].x - x, run.found[i].y - y);
      if (d < r) r = d, best = static_cast<int>(i);
    }
    return best;
  };
  // Isolated single stars in a bin (by `value` of the star in [lo, hi)): count, found within 1.5 px,
  // RMS / CRB; printed with the bin's label.
  auto score_bin = [&](const char* label, auto value, double lo, double hi, double min_snr) {
    int n = 0, found = 0;
    double s2 = 0;
    for (const TruthStar& t : truth) {
      if (!t.isolated || t.pair || t.saturated || t.snr < min_snr || value(t) < lo || value(t) >= hi) continue;
      ++n;
      const int k = nearest(t.x, t.y, 1.5);
      if (k < 0) continue;
      ++found;
      const double ex = run.found[k].x - t.x, ey = run.found[k].y - t.y;
      s2 += ex * ex / (t.crb_x * t.crb_x) + ey * ey / (t.crb_y * t.crb_y);
    }
    if (n > 0)
      std::printf("  %-22s %5d  %5.1f %%   %6.3f\n", label, n, 100.0 * found / n, found ? std::sqrt(s2 / (2 * found)) : 0.0);
  };
  std::printf("  isolated stars by SNR    N   found   RMS/CRB\n");
  for (int b = 0; b + 1 < int(std::size(kBins)); ++b) {
    const std::string label = std::to_string(long(kBins[b])) + ".." + std::to_string(long(std::min(kBins[b + 1], 99999.0)));
    score_bin(label.c_str(), [](const TruthStar& t) { return t.snr; }, kBins[b], kBins[b + 1], 0.0);
  }
  bool varying = false;
  for (const TruthStar& t : truth) varying = varying || std::abs(t.sigma_px - truth.front().sigma_px) > 0.05;
  if (varying) {
    std::printf("  isolated stars by width  N   found   RMS/CRB  (true sigma px, SNR >= 10)\n");
    for (int b = 0; b + 1 < int(std::size(kWidthBins)); ++b) {
      char label[32];
      std::snprintf(label, sizeof label, "%.1f..%.1f", kWidthBins[b], std::min(kWidthBins[b + 1], 9.9));
      score_bin(label, [](const TruthStar& t) { return t.sigma_px; }, kWidthBins[b], kWidthBins[b + 1], 10.0);
    }
  }
  // Close pairs: both found, RMS along the pair axis, mean drift toward the neighbour.
  int members = 0, found = 0;
  double drift = 0, d2 = 0, c2 = 0;
  for (const TruthStar& t : truth) {
    if (!t.pair) continue;
    ++members;
    const int k = nearest(t.x, t.y, 0.4 * t.pair_sep);
    if (k < 0) {
      if (Verbose()) std::printf("    %s sep %.2f snr %.0f MISSED at %.1f %.1f\n", t.id.c_str(), t.pair_sep, t.snr, t.x, t.y);
      continue;
    }
    ++found;
    const double e = (run.found[k].x - t.x) * t.nx + (run.found[k].y - t.y) * t.ny;
    if (Verbose())
      std::printf("    %s at %.1f %.1f sep %.2f snr %.0f err_axis %+.4f crb_axis %.4f flags %u\n", t.id.c_str(), t.x, t.y, t.pair_sep, t.snr, e,
                  t.pair_crb_axis, run.found[k].flags);
    drift += e, d2 += e * e, c2 += t.pair_crb_axis * t.pair_crb_axis;
  }
  if (members)
    std::printf("  close pairs 3..6 px: %d of %d stars found (%.1f %%), mean drift toward the neighbour %+.3f px, "
                "RMS along the axis %.4f px = %.2f x the joint CRB\n",
                found, members, 100.0 * found / members, found ? drift / found : 0, found ? std::sqrt(d2 / found) : 0,
                found ? std::sqrt(d2 / c2) : 0);
  int sat = 0, sat_found = 0;
  double sat2 = 0;
  for (const TruthStar& t : truth) {
    if (!t.saturated || !t.isolated) continue;
    ++sat;
    const int k = nearest(t.x, t.y, 1.5);
    if (k < 0) continue;
    ++sat_found;
    sat2 += std::pow(run.found[k].x - t.x, 2) + std::pow(run.found[k].y - t.y, 2);
  }
  if (sat)
    std::printf("  saturated isolated stars: %d of %d found, position RMS %.4f px\n", sat_found, sat,
                sat_found ? std::sqrt(sat2 / (2 * sat_found)) : 0.0);
  // False detections: farther than 3 px from every true star.
  int false_n = 0, on_marks = 0;
  for (const Detection& d : run.found) {
    bool real = false;
    for (const TruthStar& t : truth)
      if (std::hypot(d.x - t.x, d.y - t.y) < 3.0) real = true;
    if (real) continue;
    ++false_n;
    for (const auto& m : marks)
      if (std::hypot(d.x - m.first, d.y - m.second) < 15) {
        ++on_marks;
        break;
      }
  }
  std::printf("  false detections: %d (%.2f %% of detections), %d of them on reseau crosses\n", false_n,
              run.found.empty() ? 0.0 : 100.0 * false_n / run.found.size(), on_marks);
  // Faint completeness at SNR 10..30 over all (also non-isolated) single stars.
}

// --width-px: every star image's Gaussian sigma (PSF and the scanner's blur_px) from min_px at the
// plate's centre growing linearly with the distance to max_px at the farthest star; sigma_px per mark.
void WidenStarImages(double min_px, double max_px, double blur_px, double pixel_um, sim::SimulatedPlate* plate,
                     std::vector<double>* sigma_px) {
  const double cx = 0.5 * plate->scene.width_px, cy = 0.5 * plate->scene.height_px;
  std::vector<int> stars;  // their scene marks
  for (size_t i = 0; i < plate->truth.size(); ++i)
    if (plate->truth[i].kind == PointKind::kStar && plate->truth_mark[i] >= 0) stars.push_back(plate->truth_mark[i]);
  auto radius = [&](int mark) {
    const sim::SceneMark& m = plate->scene.marks[mark];
    return std::hypot(m.centre_px.x_px - cx, m.centre_px.y_px - cy);
  };
  double r_max = 0;
  for (int mark : stars) r_max = std::max(r_max, radius(mark));
  for (int mark : stars) {
    const double sigma = min_px + (max_px - min_px) * radius(mark) / r_max;
    (*sigma_px)[mark] = sigma;
    plate->scene.marks[mark].psf_fwhm_um = 2.3548 * std::sqrt(sigma * sigma - blur_px * blur_px) * pixel_um;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 6 && std::string(argv[1]) == "--detect") return RunDetector(argv[2], argv[3], argv[4], std::stod(argv[5]));
  double pixel_um = 10.0;
  int stars = 2000;
  std::string keep;
  bool run_sep = true;
  double width_min_px = 0, width_max_px = 0;  // --width-px: 0 = every star the bench's width
  double given_fwhm_px = 0;                    // --given-fwhm-px: 0 = the true (centre's) FWHM
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--no-sep") {  // SEP cannot take arrays over 2 GB (large scans)
      run_sep = false;
      continue;
    }
    if (i + 1 >= argc) break;
    if (a == "--pixel-um") pixel_um = std::stod(argv[i + 1]);
    else if (a == "--stars") stars = std::stoi(argv[i + 1]);
    else if (a == "--keep") keep = argv[i + 1];
    else if (a == "--given-fwhm-px") given_fwhm_px = std::stod(argv[i + 1]);
    else if (a == "--width-px" && std::sscanf(argv[i + 1], "%lf:%lf", &width_min_px, &width_max_px) != 2) {
      std::fprintf(stderr, "bench_stars: --width-px takes A:B (Gaussian sigma in px)\n");
      return 2;
    }
    ++i;
  }
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::string dir = keep.empty() ? (std::filesystem::temp_directory_path() / "bench_stars").string() : keep;
  std::filesystem::create_directories(dir);
  // Star sigma: FWHM 2 px on the plate and a 0.5 px scanner blur (in pixels of this scan).
  const double psf_sigma_um = 2.0 * pixel_um / 2.3548, blur_um = 0.5 * pixel_um;
  const double fwhm_px = 2.3548 * std::hypot(psf_sigma_um, blur_um) / pixel_um;
  std::ostringstream spec;
  spec << "name = \"bench-stars\"\ncamera = \"sn004-stellar\"\nseed = 23\n[output]\npixel_size_um = " << pixel_um
       << "\nmargin_mm = 1.0\nbits = 16\n[marks.reseau]\npolarity = \"dark\"\ncontrast_dn = 12000.0\n"
       << "[stars]\nreference_magnitude = 6.0\nreference_peak_dn = 40000.0\nfwhm_um = " << 2.0 * pixel_um
       << "\npolarity = \"dark\"\ncount = " << stars << "\nmagnitude_min = 3.0\nmagnitude_max = 13.0\n";
  // Close pairs on a grid between the reseau crosses: separations 3..6 px, equal and unequal.
  int pairs = 0;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      const double x = -9.5 + 1.9 * i + 0.41, y = -9.5 + 1.9 * j + 0.67;
      const double sep_px = 3.0 + 3.0 * ((i * 10 + j) % 7) / 6.0, angle = 0.61 * (i * 10 + j);
      const double dx = 0.5 * sep_px * pixel_um / 1000 * std::cos(angle), dy = 0.5 * sep_px * pixel_um / 1000 * std::sin(angle);
      const double mag_b = 7.0 + 0.5 * ((i + j) % 3);
      spec << "[[stars.star]]\nid = \"PA" << pairs << "\"\nx_mm = " << x + dx << "\ny_mm = " << y + dy << "\nmagnitude = 7.0\n";
      spec << "[[stars.star]]\nid = \"PB" << pairs << "\"\nx_mm = " << x - dx << "\ny_mm = " << y - dy << "\nmagnitude = " << mag_b << "\n";
      ++pairs;
    }
  spec << "[background]\nlevel_dn = 50000.0\n[noise]\nblur_sigma_um = " << blur_um << "\nsensor_sigma_dn = 20.0\n"
       << "[defects]\ndust_count = 40\ndust_diameter_min_um = " << 6 * pixel_um << "\ndust_diameter_max_um = " << 30 * pixel_um
       << "\ndust_contrast_dn = 8000.0\nscratch_count = 6\nscratch_polarity = \"dark\"\nscratch_width_um = " << 2 * pixel_um
       << "\n";

  const DefinitionRegistry registry;
  const auto t0 = std::chrono::steady_clock::now();
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(spec.str(), "bench spec"), registry);
  // The true sigma of every star image, px (--width-px: growing with the distance from the centre).
  const double blur_px = blur_um / pixel_um;
  std::vector<double> star_sigma_px(plate.scene.marks.size(), std::hypot(psf_sigma_um, blur_um) / pixel_um);
  if (width_max_px > 0) {
    if (!(width_min_px > blur_px && width_max_px >= width_min_px)) {
      std::fprintf(stderr, "bench_stars: --width-px needs %.2f < A <= B\n", blur_px);
      return 2;
    }
    WidenStarImages(width_min_px, width_max_px, blur_px, pixel_um, &plate, &star_sigma_px);
  }
  const double start_fwhm_px = given_fwhm_px > 0 ? given_fwhm_px : width_max_px > 0 ? 2.3548 * width_min_px : fwhm_px;
  const std::vector<sim::MarkCramerRao> crb = sim::CramerRaoBounds(plate.scene);
  const std::string image_path = sim::WriteSimulatedPlate(plate, dir).image_path;
  const Image image = Image::Open(image_path);
  const long pixels = image.info().width_px * image.info().height_px;
  std::printf("plate: %ld x %ld px 16-bit, %.0f um pixels, star FWHM %.2f..%.2f px (detectors given %.2f), rendered in %.1f s; %s\n",
              image.info().width_px, image.info().height_px, pixel_um, width_max_px > 0 ? 2.3548 * width_min_px : fwhm_px,
              width_max_px > 0 ? 2.3548 * width_max_px : fwhm_px, start_fwhm_px,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), image_path.c_str());

  std::vector<TruthStar> truth;
  std::vector<std::pair<double, double>> marks;  // reseau crosses
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& p = plate.truth[i];
    if (!p.x_px) continue;
    if (p.kind == PointKind::kReseau) marks.push_back({*p.x_px, *p.y_px});
    if (p.kind != PointKind::kStar || plate.truth_mark[i] < 0) continue;
    if (*p.x_px < 5 || *p.y_px < 5 || *p.x_px > image.info().width_px - 6 || *p.y_px > image.info().height_px - 6) continue;
    const sim::MarkCramerRao& c = crb[plate.truth_mark[i]];
    TruthStar t;
    t.x = *p.x_px, t.y = *p.y_px;
    t.snr = std::abs(plate.scene.marks[plate.truth_mark[i]].amplitude_dn) / c.sigma_amplitude_dn;
    t.crb_x = c.sigma_x_px, t.crb_y = c.sigma_y_px;
    t.sigma_px = star_sigma_px[plate.truth_mark[i]];
    t.id = p.id;
    t.saturated = std::find(p.flags.begin(), p.flags.end(), "saturated") != p.flags.end();
    t.pair = p.id.rfind("PA", 0) == 0 || p.id.rfind("PB", 0) == 0;
    truth.push_back(t);
  }
  // Isolation: no other star within 15 px, no cross within 25 px. Pair geometry.
  std::map<std::string, size_t> by_id;
  for (size_t i = 0; i < truth.size(); ++i) by_id[truth[i].id] = i;
  for (TruthStar& t : truth) {
    for (const TruthStar& u : truth)
      if (&u != &t && std::hypot(u.x - t.x, u.y - t.y) < 15.0 && !(t.pair && u.pair && u.id.substr(2) == t.id.substr(2)))
        t.isolated = false;
    for (const auto& m : marks)
      if (std::hypot(m.first - t.x, m.second - t.y) < 25) t.isolated = false;
    if (t.pair) {
      const std::string other = (t.id[1] == 'A' ? "PB" : "PA") + t.id.substr(2);
      if (!by_id.count(other)) { t.pair = false; continue; }
      const TruthStar& o = truth[by_id[other]];
      t.pair_sep = std::hypot(o.x - t.x, o.y - t.y);
      t.nx = (o.x - t.x) / t.pair_sep, t.ny = (o.y - t.y) / t.pair_sep;
    }
  }
  // Dust and scratches (scene geometry): stars on them are not isolated.
  int on_defects = 0;
  for (TruthStar& t : truth) {
    bool near = false;
    for (int i : plate.dust) {
      const sim::SceneMark& m = plate.scene.marks[i];
      const double r_px = 0.5 * m.size_um * std::hypot(m.px_from_um[0], m.px_from_um[2]);
      if (std::hypot(m.centre_px.x_px - t.x, m.centre_px.y_px - t.y) < r_px + 8) near = true;
    }
    for (int i : plate.scratches) {
      const sim::SceneMark& m = plate.scene.marks[i];
      const double hu = 0.5 * m.size_um * std::cos(m.corner_angle_rad), hv = 0.5 * m.size_um * std::sin(m.corner_angle_rad);
      const double ex = m.px_from_um[0] * hu + m.px_from_um[1] * hv, ey = m.px_from_um[2] * hu + m.px_from_um[3] * hv;
      const double len2 = ex * ex + ey * ey;
      double f = ((t.x - m.centre_px.x_px) * ex + (t.y - m.centre_px.y_px) * ey) / len2;
      f = std::clamp(f, -1.0, 1.0);
      const double w_px = 0.5 * m.line_width_um * std::hypot(m.px_from_um[0], m.px_from_um[2]);
      if (std::hypot(m.centre_px.x_px + f * ex - t.x, m.centre_px.y_px + f * ey - t.y) < w_px + 8) near = true;
    }
    if (near) t.isolated = false, ++on_defects;
  }
  for (TruthStar& t : truth)
    if (t.pair && !t.isolated) t.pair = false, t.isolated = false;  // pairs near other marks: not scored as pairs
  // Joint bound of each pair (true sigma of the star images, the simulator's noise).
  for (TruthStar& t : truth) {
    if (!t.pair) continue;
    const std::string other = (t.id[1] == 'A' ? "PB" : "PA") + t.id.substr(2);
    const TruthStar& o = truth[by_id[other]];
    auto flux = [&](const std::string& id) {
      for (size_t i = 0; i < plate.truth.size(); ++i)
        if (plate.truth[i].id == id) return std::abs(plate.scene.marks[plate.truth_mark[i]].amplitude_dn);
      return 0.0;
    };
    const auto c = PairAxisCrb(t.x, t.y, flux(t.id), o.x, o.y, flux(other), t.sigma_px, 20.0 * 20.0 + 1.0 / 12.0);
    t.pair_crb_axis = std::sqrt(c.first);
  }
  std::printf("truth: %zu stars in the image, %d on dust or scratches\n", truth.size(), on_defects);

  const Run ours = RunChild(self, "ours", image_path, dir + "/ours.txt", start_fwhm_px);
  Score("platemeter (DetectStars, PSF fit)", ours, truth, marks, pixels);
  if (run_sep) {
    const Run sep = RunChild(self, "sep", image_path, dir + "/sep.txt", start_fwhm_px);
    Score("SEP (sep_background + sep_extract + sep_windowed)", sep, truth, marks, pixels);
  }
  if (keep.empty()) std::filesystem::remove_all(dir);
  return 0;
}
