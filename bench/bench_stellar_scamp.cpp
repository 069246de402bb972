// The physical model against a polynomial peer (issue #24): one exposure of a
// simulated Orbigon star plate (every star's image at one mid-time, 2.5 um
// noise, catalog places 0.4" off the truth), calibrated by platemeter's
// 11-parameter model and by SCAMP (Debian package `scamp`, TAN + TPV
// polynomial of degree 3..7) from the same identified images and reference
// places.
//
// Comparison. Each solution maps every point of a 2 mm grid over the format to
// a direction; that direction goes back through the TRUE camera and orientation
// to the plate, and the landing point minus the grid point is the solution's
// error there (um). "raw" is that field as is; the main columns are after
// removing, from each method's field separately, the 4-parameter similarity
// (shift, rotation, scale) fitted to it by least squares on the grid: a single
// exposure cannot tell those from the pointing and the principal distance, so
// what remains is the error of the recovered distortion. Printed: RMS and
// largest error over the grid, stars used, fit times.
//
// SCAMP's sky is the site's local frame turned so that the zenith is at
// (RA, Dec) = (0, 0): the stars' apparent places at the exposure, refraction
// included (SCAMP has no atmosphere), so both solutions see the same
// directions. SCAMP runs without pattern matching from an initial TAN WCS of the
// nominal lens at the TRUE pointing (it refits every linear term).
//
//   apt-get install scamp   (not in scripts/setup; python3-astropy is)
//   build/bench/bench_stellar_scamp [--work DIR] [--clip-sigma S] [--seed N]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include "platemeter/calib/stellar_plate.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/stellar_plates.h"

using namespace platemeter;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kNominalC_mm = 80.2;   // the Orbigon's nominal principal distance
constexpr double kPixelMm = 0.0125;     // the "scan" SCAMP sees: 12.5 um pixels
constexpr int kAxisPx = 9120;           // 114 mm format
constexpr double kCentrePx = 4560.5;    // FITS 1-based centre of kAxisPx
constexpr double kHalfFormatMm = 55.0;  // the grid's extent (images reach 55 mm)
constexpr double kGridStepMm = 2.0;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Local frame (east, north, up) -> SCAMP's sky: the zenith at RA = Dec = 0.
Eigen::Vector2d SkyDeg(const Eigen::Vector3d& enu) {
  const Eigen::Vector3d u = enu.normalized();
  const double ra_deg = std::atan2(u.x(), u.z()) / kDeg;
  return {ra_deg < 0 ? ra_deg + 360.0 : ra_deg, std::asin(u.y()) / kDeg};  // FITS: RA in [0, 360)
}
Eigen::Vector3d EnuFromSky(double ra_deg, double dec_deg) {
  const double a = ra_deg * kDeg, d = dec_deg * kDeg;
  return {std::cos(d) * std::sin(a), std::sin(d), std::cos(d) * std::cos(a)};
}

// Plate position (mm) of an ENU direction through a camera (Slama model) and orientation.
Eigen::Vector2d Project(const StellarCamera& c, double s, double epsilon, const Eigen::Matrix3d& m,
                        const Eigen::Vector3d& enu) {
  const Eigen::Vector3d v = m * enu;
  double x, y;
  SlamaImageEquation(c.data() + 3, c[0] * (1 + s), c[0] * (1 - s), c[1], c[2], epsilon, v.x(), v.y(), v.z(), &x, &y);
  return {x, y};
}

// The ENU direction of a plate position through a fitted camera (Newton on m/q, n/q).
Eigen::Vector3d Unproject(const StellarCamera& c, double s, double epsilon, const Eigen::Matrix3d& m,
                          const Eigen::Vector2d& p) {
  auto residual = [&](const Eigen::Vector2d& w) -> Eigen::Vector2d {
    return Project(c, s, epsilon, Eigen::Matrix3d::Identity(), Eigen::Vector3d(w.x(), w.y(), 1.0)) - p;
  };
  Eigen::Vector2d uv((p.x() - c[1]) / c[0], (p.y() - c[2]) / c[0]);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector2d r = residual(uv);
    Eigen::Matrix2d j;
    const double h = 1e-7;
    j.col(0) = (residual(uv + Eigen::Vector2d(h, 0)) - r) / h;
    j.col(1) = (residual(uv + Eigen::Vector2d(0, h)) - r) / h;
    uv -= j.inverse() * r;
  }
  return m.transpose() * Eigen::Vector3d(uv.x(), uv.y(), 1.0).normalized();
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<Eigen::Vector2d> ReadWorld(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<Eigen::Vector2d> out;
  while (std::getline(in, line)) {
    double ra = 0, dec = 0;
    if (std::sscanf(line.c_str(), "%lf,%lf", &ra, &dec) == 2) out.emplace_back(ra, dec);
  }
  return out;
}

int Run(const std::string& command) { return std::system(command.c_str()); }

// --- the exposure and platemeter's fit ---------------------------------------

// One exposure: every star's dot at the mid-time with the most images.
sim::StellarTruthPlate SimulateExposure() {
  const DefinitionRegistry registry;
  sim::StellarPlateSimulation spec;
  spec.plate_id = "one-exposure";
  spec.field.place.site = {39.03 * kDeg, -76.93 * kDeg, 50.0};
  spec.field.start_utc = calib::ParseUtcIso8601("1972-05-12T05:30:00Z");
  spec.images_per_cell_per_trail = 1000;  // all dots
  const sim::StellarTruthPlate all = sim::SimulateStellarTruth(spec, registry.Camera("orbigon"));
  std::map<std::pair<double, double>, int> count;
  for (const auto& o : all.plate.images) ++count[{o.mid_time.jd1, o.mid_time.jd2}];
  const auto epoch = std::max_element(count.begin(), count.end(),
                                      [](const auto& a, const auto& b) { return a.second < b.second; })->first;
  sim::StellarTruthPlate truth = all;
  truth.plate.images.clear();
  for (const auto& o : all.plate.images) {
    if (o.mid_time.jd1 == epoch.first && o.mid_time.jd2 == epoch.second) truth.plate.images.push_back(o);
  }
  return truth;
}

std::vector<Eigen::Vector2d> GridMm() {
  std::vector<Eigen::Vector2d> points;
  for (double y = -kHalfFormatMm; y <= kHalfFormatMm + 1e-9; y += kGridStepMm) {
    for (double x = -kHalfFormatMm; x <= kHalfFormatMm + 1e-9; x += kGridStepMm) points.emplace_back(x, y);
  }
  return points;
}

// Where a solution's direction lands through the true camera, minus the grid point (um).
template <typename DirectionOf>
std::vector<Eigen::Vector2d> ErrorFieldUm(const sim::StellarTruthPlate& truth, const std::vector<Eigen::Vector2d>& grid,
                                          DirectionOf direction_of) {
  std::vector<Eigen::Vector2d> errors;
  for (size_t k = 0; k < grid.size(); ++k) {
    errors.push_back(1e3 * (Project(truth.camera, 0, 0, truth.camera_from_enu, direction_of(k)) - grid[k]));
  }
  return errors;
}

// The field minus its least-squares similarity e = t + (a I + b J) p (shift, scale, rotation).
std::vector<Eigen::Vector2d> WithoutSimilarity(const std::vector<Eigen::Vector2d>& grid,
                                               const std::vector<Eigen::Vector2d>& errors_um) {
  Eigen::MatrixXd a(2 * grid.size(), 4);
  Eigen::VectorXd b(2 * grid.size());
  for (size_t k = 0; k < grid.size(); ++k) {
    const Eigen::Vector2d& p = grid[k];
    a.row(2 * k) << 1, 0, p.x(), -p.y();
    a.row(2 * k + 1) << 0, 1, p.y(), p.x();
    b(2 * k) = errors_um[k].x(), b(2 * k + 1) = errors_um[k].y();
  }
  const Eigen::VectorXd residual = b - a * a.colPivHouseholderQr().solve(b);
  std::vector<Eigen::Vector2d> out;
  for (size_t k = 0; k < grid.size(); ++k) out.emplace_back(residual(2 * k), residual(2 * k + 1));
  return out;
}

struct Errors {
  double rms_um = 0.0, max_um = 0.0;
};
Errors Summarize(const std::vector<Eigen::Vector2d>& e) {
  Errors out;
  for (const auto& v : e) out.rms_um += v.squaredNorm(), out.max_um = std::max(out.max_um, v.norm());
  out.rms_um = std::sqrt(out.rms_um / e.size());
  return out;
}

struct Row {
  std::string method;
  int stars = 0;
  Errors distortion, raw;  // similarity removed / as is
  double seconds = 0.0;
};

void PrintRow(const Row& r) {
  std::printf("%-30s %6d %8.3f %8.3f %9.3f %9.3f %7.3f\n", r.method.c_str(), r.stars, r.distortion.rms_um,
              r.distortion.max_um, r.raw.rms_um, r.raw.max_um, r.seconds);
}

Row FitPlatemeter(const sim::StellarTruthPlate& truth, const sim::NoisyStellarPlate& noisy,
                  const std::vector<Eigen::Vector2d>& grid) {
  StellarOptions options;
  options.orientation_sets = 1;
  const auto start = std::chrono::steady_clock::now();
  const StellarPlateResult fit =
      RunStellarPlate(noisy.plate, noisy.catalog, NominalStellarCamera(kNominalC_mm), options);
  Row row{"platemeter 11-parameter", fit.images - fit.rejected_images, {}, {}, Seconds(start)};
  const double s_fit = (fit.cx_mm - fit.cy_mm) / (fit.cx_mm + fit.cy_mm);
  const Eigen::Matrix3d m_fit = fit.orientation_sets.front().camera_from_enu;
  const auto errors = ErrorFieldUm(truth, grid, [&](size_t k) {
    return Unproject(fit.camera, s_fit, fit.epsilon_rad, m_fit, grid[k]);
  });
  row.raw = Summarize(errors);
  row.distortion = Summarize(WithoutSimilarity(grid, errors));
  return row;
}

// --- SCAMP's input -------------------------------------------------------------

// The initial WCS: TAN at the true optical axis, CD from the nominal lens
// (no distortion): the derivative of the gnomonic standard coordinates (deg)
// at CRVAL with respect to pixels. (The draft differenced RA across its
// 0/360 wrap, which gave SCAMP a CD1_1 of -2.24 deg/px: nothing matched.)
std::string InitialWcsHeader(const sim::StellarTruthPlate& truth, double mjd) {
  const Eigen::Vector2d crval = SkyDeg(truth.camera_from_enu.row(2).transpose());
  const Eigen::Vector3d centre = EnuFromSky(crval.x(), crval.y());
  const Eigen::Vector3d east(std::cos(crval.x() * kDeg), 0.0, -std::sin(crval.x() * kDeg));
  const Eigen::Vector3d north = centre.cross(east);
  auto standard_deg = [&](double x_mm, double y_mm) -> Eigen::Vector2d {
    const Eigen::Vector3d u =
        truth.camera_from_enu.transpose() * Eigen::Vector3d(x_mm / kNominalC_mm, y_mm / kNominalC_mm, 1.0);
    return Eigen::Vector2d(u.dot(east) / u.dot(centre), u.dot(north) / u.dot(centre)) / kDeg;
  };
  const double h_mm = 1.0;
  const Eigen::Vector2d dx = (standard_deg(h_mm, 0) - standard_deg(-h_mm, 0)) / (2 * h_mm / kPixelMm);
  const Eigen::Vector2d dy = (standard_deg(0, h_mm) - standard_deg(0, -h_mm)) / (2 * h_mm / kPixelMm);
  return fmt::format(
      "SIMPLE  = T\nBITPIX  = -32\nNAXIS   = 2\nNAXIS1  = {}\nNAXIS2  = {}\nCTYPE1  = 'RA---TAN'\n"
      "CTYPE2  = 'DEC--TAN'\nCRVAL1  = {:.12f}\nCRVAL2  = {:.12f}\nCRPIX1  = {}\nCRPIX2  = {}\n"
      "CD1_1   = {:.12E}\nCD1_2   = {:.12E}\nCD2_1   = {:.12E}\nCD2_2   = {:.12E}\nEQUINOX = 2000.0\n"
      "RADESYS = 'ICRS'\nEXPTIME = 1.0\nFILTER  = 'V'\nMJD-OBS = {:.8f}\n",
      kAxisPx, kAxisPx, crval.x(), crval.y(), kCentrePx, kCentrePx, dx.x(), dy.x(), dx.y(), dy.y(), mjd);
}

// stars.csv (pixels), reference.csv (apparent places at the exposure), header.txt, grid.csv.
void WriteScampTables(const std::string& work, const sim::StellarTruthPlate& truth,
                      const sim::NoisyStellarPlate& noisy, const std::vector<Eigen::Vector2d>& grid) {
  const calib::ApparentPlaceCalculator sky(noisy.plate.place, noisy.plate.images.front().mid_time);
  std::string stars = "x_px,y_px,sigma_px,flux\n", reference = "ra_deg,dec_deg,sigma_deg,mag\n";
  for (const auto& o : noisy.plate.images) {
    stars += fmt::format("{:.6f},{:.6f},{:.6f},{}\n", kCentrePx + o.x_mm / kPixelMm, kCentrePx + o.y_mm / kPixelMm,
                         o.sigma_x_mm / kPixelMm, 1e4);
    const CatalogEntry& e = noisy.catalog.at(o.star_id);
    const Eigen::Vector2d radec = SkyDeg(sky.Observe(e.star).enu);
    reference += fmt::format("{:.10f},{:.10f},{:.3e},{:.2f}\n", radec.x(), radec.y(), e.sigma_arcsec / 3600.0,
                             e.star.v_mag);
  }
  std::string grid_px = "x_px,y_px\n";
  for (const auto& p : grid) {
    grid_px += fmt::format("{:.6f},{:.6f}\n", kCentrePx + p.x() / kPixelMm, kCentrePx + p.y() / kPixelMm);
  }
  WriteText(work + "/stars.csv", stars);
  WriteText(work + "/reference.csv", reference);
  WriteText(work + "/header.txt", InitialWcsHeader(truth, noisy.plate.images.front().mid_time.Mjd()));
  WriteText(work + "/grid.csv", grid_px);
}

// --- SCAMP ------------------------------------------------------------------------

// Settings beyond SCAMP's defaults (scamp -dd), and why: the reference is our
// LDAC file; no pattern matching (identities and a good WCS are given);
// CROSSID_RADIUS 300" because the nominal-lens WCS is up to 3 px (100") off
// (principal point and distortion): SCAMP's default 2" matches nothing, 30"
// 505 stars with a poor fit, 150" and more all 552 (the closest pairs, 25"
// apart, do not confuse it); S/N cuts below our fixed S/N of 100.
std::string ScampSettings(const std::string& degree, double clip_sigma) {
  return fmt::format("-ASTREF_CATALOG FILE -ASTREFCAT_NAME reference.cat -MATCH N -CROSSID_RADIUS 300 "
                     "-SN_THRESHOLDS 1,2 -DISTORT_DEGREES {} -ASTRCLIP_NSIGMA {} -SOLVE_PHOTOM N "
                     "-STABILITY_TYPE EXPOSURE -CHECKPLOT_TYPE NONE",
                     degree, clip_sigma);
}

struct ScampResult {
  bool ok = false;
  int matched = 0;
  double seconds = 0.0;
  std::string failure;  // SCAMP's own warnings when it produced no solution
};

// SCAMP's warnings (the ATLAS threading note left out).
std::string ScampWarnings(const std::string& log_path) {
  std::istringstream log(ReadText(log_path));
  std::string line, out;
  while (std::getline(log, line)) {
    if ((line.find("WARNING") != std::string::npos || line.find("Error") != std::string::npos) &&
        line.find("ATLAS") == std::string::npos)
      out += "  " + line + "\n";
  }
  return out;
}

ScampResult RunScamp(const std::string& work, const std::string& here, int degree, double clip_sigma) {
  for (const char* f : {"plate.head", "scamp.xml", "world.csv", "stats.txt"}) std::filesystem::remove(work + "/" + f);
  ScampResult r;
  const auto start = std::chrono::steady_clock::now();
  const int status = Run(fmt::format("cd '{}' && scamp plate.cat -c /dev/null {} -WRITE_XML Y -XML_NAME scamp.xml "
                                     "-VERBOSE_TYPE QUIET > scamp.log 2>&1",
                                     work, ScampSettings(std::to_string(degree), clip_sigma)));
  r.seconds = Seconds(start);
  if (status == 0 && std::filesystem::exists(work + "/plate.head")) {
    Run(fmt::format("/usr/bin/python3 '{0}/scamp_io.py' evaluate '{1}/plate.head' '{1}/header.txt' '{1}/grid.csv' "
                    "'{1}/scamp.xml' '{1}/world.csv' '{1}/stats.txt'",
                    here, work));
    std::ifstream(work + "/stats.txt") >> r.matched;
  }
  r.ok = r.matched > 0;  // SCAMP writes a .head (its input WCS) even when nothing matched
  if (!r.ok) r.failure = fmt::format("exit status {}\n{}", status, ScampWarnings(work + "/scamp.log"));
  return r;
}

bool HaveTools() {
  if (Run("command -v scamp > /dev/null 2>&1") != 0) {
    std::printf("note: `scamp` not found (Debian package scamp; scripts/setup does not install it): "
                "SCAMP half skipped.\n");
    return false;
  }
  if (Run("/usr/bin/python3 -c 'import astropy' > /dev/null 2>&1") != 0) {
    std::printf("note: /usr/bin/python3 without astropy (python3-astropy): SCAMP half skipped.\n");
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string work = "/tmp/bench_stellar_scamp";
  // The simulation has no outliers: SCAMP's default 3-sigma clip (ASTRCLIP_NSIGMA)
  // drops 6-11 good stars and does slightly worse; 5 keeps them all, as platemeter does.
  double clip_sigma = 5.0;
  uint64_t seed = 4;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--work") == 0) work = argv[i + 1];
    if (std::strcmp(argv[i], "--clip-sigma") == 0) clip_sigma = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--seed") == 0) seed = std::strtoull(argv[i + 1], nullptr, 10);
  }
  std::filesystem::create_directories(work);
  const std::string here = std::filesystem::path(__FILE__).parent_path().string();

  const sim::StellarTruthPlate truth = SimulateExposure();
  const sim::NoisyStellarPlate noisy = sim::Noisy(truth, {.seed = seed});
  const std::vector<Eigen::Vector2d> grid = GridMm();
  std::printf("one exposure of an Orbigon star plate: %zu stars (V <= 6), 2.5 um image noise, catalog 0.4\"\n"
              "error over the format: %zu grid points (%.0f mm step, +-%.0f mm); each solution's direction of a\n"
              "grid point projected through the TRUE camera and orientation, minus the grid point. rms/max: after\n"
              "removing each field's least-squares similarity (shift, rotation, scale); raw: as is.\n\n",
              noisy.plate.images.size(), grid.size(), kGridStepMm, kHalfFormatMm);
  std::printf("%-30s %6s %8s %8s %9s %9s %7s\n", "method", "stars", "rms um", "max um", "raw rms", "raw max",
              "time s");
  const Row platemeter = FitPlatemeter(truth, noisy, grid);
  PrintRow(platemeter);
  if (!HaveTools()) return 0;

  WriteScampTables(work, truth, noisy, grid);
  if (Run(fmt::format("/usr/bin/python3 '{0}/scamp_io.py' write '{1}/stars.csv' '{1}/reference.csv' "
                      "'{1}/header.txt' '{1}/'",
                      here, work)) != 0)
    return 1;
  for (int degree = 3; degree <= 7; ++degree) {
    const ScampResult scamp = RunScamp(work, here, degree, clip_sigma);
    if (!scamp.ok) {
      std::printf("SCAMP degree %d failed: scamp plate.cat -c /dev/null %s\n%s", degree,
                  ScampSettings(std::to_string(degree), clip_sigma).c_str(), scamp.failure.c_str());
      continue;
    }
    const std::vector<Eigen::Vector2d> world = ReadWorld(work + "/world.csv");
    if (world.size() != grid.size()) return 1;
    const auto errors = ErrorFieldUm(truth, grid, [&](size_t k) { return EnuFromSky(world[k].x(), world[k].y()); });
    PrintRow({fmt::format("SCAMP TAN+TPV degree {}", degree), scamp.matched,
              Summarize(WithoutSimilarity(grid, errors)), Summarize(errors), scamp.seconds});
  }
  std::printf("\nSCAMP 2.10 settings beyond its defaults: %s\n", ScampSettings("3..7", clip_sigma).c_str());
  std::printf("stars: SCAMP's AstromNDets_Reference; platemeter's images kept. time: platemeter's\n"
              "RunStellarPlate; the scamp process (LDAC writing and evaluation excluded).\n");
  return 0;
}
