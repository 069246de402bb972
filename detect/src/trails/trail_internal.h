#pragma once
// Internals of the trail linker shared by its source files (not installed).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/pixel.h"
#include "platemeter/detect/dash_in_pixels.h"
#include "platemeter/detect/sky_flow.h"
#include "platemeter/detect/star_detector.h"
#include "platemeter/detect/trail_linker.h"

namespace platemeter::trail_internal {

// A star's track on the plate: x and y polynomials in the mid-exposure time,
// fitted by weighted least squares (trail_fit.cpp).
class Track {
 public:
  // Fits points (t_s, x, y) with per-point sigmas (px; empty: unit weights) with polynomials of
  // `degree` (lowered to what the points support: at least degree + 2 points). false if singular.
  bool Fit(const std::vector<double>& t_s, const std::vector<PixelPoint>& p, const std::vector<double>& sigma_x_px,
           const std::vector<double>& sigma_y_px, int degree);
  PixelPoint At(double t_s) const;
  PixelPoint VelocityAt(double t_s) const;  // px/s
  // Formal sigmas of At(t_s): from the fit's covariance, scaled by its reduced chi^2 when above 1.
  void SigmaAt(double t_s, double* sigma_x_px, double* sigma_y_px) const;
  // Leverage (hat-matrix diagonal, 0..1) of a point at t_s with these sigmas, per coordinate: how much
  // the fit follows it. A residual r has the sigma sigma sqrt(1 - h).
  void LeverageAt(double t_s, double sigma_x_px, double sigma_y_px, double* h_x, double* h_y) const;
  int degree() const { return degree_; }
  double reduced_chi2() const { return reduced_chi2_; }

 private:
  Eigen::VectorXd Basis(double t_s) const;
  double t0_s_ = 0.0, scale_s_ = 1.0;
  int degree_ = 0;
  Eigen::VectorXd ax_, ay_;
  Eigen::MatrixXd cov_x_, cov_y_;  // (A^T W A)^-1 per coordinate
  double reduced_chi2_ = 1.0;
};

// (sqrt, not hypot: pixel coordinates cannot overflow, and the linker's inner loops call this most)
inline double Dist(const PixelPoint& a, const PixelPoint& b) {
  const double dx = a.x_px - b.x_px, dy = a.y_px - b.y_px;
  return std::sqrt(dx * dx + dy * dy);
}

// Spatial hash of points in cells of `cell_px`.
class Grid {
 public:
  Grid(const std::vector<PixelPoint>& p, const std::vector<int>& ids, double cell_px) : p_(p), cell_px_(cell_px) {
    for (int i : ids) {
      cells_[Key(p[i].x_px, p[i].y_px)].push_back(i);
      const long cx = Cell(p[i].x_px), cy = Cell(p[i].y_px);
      x_min_ = std::min(x_min_, cx), x_max_ = std::max(x_max_, cx);
      y_min_ = std::min(y_min_, cy), y_max_ = std::max(y_max_, cy);
    }
  }
  // Calls f(j) for every point within r of (x, y). The cells searched are those the points occupy: a place
  // predicted far off the plate (a flow carried beyond its images), with a tolerance that grows with the
  // distance, must not walk millions of empty cells.
  template <class F>
  void Near(double x, double y, double r, F f) const {
    if (!(std::isfinite(x) && std::isfinite(y) && r >= 0.0) || x_min_ > x_max_) return;
    // The occupied cells' extent (px); the search range is cut to it before it becomes cell indices.
    const double lo_x = x_min_ * cell_px_, hi_x = (x_max_ + 1) * cell_px_, lo_y = y_min_ * cell_px_, hi_y = (y_max_ + 1) * cell_px_;
    if (x + r < lo_x || x - r > hi_x || y + r < lo_y || y - r > hi_y) return;  // (no point can lie within r)
    const long x0 = std::max(Cell(std::max(x - r, lo_x)), x_min_), x1 = std::min(Cell(std::min(x + r, hi_x)), x_max_);
    const long y0 = std::max(Cell(std::max(y - r, lo_y)), y_min_), y1 = std::min(Cell(std::min(y + r, hi_y)), y_max_);
    for (long cy = y0; cy <= y1; ++cy)
      for (long cx = x0; cx <= x1; ++cx) {
        auto it = cells_.find(Pack(cx, cy));
        if (it == cells_.end()) continue;
        for (int j : it->second)
          if (Dist(p_[j], {x, y}) <= r) f(j);
      }
  }

 private:
  long Cell(double v) const { return static_cast<long>(std::floor(v / cell_px_)); }
  static long long Pack(long x, long y) { return (static_cast<long long>(x) << 32) ^ (y & 0xffffffffLL); }
  long long Key(double x, double y) const { return Pack(Cell(x), Cell(y)); }
  const std::vector<PixelPoint>& p_;
  double cell_px_;
  std::unordered_map<long long, std::vector<int>> cells_;
  long x_min_ = std::numeric_limits<long>::max(), x_max_ = std::numeric_limits<long>::min();  // occupied cells
  long y_min_ = std::numeric_limits<long>::max(), y_max_ = std::numeric_limits<long>::min();
};

// Whether p lies inside the scanned area (image_min_px/image_max_px, when set) and the exposed format
// (exposed_outline_px, when set) by at least margin_px.
bool Inside(const TrailOptions& o, const PixelPoint& p, double margin_px);

// What image i is tagged with: its trail number (1..; 0: untagged) and exposure's mid-time.
struct ImageTag {
  int trail = 0;
  double mid_s = 0;
};
using TagOf = std::function<ImageTag(int)>;

// Whether an image at p, length_px long (0: a point), would touch what the detector masked (TrailOptions::blind):
// it would not have been detected, so its absence proves nothing.
bool Blind(const TrailOptions& o, const PixelPoint& p, double length_px);

// What every step of the linker reads.
struct Context {
  const std::vector<DetectedStar>& images;
  const TrailOptions& o;
  std::vector<PixelPoint> p;
  std::vector<bool> usable, elongated;
  bool use_lengths = false;
  std::vector<std::vector<ShutterExposure>> per_trail;  // exposures of each trail, time order
  std::vector<int> lines;  // rejected lines with an extent (defects with length_px > 0), for ForReaching
  const ScanPixels* scan = nullptr;  // the scan's pixels, where the caller has them (a lone run's held dashes)
};

// How far from q an image predicted by the flow may lie, carried there from origin: the flow's error grows
// with the distance carried.
inline double FlowTolerance_px(const TrailOptions& o, const PixelPoint& q, const PixelPoint& origin) {
  return o.flow_tolerance_px + o.tuning.flow_tolerance_fraction * Dist(q, origin);
}

inline bool IsLine(const DetectedStar& d) { return (d.flags & kStarDefect) && d.length_px > 0; }

// Whether a rejected line may reach within r of q: a dash merged into it lies somewhere on its pixels,
// inside its box where the detector gave one (a line along the format's edge, 600 px long, reaches
// 300 px into the format as a disk), else within half its length of its centre.
inline bool LineReaches(const DetectedStar& line, const PixelPoint& q, double r) {
  if (line.box_min_px.x_px <= line.box_max_px.x_px) {
    const double dx = std::max({line.box_min_px.x_px - q.x_px, 0.0, q.x_px - line.box_max_px.x_px});
    const double dy = std::max({line.box_min_px.y_px - q.y_px, 0.0, q.y_px - line.box_max_px.y_px});
    return std::hypot(dx, dy) <= r;
  }
  return Dist(line.point.position_px, q) <= r + 0.5 * line.length_px;
}

// Calls f(i) for every image within r of q, and for every rejected line that may reach that far.
template <class F>
void ForReaching(const Context& c, const Grid& all, const PixelPoint& q, double r, F f) {
  all.Near(q.x_px, q.y_px, r, [&](int i) {
    if (!IsLine(c.images[i])) f(i);
  });
  for (int i : c.lines)
    if (LineReaches(c.images[i], q, r)) f(i);
}

// Whether a detection may hold (or be) a 20 s dash of a star whose dashes measure this flux and
// length: anything but an image measured fainter than half the dash and shorter than half of it
// (another star's dot; a dash merged with another image measures at least the dash's flux). A piece of
// a crowded clump always may: the deblender may have cut a dash into parts, each fainter than half.
inline bool CouldHoldDash(const DetectedStar& d, double dash_flux_dn, double dash_length_px) {
  return (d.flags & kStarCrowded) ||
         !(dash_flux_dn > 0 && d.flux_dn > 0 && d.flux_dn < 0.5 * dash_flux_dn && d.length_px < 0.5 * dash_length_px);
}

// Whether the images near a place may hold a dash between them: one that could on its own, or pieces fainter
// than half of it whose fluxes add up to half of it (the deblender may cut a dash crossed by other images).
// by_flux: by their fluxes added up (and any image without one, a piece of a crowded clump, or an image
// fitted jointly with a neighbour, whose flux the deblender or the fit may have given the neighbour: beside
// a bright star a dash is measured as a blended point at a third to a half of its flux), whatever their
// lengths -- for a dash whose flux is known to be the star's (CouldHoldDash lets another star's dash of 2 %
// of it hold).
struct DashHolder {
  double dash_flux_dn = 0, dash_length_px = 0;
  double faint_flux_dn = 0;
  bool held = false;
  bool by_flux = false;
  void Add(const DetectedStar& d) {
    if (by_flux ? !(d.flux_dn > 0) || (d.flags & (kStarCrowded | kStarBlended))
                : CouldHoldDash(d, dash_flux_dn, dash_length_px))
      held = true;
    else faint_flux_dn += d.flux_dn;
  }
  bool Holds() const { return held || (faint_flux_dn > 0 && faint_flux_dn >= 0.5 * dash_flux_dn); }
};

// Whether nothing could hold a dash of this flux, duration_s of motion long, predicted at q (within tol_px)
// moving with this velocity: no detection, alone or with others (DashHolder), within half the dash and two
// FWHM along the motion and 1.5 FWHM across it (a neighbouring star's parallel trail, a few FWHM aside,
// holds none of it), and no rejected line reaching there. by_flux: DashHolder::by_flux. Images `explained`
// says are another's hold nothing.
bool DashPlaceEmpty(const Context& c, const Grid& all, const PixelPoint& q, const PixelPoint& velocity_px_per_s,
                    double dash_flux_dn, double duration_s, double tol_px, bool by_flux = false,
                    const std::function<bool(int)>& explained = {});

// What the scan's pixels (c.scan: required) show at a dash's place: its thirds fitted with the light of the
// detections about it (MeasureDashInPixels; trail_lone.cpp).
DashInPixels DashInPixelsAt(const Context& c, const Grid& all, const DashPlace& place);
// Whether the scan's pixels (where LinkTrails was given them; false without) may hold a dash at its place: its
// light in the thirds (DashInPixelsAt), or a saturated core on its sweep's half away from `own`, the star's
// neighbouring dash (ClippedOnSweep: the detector does not see into a saturated image).
bool PixelsMayHoldDash(const Context& c, const Grid& all, const DashPlace& place, const DetectedStar* own);

// Whether image i, taken by another star with that star's flux, cannot have swallowed a dash of dash_flux_dn:
// its flux would exceed its star's by the dash's, which the flux tolerance lets through only when
// dash_flux <= (tolerance x its flux + 4 sigma) / (1 + tolerance). Not a piece of a crowded clump (the dash
// may have been cut, part of it taken with that image).
inline bool CannotHideDash(const Context& c, int i, double dash_flux_dn) {
  const DetectedStar& h = c.images[i];
  return h.flux_dn > 0 && !(h.flags & kStarCrowded) &&
         dash_flux_dn > (c.o.flux_tolerance * h.flux_dn + 4.0 * h.sigma_flux_dn) / (1.0 + c.o.flux_tolerance);
}

// Whether a point image (length 0) may be an exposure expected expect_px long: the detector sees no sweep
// under about one FWHM in its thresholded moments, which run short, so a swept image of up to two FWHM (a
// slow star's 20 s dash) is often measured as a point.
inline bool PointMayBeSwept(const TrailOptions& o, double expect_px) { return expect_px <= 2.0 * o.psf_fwhm_px; }

// Whether an image may count as evidence for a reading of the flow (a seed, a trail's images, a program's
// cover): not a piece of a crowded clump, which the deblender cuts where it can, so that clumps offer a
// piece near almost any prediction (on the whole V <= 8 plate: 21 wrong tags from readings seeded by, or
// lined up with, such pieces). They may still be taken once a reading is decided.
inline bool IsEvidence(const Context& c, int i) { return !(c.images[i].flags & kStarCrowded); }
// How many of these (exposure, image) pairs are evidence.
inline int EvidenceCount(const Context& c, const std::vector<std::pair<int, int>>& taken) {
  const auto evidence = [&](const std::pair<int, int>& ji) { return IsEvidence(c, ji.second); };
  return static_cast<int>(std::count_if(taken.begin(), taken.end(), evidence));
}

// What a reading's images show of the program: dashes besides the seed, and distinct exposure durations
// (a reading shifted by a dot group maps the dots onto other durations; the flux tolerance lets some through,
// not all); evidence only (IsEvidence). taken_per_trail: (exposure, image) per trail (0-based).
// The number of distinct values among `values` (exposure durations, s).
inline int DistinctCount(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return static_cast<int>(std::unique(values.begin(), values.end()) - values.begin());
}

struct ProgramCover {
  int other_dashes = 0, durations = 0;
};
ProgramCover CoverOf(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken_per_trail, int seed);

// Track degree the taken images support (span and count), capped by the option.
int DegreeFor(int n, double span_s, int max_degree);

// An image's position sigmas in a track fit: its formal ones (0.05 px if unknown) with position_floor_px.
struct FitSigma {
  double x_px = 0, y_px = 0;
};
FitSigma FitSigmaOf(const TrailOptions& o, const DetectedStar& d);

// The track of a trail's images (exposure, image) at their mid times (time_s(image)) whose `use` is true,
// weighted by FitSigmaOf; false when fewer than `min_images` or singular.
bool FitTrackOf(const Context& c, const std::vector<std::pair<int, int>>& taken,
                const std::function<double(int)>& time_s, const std::function<bool(int)>& use, size_t min_images,
                Track* track);

// Whether image i may be exposure e (elongation and measured length against the duration).
// With measured lengths (trail-mode detection) the length decides, within its own sigma; else the flag.
// With the star's flux per second (flux_per_s > 0) the flux must match the duration too: in a crowded
// field another star's image may sit where a faint dot was expected.
// A segment at least two FWHM long must also lie along the track (velocity_px_per_s) within max_run_bend_deg.
bool Compatible(const Context& c, int i, const ShutterExposure& e, const PixelPoint& velocity_px_per_s,
                double flux_per_s = 0.0);

// One growth of a trail along its predicted track (trail_grow.cpp).
struct GrowSpec {
  const std::vector<ShutterExposure>* exposures = nullptr;  // the exposure sequence, time order
  std::vector<std::pair<int, int>> seed;  // (exposure index, image) already known, any order
  int first = 0;                          // first exposure index tried
  int step = 1;                           // +1: later exposures, -1: earlier ones
  double flux_per_s = 0.0;                // the star's flux per second of exposure (0: not compared)
  int max_missed_in_row = 5;
  double window_s = 1e300;                // the track is fitted to the taken images within this of the prediction
  // Extrapolated (a sibling trail across a break): an image is taken only within sibling_tolerance_px +
  // sibling_tolerance_fraction x its distance from the nearest taken image.
  bool extrapolated = false;
  std::function<bool(int)> excluded;      // images that belong elsewhere (may be empty)
};

struct Growth {
  std::vector<std::pair<int, int>> taken;  // (exposure index, image): the seed, then the new ones in order
  int after_run = 0;                       // exposures taken past the seed
  int missed = 0;                          // exposures between the seed and the last one taken, untaken
  double rate_px_per_s = 0.0;
};

// Grows exposure by exposure from spec.first in direction spec.step: a smooth track fitted to the
// images taken so far predicts the next exposure; the one compatible image within the tolerance is
// taken, none or several leave it untaken; growth stops after max_missed_in_row untaken in a row.
Growth Grow(const Context& c, const Grid& all, const GrowSpec& spec);

// Grows trail s (0-based) from the images (exposure in trail t, image) of its neighbour t (s = t +- 1):
// t's track carried across the break, every image within the sibling tolerance of the prediction.
// `taken`: the images of trail s (exposure in trail s, image), exposure order.
Growth GrowSibling(const Context& c, const Grid& all, const std::vector<std::pair<int, int>>& images, int t, int s,
                   double flux_per_s, const std::function<bool(int)>& excluded, std::vector<std::pair<int, int>>* taken);

// Sibling evidence (trail_siblings.cpp): under trail number u (0-based), a trail's track (its images
// from t0_s to t1_s) carried to the exposures of trails u - 1 and u + 1 within the break +
// sibling_window_s of its ends (their leading dashes excepted), inside the scan: the count of those
// exposures holding a compatible image (length, flux) within the sibling tolerance, not the trail's own.
struct SiblingEvidence {
  int hits = 0;
};
SiblingEvidence SiblingsOf(const Context& c, const Grid& all, const Track& track, double t0_s, double t1_s, int u,
                           double flux_per_s, const std::function<bool(int)>& own);

// A trail grown from one separator dash (trail_pattern.cpp), its exposures those of trail
// `reference` (the trail with the most leading dashes, so that growth can take all of them).
struct PatternTrail {
  std::vector<std::pair<int, int>> taken;  // (exposure index in c.per_trail[reference], image), time order
  double flux_per_s = 0.0;
};
// Tries the dash (not a blend) as each separator (1..4) in each direction (only along `motion`, the local
// direction of the stars' motion, when known): the neighbouring exposure's image, then growth both ways.
// Exactly one hypothesis must reach 1 + min_exposures_after_run images, its other images' flux per second
// the dash's; false otherwise.
bool GrowFromSeparator(const Context& c, const Grid& all, int dash, int reference, const PixelPoint* motion,
                       const std::function<bool(int)>& excluded, PatternTrail* out);

// Whether track a (images up to a1_s) and track b (images from b0_s, later) lie on one arc: each carried to
// the other's end lands on it within join_tolerance_px + join_tolerance_fraction x the distance.
bool OnOneArc(const TrailOptions& o, const Track& a, double a1_s, const Track& b, double b0_s);

// The median flux per second (DN/s) of images (image, its exposure's duration in s) that may show it
// (evidence, with a flux, neither clipped nor a crowd's piece), and its sigma (the spread's, MAD, over the
// root of their count, as a median's); {0, 0} with fewer than kMinFluxImages (trail_pattern.cpp).
std::pair<double, double> MedianFluxPerSecond(const Context& c, const std::vector<std::pair<int, double>>& image_durations);
// The same of a trail's images (exposure j of trail t: per_trail[t][j]).
std::pair<double, double> FluxPerSecond(const Context& c, const std::vector<std::pair<int, int>>& images, int t);
// Whether two trails' images (a of trail ta, b of trail tb) cannot be one star's: their fluxes per second
// differ by more than kStarFluxSpread and 4 sigmas (a star's trails agree; another star on its diurnal path
// has another magnitude). False where either has too few images to tell.
bool OtherStarsFlux(const Context& c, const std::vector<std::pair<int, int>>& a, int ta,
                    const std::vector<std::pair<int, int>>& b, int tb);

// The sibling a separator-grown trail grew under its number (NumberBySiblings).
struct SiblingGrowth {
  int sibling = -1;                        // 0-based trail number of the sibling
  std::vector<std::pair<int, int>> images;  // (exposure in the sibling, image)
  double rate_px_per_s = 0.0;              // the trail's speed
};
// The number (0-based) under which exactly one sibling grows from the trail's track: at least
// min_exposures_after_run images, their own track fitted to the measuring precision (median residual
// within max_median_residual_px), on one arc with the trail's and of its flux per second (not
// OtherStarsFlux). -1 if none or several, or for a slow
// star (10 s of motion, the offset of a wrong number, within twice the sibling tolerance across a break).
// other_number(image, sibling): the image belongs to a decoded trail of another number than the sibling's.
int NumberBySiblings(const Context& c, const Grid& all, const PatternTrail& pt, int reference,
                     const std::vector<int>& leading_dashes, const std::function<bool(int, int)>& other_number,
                     SiblingGrowth* grown);

// The plate's flow (trail_flow.cpp, docs/trails.md "The plate's flow").
// Samples of a decoded trail's motion for SkyFlow::Fit: its track's position and velocity at its images'
// times (t_s), the outer tenth of its span at either end left out (a cubic's ends bend).
void AddFlowSamples(const Track& track, const std::vector<double>& t_s, std::vector<PixelPoint>* p,
                    std::vector<PixelPoint>* velocity_px_per_s);

// The path through p over the whole plate's time span (either way), ending 50 px outside the scan and format.
FlowPath PlatePath(const Context& c, const SkyFlow& flow, const PixelPoint& p);

// Whether a trail's images (mid time s, position; time order) lie on two flow paths: kFlowStrayImages or more
// off_px or further from the path through its first image, and as many from the path through its last (one
// stray image at either end moves only that end's path).
bool OnTwoFlowPaths(const SkyFlow& flow, const std::vector<std::pair<double, PixelPoint>>& images, double off_px);

// The images of one star found along its flow path, per trail (0-based): (exposure in the trail, image).
struct FlowStar {
  std::vector<std::vector<std::pair<int, int>>> taken;
  double flux_per_s = 0.0;
  double seed_s = 0.0;  // the reading's time of its seed (DecodeByFlow)
  int hits = 0;  // images taken over all trails
};
// Every exposure of the trails in `trail_mask` (bit t: trail t, 0-based) predicted along `path` (the star
// was at the path's origin at t_origin_s): the one compatible image (flux per second, length, direction)
// within flow_tolerance_px + flow_tolerance_fraction x its distance from the origin is taken; none or
// several leave the exposure untaken.
FlowStar CollectAlongFlow(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& origin,
                          double t_origin_s, double flux_per_s, unsigned trail_mask,
                          const std::function<bool(int)>& excluded);
// The star of an unassigned dash (not a blend) decoded by the flow: the dash read as every dash exposure of
// the plate (its length must be 20 s of the flow's motion there, along it). Exactly one reading may line up
// a trail of 5 images and 3 dots of another, and it must be decoded: the dash taken as that exposure, a
// trail of flow_min_images, 4 dots of a second trail, 2 other dashes and images of 4 of the 6 exposure
// durations (trail_flow.cpp says why). A slow star (10 s of motion within 4 tolerances) needs a trail of 12,
// 8 dots of a second trail and 5 durations.
bool DecodeByFlow(const Context& c, const Grid& all, const SkyFlow& flow, int dash,
                  const std::function<bool(int)>& excluded, FlowStar* out);

// The dash places of trail s (0-based) predicted along `path` for a star at p at seed_s (reading_places.cpp):
// `inside` counts those inside the format (edge margin) where no image of kDominatingRatio times the dash's
// flux or more reaches (DominatedReach_px: its light hides or halves the dash, so the place says nothing);
// `empty` counts those of them where trail s was exposed (an image of it, any star's, tagged within
// kExposedRadius_px) and nothing could hold the dash, judged by flux (DashPlaceEmpty, by_flux; an image
// tagged as another number whose flux tolerance could not have let the dash through holds nothing).
// tag_of(i): the trail number (1..) and exposure time image i is tagged with (trail 0: untagged).
struct DashPlaces {
  int inside = 0, empty = 0;          // dash places
  int dot_inside = 0, dot_empty = 0;  // dot places (ReadingPlaces)
};
DashPlaces CountDashPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                           int s, double flux_per_s, const TagOf& tag_of);
// A whole reading's places (the seed at p at seed_s): every trail's dash places as CountDashPlaces counts
// them, and so its dot places where the dot's flux (flux_per_s x its duration) is at least min_dot_flux_dn,
// bright enough that the detector cannot have missed it.
// max_empty: counting stops beyond that many empty places (a rival reading that cannot be likelier).
DashPlaces ReadingPlaces(const Context& c, const Grid& all, const FlowPath& path, const PixelPoint& p, double seed_s,
                         double flux_per_s, double min_dot_flux_dn, const TagOf& tag_of,
                         int max_empty = std::numeric_limits<int>::max());
// The flux per second of a reading's faintest dash (taken: per trail, (exposure, image); evidence only), at
// most flux_per_s: a blend only adds flux, so the faintest dash is the star's own.
double FaintestDashRate(const Context& c, const std::vector<std::vector<std::pair<int, int>>>& taken,
                        double flux_per_s);
// The log of how much likelier a reading's empty places are if the reading is wrong than if it is right: each
// place empty with probability kEmptyWhenWrong or kEmptyWhenRight (evidence.h), independently.
double EmptyPlacesLogOdds(const DashPlaces& places);
// Whether another reading of the same images (other) is kRefuteOdds times likelier than own. Reading b is
// exp(LO_a - LO_b) times likelier than a (each place independent, one of them right); counted on the empty
// places alone (the held ones each reading predicts, whatever its number), two fewer empty places make it so
// (kEmptyWhenWrong / kEmptyWhenRight = 10 each). Only where the other reading looks at as many places, or
// own leans wrong (log odds above 0): a reading putting fewer places on the format has fewer to find empty.
bool OtherReadingLikelier(const DashPlaces& own, const DashPlaces& other);

// A lone trail (trail_lone.cpp): a star whose other trails are off the format or hidden, numbered by its
// leading run found along the flow.
struct LoneTrail {
  int trail = -1;                          // 0-based trail number
  std::vector<std::pair<int, int>> taken;  // (exposure in the trail, image), the run first
  double flux_per_s = 0.0;
};
// The unassigned dash (a blend too) read as every dash exposure; the readings grouped by the dash's time from
// the trail's first dot (a group predicts the same images past the run). Exactly one group may line up 5
// images past the run, no reading of another group 3 dots of a second trail. Its run, counted back from its
// last dash along the flow: at each place one detection explaining k dashes (single, or merged through their
// gaps: at their centre, (30 k - 10) s of motion long, k dashes' flux; exactly one k), up to a place inside
// the format where nothing may hold a dash (within half a dash and two FWHM: no image but one fainter than
// half a dash, or one taken by another star whose flux tolerance could not have let a swallowed dash
// through; no rejected line). That count must be a trail's and the star's other trails must not prefer
// another number; then flow_min_images images, 2 dashes besides the seed, 4 exposure durations (a trail
// cut by the format's edge: those it shows there, at least 3; flow_cut_trails). A slow star
// (10 s of motion within 2 tolerances) is not decoded.
// tag_of(i): the trail number (1..) image i is tagged with, trail 0 if none (entering trails: a place counts as
// empty only where that trail was exposed, "Trails entering the format").
bool DecodeLoneTrail(const Context& c, const Grid& all, const SkyFlow& flow, int dash,
                     const std::function<bool(int)>& excluded, const TagOf& tag_of,
                     LoneTrail* out);

// Runs of leading dashes (runs.cpp): elongated images equally spaced along a line, each run in spatial order.
// With measured segments (trail-mode detection) a dash's neighbours lie along its own direction at 1.5 of
// its length; a run whose end dash has several candidates beyond it (a crossing) is left out.
std::vector<std::vector<int>> FindRuns(const Context& c, const Grid& dashes, const std::vector<int>& dash_ids);

// The final sidereal fit of one trail's images (exposure, image) at their tagged mid times (final_fit.cpp):
// weighted track, outliers (studentised residual over bad_sigma x the robust spread, over min_bad_px) flagged
// bad one at a time, at most a third; every image's residual, refined position and its sigma written into
// `out`, the chain's rms and bad count. false when the images cannot support a track.
bool FitTrail(const Context& c, const std::vector<std::pair<int, int>>& taken, TrailChain* chain,
              std::vector<TrailImage>* out, Track* final_track);

}  // namespace platemeter::trail_internal
